"""One door for a request: `resolve` turns a request (the service's, the action's, the
command line's, a gait library's grid point, a Python call) into a `Problem`, frozen and
checked, which everything downstream takes and never checks again.

What is checked, in this order, and where the rule is written:
1. every field's own rule (a number, a sign, a range of steps; 0 for the default):
   `gait_planner.request.checked`;
2. the scene: found by `scenes` (its name, or a path for the command line's `find_scene`)
   and given the request's gait (`model.loader.with_gait`);
3. the scene's ranges for the request (step length, friction, intervals, time limit):
   `gait_planner.ocp.request_ranges.check_request`;
4. the gait settings the request and the scene make, with their own consistency (a speed
   the scaling bounds can reach, a ground the scene can stand on): `ocp.settings.settings_for`.
Any refusal is a `RequestError` whose sentence names the field, its value and what is
allowed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from gait_planner.model.loader import SceneError, available_scenes, load_scene, with_gait
from gait_planner.model.scene import Scene
from gait_planner.ocp.held_efforts import check_holds
from gait_planner.ocp.request_ranges import RangeError, check_request
from gait_planner.ocp.settings import GaitSettings, SettingsError, settings_for
from gait_planner.request import PlanRequest, RequestError, checked

SceneLookup = Callable[[str], Scene]  # a request's scene field -> the scene


@dataclass(frozen=True)
class Problem:
    """A request resolved: the checked request (its 0 fields None, steps at least 1; its
    output name, steps and start are read from it), the scene with the request's gait,
    and the gait settings (the problem solved and the solver's options)."""

    request: PlanRequest
    scene: Scene
    settings: GaitSettings

    @property
    def steps(self) -> int:
        """Half cycles in the answer (joined by the mirror, `ocp.walk_on`)."""
        return self.request.steps

    @property
    def warm_start(self) -> bool:
        """Whether the plan may start from a plan the planner keeps (not cold_start)."""
        return not self.request.cold_start


def resolve(request: PlanRequest, scenes: SceneLookup = load_scene) -> Problem:
    """The `Problem` of `request` (module docstring); RequestError says what cannot be
    planned. scenes: finds the scene of request.scene (`load_scene`: bare names only; the
    command line's `find_scene` also takes paths, the node's looks in its scene_dirs too)."""
    request = checked(request)
    try:
        try:
            scene = with_gait(scenes(request.scene), request.gait)
        except OSError as err:  # a name the file system refuses, e.g. one too long
            raise SceneError(f"scene {request.scene!r} cannot be looked up ({err.strerror}); "
                             f"available scenes: {', '.join(available_scenes())}") from None
        check_request(scene, step_length=request.step_length,
                      friction_coefficient=request.friction_coefficient,
                      intervals_per_phase=request.intervals_per_phase,
                      max_solve_time=request.max_solve_time)
        check_holds(scene)
        settings = settings_for(
            scene, step_length=request.step_length, cost=request.cost or None,
            friction_coefficient=request.friction_coefficient,
            intervals_per_phase=request.intervals_per_phase,
            max_solve_time=request.max_solve_time,
            **({"compiled": True} if request.compiled else {}),
            **({"posture": request.posture} if request.posture else {}),
            **({"speed": request.speed} if request.speed else {}),
            **({"step_length_free": True} if request.speed and not request.step_length else {}),
            **({"slope": request.slope} if request.slope else {}),
            **({"step_height": request.step_height} if request.step_height else {}))
    except (SceneError, SettingsError, RangeError) as err:
        raise RequestError(str(err)) from None
    return Problem(request, scene, settings)
