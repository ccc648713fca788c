"""A plan request and the one rule its fields follow, wherever it comes from (the service,
the action, ``gait-planner call`` before sending, ``gait-planner plan``).

The fields are those of ``msg_defs/srv/PlanGait.srv``. 0 or an empty string means the
default: the scene's (step_length, cost, friction_coefficient, intervals_per_phase,
posture), the node's (scene, max_solve_time; ``plan``: GaitSettings' time limit), 1
(steps), free phase durations (speed) or level ground (slope, step_height, which may be
negative: downhill, stairs down); output_name is a bare file name. Otherwise a negative,
NaN or infinite number is refused
with `RequestError` naming the field, its value and what is allowed, e.g. "step_length
must be > 0 m, or 0 for the scene's default, got -0.5". Numbers that pass this rule still
meet the scene's ranges (`gait_planner.ocp.request_ranges`; a speed: the half-cycle
durations the scene's scaling_bounds allow at the step length,
`gait_planner.ocp.settings.speed_range`) when the request is planned. Pure Python: no ROS,
no CasADi, so a client checks a request before it sends it.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any

MAX_STEPS = 100  # half cycles one request may join (60 s of walking for walker3d)
# the request's fields (PlanGait.srv), in its order
FIELDS = ("scene", "step_length", "cost", "friction_coefficient", "intervals_per_phase",
          "max_solve_time", "output_name", "cold_start", "steps", "posture", "speed", "slope",
          "step_height", "gait")
# numeric field -> (unit, what 0 stands for)
_OUTPUT_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,127}")  # a bare file name
_NUMBERS = {
    "step_length": (" m", "the scene's default"),
    "friction_coefficient": ("", "the scene's default"),
    "intervals_per_phase": ("", "the scene's default"),
    "max_solve_time": (" s", "the default limit"),
    "speed": (" m/s", "free phase durations"),
}
# signed numeric field -> (unit, what 0 stands for): any finite number
_SIGNED = {
    "slope": (" deg", "level ground"),
    "step_height": (" m", "no stairs"),
}


class RequestError(ValueError):
    """A request that cannot be planned as asked; the message says why."""


@dataclass(frozen=True)
class PlanRequest:
    """A plan request; None (or empty) fields take the scene's values (`checked` also
    takes 0 for None)."""

    scene: str
    step_length: float | None = None
    cost: str | None = None
    friction_coefficient: float | None = None
    intervals_per_phase: int | None = None
    max_solve_time: float | None = None
    output_name: str = ""
    cold_start: bool = False
    compiled: bool = False  # compile the derivative elements (SolveOptions.compiled)
    steps: int = 1  # half cycles in the result, joined by the mirror (`ocp.walk_on`)
    posture: str = ""  # "paper" or "human" (`model.posture`); empty = the scene's
    speed: float | None = None  # m/s, step_length / half cycle (GaitSettings.speed); None: free
    slope: float = 0.0  # deg, uphill positive (GaitSettings.slope); 0: level
    step_height: float = 0.0  # m per step, stairs up (> 0) or down (GaitSettings.step_height)
    gait: str = ""  # a gait of the scene ("walk", "run", ...; `model.loader.with_gait`); "": walk


def _refuse(name: str, value: Any, allowed: str) -> RequestError:
    shown = value if isinstance(value, Real) else repr(value)
    return RequestError(f"{name} must be {allowed}, got {shown}")


def _number(name: str, value: Any) -> Any:
    """`value` of the numeric field `name`, None for 0 (the default); RequestError for
    anything else that is not a positive finite number."""
    whole = name == "intervals_per_phase"
    number = not isinstance(value, bool) and isinstance(value, Integral if whole else Real)
    if value is None or (number and value == 0):
        return None
    unit, zero = _NUMBERS[name]
    if not number or not math.isfinite(value) or value < 0:
        what = "a whole number > 0" if whole else f"> 0{unit}"
        raise _refuse(name, value, f"{what}, or 0 for {zero}")
    return value


def checked(request: PlanRequest) -> PlanRequest:
    """`request` with its 0 fields as None (the defaults) and 0 steps as 1; RequestError for
    the first field that breaks the rule of the module docstring."""
    numbers = {name: _number(name, getattr(request, name)) for name in _NUMBERS}
    for name, (unit, zero) in _SIGNED.items():
        value = getattr(request, name)
        if value is None:
            numbers[name] = 0.0
        elif isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
            raise _refuse(name, value, f"a finite number{unit}, or 0 for {zero}")
        else:
            numbers[name] = float(value)
    steps = request.steps or 1
    if isinstance(steps, bool) or not isinstance(steps, Integral) or not 1 <= steps <= MAX_STEPS:
        raise _refuse("steps", request.steps,
                      f"a whole number of half cycles from 1 to {MAX_STEPS}, or 0 for 1")
    if not isinstance(request.gait, str):
        raise _refuse("gait", request.gait, "a gait's name, or empty for the scene's walk")
    name = request.output_name or ""
    if not isinstance(name, str) or (name and (not _OUTPUT_NAME.fullmatch(
            name.removesuffix(".mcap")) or ".." in name)):
        raise RequestError(f"output_name must be a bare file name of letters, digits, '_', "
                           f"'-', '.' (no folders), got {request.output_name!r}")
    return dataclasses.replace(request, **numbers, steps=steps, cost=request.cost or None)


def plan_request(fields: Any = None, *, default_scene: str = "",
                 default_max_solve_time: float | None = None, compiled: bool = False,
                 **values: Any) -> PlanRequest:
    """The checked `PlanRequest` of a request's fields (`FIELDS`), read as attributes of
    `fields` (a PlanGait request, an action goal, parsed options named after the fields) or
    given as keywords; missing, 0 and empty fields take the defaults (`default_scene` and
    `default_max_solve_time`: the node's). The rule of the fields alone (a client checks a
    request before it sends it); `gait_planner.problem.resolve` checks it with the scene."""
    given = {name: getattr(fields, name) for name in FIELDS if hasattr(fields, name)}
    given.update(values)
    unknown = sorted(set(given) - set(FIELDS))
    if unknown:
        raise TypeError(f"not fields of a plan request: {', '.join(unknown)}")
    request = checked(PlanRequest(scene=given.get("scene") or default_scene,
                                  compiled=compiled, **{
                                      name: value for name, value in given.items()
                                      if name != "scene" and value is not None}))
    if request.max_solve_time is None and default_max_solve_time is not None:
        request = dataclasses.replace(request, max_solve_time=default_max_solve_time)
    return request
