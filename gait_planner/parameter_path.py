"""A request planned from a kept optimum of another request, along a path of parameters.

The ground (slope, stair height), the pace (speed), the step length and the friction
coefficient are parameters of a built problem (`ocp.transcription.Transcription.parameters`),
so one optimum can start any request of the same grid. A far start costs IPOPT hundreds of
iterations, or fails: its active set (the contact forces on their cones' faces, the swing
clearances, sigma on its bounds) is not the request's. The path moves the parameters from
the start's values to the request's in steps no larger than `PATH_STEP` each, solving every
step from the last step's optimum (`ocp.solve.VARIANTS["continued"]`: the barrier fixed from
1e-4), and halves a step that fails, down to `SMALLEST_STEP` of the way.

* A start on another problem shape (`ocp.transcription.shape_of`: level ground for a stair,
  free durations for a speed) keeps x and the bounds' multipliers; the constraints'
  multipliers start at zero, as their rows are not the same.
* A free-durations start's speed is its step length over its half cycle's duration
  (`Transcription.duration`), so that a requested speed is reached along the path too.
* On stairs down a path of more than one step is followed with the edge margin instead of
  the segment rows (`gait_planner.model.ground.Ground.segment_rows`), as the cold start is
  (`strategies.stair_start`), and the request is then solved with its segment rows from
  that plan (barrier fixed from 1e-4, else IPOPT's adaptive barrier). walker3d's five
  stairs-down requests of the benchmark, from the anchors at -0.05 and -0.10 m
  (2026-11-29): with the rows all the way, one of five got there (the one a single step
  away); this way three of five, in 68-263 iterations; the two with steps of 0.42 and
  0.47 m found no plan either way, nor cold.

Measured on walker3d, 2026-11-29 (benchmarks/HISTORY.md, REPORT section 12): the 30 random
requests of `benchmarks/any_request.py`, each from the nearest of the default plan, the 14
anchors (the scene's `warm_start_anchors`, `ocp.prepare_requests.anchor_requests`) and the plans
of the requests before it, certified: 28 certified, median 2.7 s, 102 iterations; cold 27,
3.4 s, 160 iterations. Faster than cold on 17 of the 28, slower where a path of 3-4 steps
took 50-100 iterations a step or failed before the cold plan.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from gait_planner.model.scene import Scene
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solve import Clock, Planner, Reached, Start, stored
from gait_planner.ocp.warm_starts import StoredPlan

# The largest change of each parameter in one step of a path (deg, m, m, -, m/s): one step
# of each took 15-60 IPOPT iterations on walker3d (module docstring)
PATH_STEP = {"slope": 2.5, "step_height": 0.025, "step_length": 0.05,
             "friction_coefficient": 0.2, "speed": 0.1}
# of the whole path: a failed step is halved while it is no shorter (a path of more than 16
# steps is not halved: it ends at its first failed step)
SMALLEST_STEP = 1.0 / 16.0
ANOTHER_SHAPE = 1.0  # the distance a start on another problem shape adds (one step more)
_FIELDS = tuple(PATH_STEP)


def _shape(step_height: float, speed: float) -> tuple[float, bool]:
    """A request's problem shape as the path sees it (`ocp.transcription.shape_of`)."""
    return (math.copysign(1.0, step_height) if step_height else 0.0), speed > 0


def point_of(settings: GaitSettings) -> dict:
    """A request's values of the path's parameters (speed 0: free durations)."""
    return {field: float(getattr(settings, field)) for field in _FIELDS}


def start_point(plan: StoredPlan, duration: float, speed_asked: bool) -> dict:
    """A kept optimum's values of the path's parameters for a request that asks a speed
    or not: with a speed, a plan with free durations has its own (its step over
    `duration`, s); without, the plan's speed is let go (0)."""
    speed = (plan.speed or plan.step / duration) if speed_asked else 0.0
    return {"slope": plan.slope, "step_height": plan.step_height, "step_length": plan.step,
            "friction_coefficient": plan.mu, "speed": speed}


def distance(a: dict, b: dict, same_shape: bool = True) -> float:
    """Steps of `PATH_STEP` between two points, plus `ANOTHER_SHAPE` unless the start is
    of the request's problem shape."""
    steps = max(abs(a[field] - b[field]) / PATH_STEP[field] for field in _FIELDS)
    return steps + (0.0 if same_shape else ANOTHER_SHAPE)


def buildable(a: dict, b: dict) -> bool:
    """Whether every point of the straight path from a to b is a ground the planner builds:
    no ramp with stairs (`gait_planner.model.ground.Ground`), so the slope or the stair
    height stays 0 all the way."""
    return (a["slope"] == 0.0 and b["slope"] == 0.0) or \
        (a["step_height"] == 0.0 and b["step_height"] == 0.0)


def nearest(planner: Planner, scene: Scene, settings: GaitSettings
            ) -> tuple[StoredPlan, dict, float] | None:
    """The kept optimum (any problem of the grid of `settings`: `Planner.all_plans`)
    nearest to the request by `distance` whose path is `buildable`: (plan, its point,
    distance), or None if the planner keeps none. (A ramp's plan as the start of stairs,
    as near as the level default by `distance`, made `make setup` fail with "a ramp with
    stairs is not a ground this planner builds" when the store listed it first,
    2026-12-07.)"""
    tr = planner.build(scene, settings, ())
    target = point_of(settings)
    best = None
    for plan in planner.all_plans(scene, settings):
        point = start_point(plan, tr.duration(plan.x), settings.speed > 0)
        if not buildable(point, target):
            continue
        d = distance(point, target, _shape(plan.step_height, plan.speed)
                     == _shape(settings.step_height, settings.speed))
        if best is None or d < best[2]:
            best = (plan, point, d)
    return best


def _between(end: GaitSettings, a: dict, b: dict, f: float) -> GaitSettings:
    """The request at fraction f of the way from point a to the path's end `end` (b)."""
    if f >= 1.0:
        return end
    return dataclasses.replace(end, **{field: a[field] + f * (b[field] - a[field])
                                       for field in _FIELDS})


def _solve(planner: Planner, scene: Scene, step: GaitSettings, x, lam_x, lam_g, qref,
           clock: Clock, variants=("continued",)) -> Reached:
    """`step` solved from (x, lam_x, lam_g, qref) by the variants in turn until one
    converges; lam_g zero if its rows are not those of `step`'s problem."""
    ng = int(planner.build(scene, step, variants).g.shape[0])
    start = Start(x, lam_x, lam_g if lam_g.size == ng else np.zeros(ng), qref, "")
    for variant in variants:
        reached = planner.attempt(scene, step, [(variant, False, False)], start, clock)
        if reached.success or clock.expired() or planner.stopped():
            break
    return reached


def follow(planner: Planner, scene: Scene, settings: GaitSettings, plan: StoredPlan,
           point: dict, clock: Clock) -> tuple[Reached | None, int]:
    """Plan `settings` from the kept optimum `plan` at `point` (`nearest`) along the path
    of parameters (module docstring), within `clock`. Returns (what the request's own
    problem reached, None if the path did not get there; the solves made)."""
    target = point_of(settings)
    steps = max(1, math.ceil(distance(point, target) - 1e-9))  # the values' steps alone
    margin = settings.step_height < 0 and settings.stair_segment_rows and steps > 1
    end = dataclasses.replace(settings, stair_segment_rows=False) if margin else settings
    done, size, solved = 0.0, 1.0 / steps, 0
    x, lam_x, lam_g, qref = plan.x, plan.lam_x, plan.lam_g, plan.qref
    while True:
        f = min(1.0, done + size)
        step = _between(end, point, target, f)
        reached = _solve(planner, scene, step, x, lam_x, lam_g, qref, clock)
        solved += 1
        if reached.success and f >= 1.0:
            break
        if reached.success:
            kept = stored(step, reached)
            x, lam_x, lam_g, qref, done = kept.x, kept.lam_x, kept.lam_g, kept.qref, f
        else:
            size /= 2.0
        if size < min(SMALLEST_STEP, 1.0 / steps) or clock.expired() or planner.stopped():
            return None, solved
    if margin:  # the segment rows, from the plan with the margin at the request's values
        kept = stored(end, reached)
        reached = _solve(planner, scene, settings, kept.x, kept.lam_x, kept.lam_g, kept.qref,
                         clock, ("continued", "warm"))
        solved += 1
    return (reached if reached.success else None), solved
