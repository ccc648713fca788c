"""What a plan request may ask of a scene, checked in microseconds before anything is built.

A request outside these ranges cannot be planned (or would exhaust the machine) and is
refused with a sentence naming the field, its value and the allowed range:

* step_length in (0, reach]: `reach` is the length of the kinematic chain from one foot's
  contact point to the other's (the sum, body by body, of the distance between the points
  where the chain enters and leaves the body), derived from the scene. No motion can put
  the feet's contact points further apart; walker3d and walker2d: 2.28 m, compass: 2.0 m.
* friction_coefficient in [0.05, 5]: below wet ice (about 0.05) no gait was found (mu = 1e-6
  ran 3000 iterations), above 5 no real surface.
* intervals_per_phase in [2, 32]: one interval per phase "converged" to a 0.06 s half cycle
  after 2393 iterations; 100000 grew the process to 4.5 GB before it answered. 32 per phase
  (walker3d: 160 intervals) builds and solves within a few minutes here.
* max_solve_time in (0, 3600] s.
"""

from __future__ import annotations

import math

import numpy as np

from gait_planner.model.scene import Scene

FRICTION_RANGE = (0.05, 5.0)
INTERVALS_RANGE = (2, 32)
MAX_SOLVE_TIME = 3600.0  # s


class RangeError(ValueError):
    """A request field outside the range the scene allows; the message names it."""


def reach(scene: Scene) -> float:
    """Length (m) of the longest chain between two contact points on different bodies:
    body by body along the joint tree, the distance between the point where the chain
    enters the body and where it leaves it (module docstring)."""
    up = {j.child: j for j in scene.joints}

    def ancestors(body: str) -> list[str]:
        out = [body]
        while out[-1] in up:
            out.append(up[out[-1]].parent)
        return out

    def span(body: str, a: str, b: str) -> float:
        points = scene.body(body).points
        return float(np.linalg.norm(np.subtract(points[a], points[b])))

    def side(start: str, where: str, stop: str) -> tuple[float, str]:
        """Length from point `where` of body `start` up to body `stop`, and the point where
        it enters stop."""
        length, body = 0.0, start
        while body != stop:
            joint = up[body]
            length += span(body, where, joint.child_point)
            where, body = joint.parent_point, joint.parent
        return length, where

    best = 0.0
    for i, a in enumerate(scene.contacts):
        for b in scene.contacts[i + 1:]:
            if a.body == b.body:
                continue
            meet = next(x for x in ancestors(a.body) if x in ancestors(b.body))
            (la, pa), (lb, pb) = side(a.body, a.point, meet), side(b.body, b.point, meet)
            best = max(best, la + lb + span(meet, pa, pb))
    return best


def check_request(scene: Scene, *, step_length: float | None, friction_coefficient: float | None,
                  intervals_per_phase: int | None, max_solve_time: float | None) -> None:
    """Raise RangeError for the first field (None = the scene's value) outside its range."""
    def refuse(field: str, value, allowed: str) -> None:
        raise RangeError(f"{field} = {value} is outside the range scene {scene.name!r} allows: "
                         f"{allowed}")

    if step_length is not None:
        limit = reach(scene)
        if not 0 < step_length <= limit:
            refuse("step_length", step_length, f"(0, {limit:.3f}] m (the legs' reach)")
    lo, hi = FRICTION_RANGE
    if friction_coefficient is not None and not lo <= friction_coefficient <= hi:
        refuse("friction_coefficient", friction_coefficient, f"[{lo}, {hi}]")
    lo, hi = INTERVALS_RANGE
    if intervals_per_phase is not None and not lo <= intervals_per_phase <= hi:
        refuse("intervals_per_phase", intervals_per_phase, f"[{lo}, {hi}]")
    if max_solve_time is not None and not (math.isfinite(max_solve_time)
                                           and 0 < max_solve_time <= MAX_SOLVE_TIME):
        refuse("max_solve_time", max_solve_time, f"(0, {MAX_SOLVE_TIME:g}] s")
