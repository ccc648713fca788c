"""Where the simulated feet met the ground and the plan did not: early strikes and scuffs.

A walk that falls has usually touched the ground where the plan had a foot in the air
(issue #40: every walker3d walk that fell in 2026-11-29's hard suite did, one or two half
cycles before it stopped). `Touches(times, active, names, threshold)` (the plan's node
times (M,) s and the contact points it holds at each node) is fed, step by step, the
ground's normal force on each planned contact point (`walk_plan.ground_forces`); a touch is
a run of steps in which a point carries more than `threshold` N while the plan holds it at
neither the node before nor the node after; a run that resumes within `REJOIN` s of its
last loaded step is the same touch (a foot chattering on the ground: G1's dragging
forefoot made 40 runs 0.5-3 ms apart in 0.2 s, 2026-11-29). `summary()` lists each touch:
its start and end (s), the point, its peak force (N), what it was (an ``early strike`` if
the plan strikes that point within `EARLY` s after the touch began (how early: the plan's
strike time minus the touch's start), otherwise a ``scuff``: a swing foot dragging on the
ground), and all that in words (`in_words`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["EARLY", "REJOIN", "Touches", "described", "in_words"]

EARLY = 0.1  # s: a touch this long before the plan's strike of the point is an early strike
REJOIN = 0.02  # s: a point loaded again this soon after a touch continues that touch


class Touches:
    def __init__(self, times: np.ndarray, active, names: list[str], threshold: float):
        self.times, self.active = np.asarray(times, dtype=float), [set(a) for a in active]
        self.names, self.threshold = list(names), threshold
        self.open: dict[str, dict[str, Any]] = {}
        self.done: list[dict[str, Any]] = []

    def update(self, t: float, normal_forces: np.ndarray) -> None:
        """normal_forces (n_contacts,) N, scene order, at time t s."""
        n = int(np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 1))
        held = self.active[n] | self.active[min(n + 1, len(self.times) - 1)]
        for name, force in zip(self.names, normal_forces):
            touching = force > self.threshold and name not in held
            if touching and name in self.open:
                touch = self.open[name]
                touch["end_s"], touch["peak_n"] = t, max(touch["peak_n"], float(force))
            elif touching:
                self.open[name] = {"start_s": t, "end_s": t, "point": name,
                                   "peak_n": float(force)}
            elif name in self.open and t - self.open[name]["end_s"] > REJOIN:
                self.done.append(self.open.pop(name))

    def summary(self) -> list[dict[str, Any]]:
        """The touches in time order (module docstring), times and forces rounded."""
        out = []
        for touch in sorted(self.done + list(self.open.values()), key=lambda x: x["start_s"]):
            strike = self._next_strike(touch["point"], touch["start_s"])
            early = strike is not None and strike - touch["start_s"] <= EARLY
            entry = {"start_s": round(touch["start_s"], 4), "end_s": round(touch["end_s"], 4),
                     "point": touch["point"], "peak_n": round(touch["peak_n"], 1),
                     "kind": "early strike" if early else "scuff",
                     **({"early_s": round(strike - touch["start_s"], 4)} if early else {})}
            out.append({**entry, "words": in_words(entry)})
        return out

    def _next_strike(self, point: str, t: float) -> float | None:
        """The time (s) of the first node after t at which the plan holds the point."""
        for k in range(int(np.searchsorted(self.times, t)), len(self.times)):
            if point in self.active[k]:
                return float(self.times[k])
        return None


def in_words(touch: dict[str, Any]) -> str:
    """One touch (`Touches.summary`'s entry): its kind, point and time, how early."""
    early = f", {1e3 * touch['early_s']:.0f} ms early" if "early_s" in touch else ""
    return f"{touch['kind']} {touch['point']} at {touch['start_s']:.3f} s{early}"


def described(touches: list[dict[str, Any]], count: int | None = None) -> str:
    """A walk's touches (`Touches.summary`, or its first ones and their `count`) in words:
    how many, and the first."""
    if not touches:
        return "none"
    return f"{len(touches) if count is None else count} (first: {in_words(touches[0])})"
