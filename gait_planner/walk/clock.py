"""The plan's time a walk follows, paced by how far the walker has come.

A walk tracks its plan at the plan's time tau. Held at the simulated time (tau = t), the
plan runs on when the walker falls behind: in a phase on one forefoot or one heel the
walker is an inverted pendulum the joints cannot push, and on a 10 deg ramp up it fell
2 cm behind its plan in the first double support and 20 cm in the next single support
with every joint within 6 deg of the plan (2026-11-29, benchmarks/HISTORY.md); the swing
leg, swung on time, then lands short. Walking controllers of underactuated walkers index
their reference by the walker's progress instead of time (the phase variable of hybrid
zero dynamics: Westervelt et al., "Feedback Control of Dynamic Bipedal Robot Locomotion",
2007). `PlanClock` keeps the time and paces it by the walker's lead:

    d tau / d t = clip(1 + gain lead / v, low, high)

lead (m): the walker's centre of mass ahead of the plan's at tau along the walking
direction on the ground (e_x on level ground and stairs, up or down the slope on a ramp);
v (m/s): the plan's mean speed. gain = 0 is the plain time.

`clock(t)` is tau (s) at simulated time t; `pace(h, lead, v)` after each simulation step
of h s.
"""

from __future__ import annotations

__all__ = ["PlanClock"]


class PlanClock:
    """gain (1/s), low and high: the bounds of the plan's rate (0 < low <= 1 <= high)."""

    def __init__(self, gain: float, low: float, high: float):
        if not 0.0 < low <= 1.0 <= high:
            raise ValueError(f"the plan's rate bounds need 0 < low <= 1 <= high, got "
                             f"[{low}, {high}]")
        self.gain, self.low, self.high = gain, low, high
        self.offset = 0.0

    def __call__(self, t: float) -> float:
        return t + self.offset

    def rate(self, lead: float, speed: float) -> float:
        """d tau / d t for the walker `lead` m ahead of a plan walking at `speed` m/s."""
        return min(max(1.0 + self.gain * lead / speed, self.low), self.high)

    def pace(self, h: float, lead: float, speed: float) -> None:
        """Advance the plan's time by rate(lead, speed) h over a simulation step of h s."""
        self.offset += (self.rate(lead, speed) - 1.0) * h
