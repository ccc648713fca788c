"""The slowest half cycle a drafted robot may take: sigma's upper bound from its own slow
joints (issue #61).

A draft scales walker3d's step and time step to the robot's leg length (equal Froude
number), so walker3d's ``scaling_bounds: [0.5, 1.5]`` give a human-like pace. A robot
whose joints are slower than a human's cannot make that step that fast: Romeo's hip and
ankle pitch turn at most 120 deg/s, and at sigma <= 1.5 no plan converged in 600 s (the
joint speed rows most violated). The draft therefore asks how long the half cycle must be
for the step's own joint excursions:

* In one step of length s the leg (hip to sole, length L) turns through the stride angle
  ``2 asin(s / 2L)`` (41.4 deg at the drafted s = 0.7066 L): the swing leg's hip pitch
  sweeps it from behind to ahead, and the stance shank turns through it over the ankle.
  The knee is not counted: its swing flexion is set by the foot's clearance, not by the
  step; nor are the roll and yaw joints, which a straight walk only sways.
* The swing takes the share of the half cycle in which one foot holds no contact (the
  drafted phases at equal sigmas: 24 of walker3d's 40 intervals, 0.6; a point foot's
  whole half cycle).
* A smooth sweep (a half sine of speed, zero at both ends) peaks at pi/2 times its mean.
  With a margin SPEED_MARGIN (the planned sweep peaks at most at 1 / 1.15 = 87 % of the
  limit, room for the feedback of a controller that walks it) the slowest hip or ankle
  pitch joint (URDF velocity limit omega) needs a swing of at least
  ``SPEED_MARGIN * (pi / 2) * stride / omega``, that is

      sigma >= SPEED_MARGIN * (pi / 2) * stride / (omega * swing share * N * base_time_step)

  with N the half cycle's intervals. The draft's upper bound is that, rounded up to
  SIGMA_STEP, or walker3d's 1.5 where the joints are fast enough (G1, Talos, iCub, Bolt,
  Alexander: 0.01 to 0.98); Romeo's 119.7 deg/s asks 2.99, so its half cycle may last up to
  1.04 s.

Minimal kinetic energy takes the slowest half cycle the bound allows, so the bound is the
drafted robot's pace; it is computed for the drafted step (a longer one, up to the draft's
``step_length_bounds``, may need more).
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from typing import Mapping, Sequence

__all__ = ["SIGMA_UPPER", "SPEED_MARGIN", "SIGMA_STEP", "Pace", "stride_angle", "swing_share",
           "scaling_upper"]

SIGMA_UPPER = 1.5  # walker3d's upper sigma bound, the draft's least
SPEED_MARGIN = 1.15  # the planned sweep's peak at most 1 / 1.15 of the joint's limit
SIGMA_STEP = 0.1  # the bound is rounded up to a multiple of this


@dataclass(frozen=True)
class Pace:
    """sigma's drafted upper bound (`upper`) and why: the bound the rule asks (`needed`,
    unrounded; 0 without a limited sweeping joint), the slowest hip or ankle pitch joint
    (`joint`, None if none has a limit) and its limit `speed` deg/s, the stride angle
    `stride` deg and the swing's share of the half cycle `swing` (0..1)."""

    upper: float
    needed: float
    joint: str | None
    speed: float
    stride: float
    swing: float

    def comment(self) -> str:
        """The draft's header lines saying why, each starting "# ", ending in a newline."""
        if self.joint is None:
            text = (f"scaling_bounds: sigma <= {self.upper:g}, walker3d's: no hip or ankle "
                    f"pitch joint has a velocity limit (gait_planner.model.urdf_pace).")
        else:
            bound = (f"sigma <= {self.upper:.1f}, so that" if self.upper > SIGMA_UPPER else
                     f"sigma <= {self.upper:.1f}, walker3d's:")
            text = (f"scaling_bounds: {bound} the slowest hip or ankle pitch joint, "
                    f"{self.joint} ({self.speed:.1f} deg/s), sweeps the stride angle "
                    f"{self.stride:.1f} deg in the swing ({100 * self.swing:.0f} % of the half "
                    f"cycle) as a half sine peaking at 1/{SPEED_MARGIN:g} of its limit from "
                    f"sigma {self.needed:.2f} on (gait_planner.model.urdf_pace).")
        return textwrap.fill(text, width=92, initial_indent="# ",
                             subsequent_indent="# ") + "\n"


def stride_angle(step: float, leg: float) -> float:
    """The angle (rad) a leg of length `leg` m turns through in a step of `step` m:
    2 asin(step / 2 leg)."""
    return 2.0 * math.asin(min(1.0, step / (2.0 * leg)))


def swing_share(phases: Sequence[Mapping], side_of: Mapping[str, str]) -> float:
    """The share (0..1) of the half cycle in which one foot holds no contact: `phases` the
    draft's phases (``contacts`` names, ``intervals``), `side_of` contact name -> "l"/"r";
    over the half cycle and its mirror image, one leg swings in the intervals where the
    left foot is in the air and those where the right foot is."""
    total = sum(int(p["intervals"]) for p in phases)
    aloft = sum(int(p["intervals"]) for p in phases for side in ("l", "r")
                if side not in {side_of[c] for c in p["contacts"]})
    return aloft / total


def scaling_upper(step: float, leg: float, base_time_step: float, phases: Sequence[Mapping],
                  side_of: Mapping[str, str], limits: Mapping[str, float]) -> Pace:
    """sigma's upper bound (module docstring): `step` and `leg` m, `base_time_step` s,
    `phases` and `side_of` as `swing_share` takes them, `limits` {hip or ankle pitch joint:
    URDF velocity limit deg/s} of both legs (empty: walker3d's 1.5)."""
    stride = stride_angle(step, leg)
    share = swing_share(phases, side_of)
    intervals = sum(int(p["intervals"]) for p in phases)
    if not limits or share <= 0.0:
        return Pace(SIGMA_UPPER, 0.0, None, 0.0, math.degrees(stride), share)
    joint = min(limits, key=lambda name: (limits[name], name))
    speed = float(limits[joint])
    needed = (SPEED_MARGIN * 0.5 * math.pi * math.degrees(stride)
              / (speed * share * intervals * base_time_step))
    steps = math.ceil(round(needed / SIGMA_STEP, 9))
    upper = max(SIGMA_UPPER, round(steps * SIGMA_STEP, 6))
    return Pace(upper, needed, joint, speed, math.degrees(stride), share)
