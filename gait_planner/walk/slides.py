"""How far the simulated feet slid while they stood on the ground.

A planned contact point that carries load is held in the plan: it does not move. In MuJoCo
it may: the soft-constraint friction lets a loaded point drift even deep inside its
friction cone, and a point past its cone slides. On 2026-11-30 walker3d's loaded forefoot
drifted 30 mm over a level stance and 65-80 mm on a 10 deg ramp, with a tangential force
6-11 % of the normal against a friction coefficient of 0.6-0.8 (benchmarks/HISTORY.md); the
walker then fell behind its plan. `Slides(names, threshold, normal)` is fed, step by step
at the simulated time, the ground's force on each planned contact point (world, N), its
part along the ground's normal and the point's position (world, m); a stance is a run of
steps in which the point's normal force exceeds `threshold` N.
Its slide is the point's displacement along the ground (the normal part removed) from the
stance's first step to its last; the ~5 mm foot spheres' rolling adds a few mm to it.
`summary()` gives the largest slide of the walk: the point, its stance (s), the slide (mm)
and the mean ratio of tangential to normal force over that stance (the friction it used).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["Slides"]


class Slides:
    """names: the contact points (scene order); threshold N: a point carrying more is
    standing; normal (3,): the ground's unit normal."""

    def __init__(self, names: list[str], threshold: float, normal: np.ndarray):
        self.names, self.threshold = list(names), threshold
        self.normal = np.asarray(normal, dtype=float)
        self.open: dict[int, dict[str, Any]] = {}
        self.largest: dict[str, Any] | None = None

    def update(self, t: float, forces: np.ndarray, normal_forces: np.ndarray,
               positions: np.ndarray) -> None:
        """forces (n_contacts, 3) N, their normal parts normal_forces (n_contacts,) N
        (forces @ normal) and positions (n_contacts, 3) m, world, at time t s."""
        n = self.normal
        for i, (force, normal, position) in enumerate(zip(forces, normal_forces, positions)):
            if normal > self.threshold:
                stance = self.open.get(i)
                if stance is None:
                    stance = self.open[i] = {"start_s": t, "from": position.copy(),
                                             "friction_sum": 0.0, "steps": 0}
                stance.update(end_s=t, to=position.copy())
                stance["friction_sum"] += float(np.linalg.norm(force - normal * n)) / normal
                stance["steps"] += 1
            elif i in self.open:
                self._close(i)

    def summary(self) -> dict[str, Any] | None:
        """The largest slide of the walk (module docstring), rounded; None if no point
        stood."""
        for i in list(self.open):
            self._close(i)
        if self.largest is None:
            return None
        return {**self.largest, "start_s": round(self.largest["start_s"], 4),
                "end_s": round(self.largest["end_s"], 4),
                "slide_mm": round(self.largest["slide_mm"], 1),
                "friction_used": round(self.largest["friction_used"], 3)}

    def _close(self, i: int) -> None:
        stance = self.open.pop(i)
        move = stance["to"] - stance["from"]
        slide = 1e3 * float(np.linalg.norm(move - (move @ self.normal) * self.normal))
        if self.largest is None or slide > self.largest["slide_mm"]:
            self.largest = {"point": self.names[i], "start_s": stance["start_s"],
                            "end_s": stance["end_s"], "slide_mm": slide,
                            "friction_used": float(stance["friction_sum"] / stance["steps"])}
