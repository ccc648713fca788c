"""The one rule of a plan request's fields (`gait_planner.request`): 0 or empty is the
default, a negative, NaN or infinite number is refused with the field, the value and what
is allowed; the same message from `plan_request` (node, action, `call`) and from
`problem.resolve` (`plan`)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from gait_planner.cli.ros_commands import GAIT_HELP, SPEED_HELP
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for, speed_range
from gait_planner.pipeline import plan_and_record
from gait_planner.request import FIELDS, MAX_STEPS, PlanRequest, RequestError, plan_request
from gait_planner.problem import resolve

SCENE_DEFAULT = "the scene's default"
REFUSED = [
    ("step_length", -0.5, f"step_length must be > 0 m, or 0 for {SCENE_DEFAULT}, got -0.5"),
    ("step_length", math.nan, f"step_length must be > 0 m, or 0 for {SCENE_DEFAULT}, got nan"),
    ("step_length", math.inf, f"step_length must be > 0 m, or 0 for {SCENE_DEFAULT}, got inf"),
    ("friction_coefficient", -1e-9,
     f"friction_coefficient must be > 0, or 0 for {SCENE_DEFAULT}, got -1e-09"),
    ("friction_coefficient", -math.inf,
     f"friction_coefficient must be > 0, or 0 for {SCENE_DEFAULT}, got -inf"),
    ("intervals_per_phase", -3,
     f"intervals_per_phase must be a whole number > 0, or 0 for {SCENE_DEFAULT}, got -3"),
    ("intervals_per_phase", 2.5,
     f"intervals_per_phase must be a whole number > 0, or 0 for {SCENE_DEFAULT}, got 2.5"),
    ("max_solve_time", -1.0, "max_solve_time must be > 0 s, or 0 for the default limit, "
     "got -1.0"),
    ("max_solve_time", math.nan, "max_solve_time must be > 0 s, or 0 for the default limit, "
     "got nan"),
    ("steps", -2, f"steps must be a whole number of half cycles from 1 to {MAX_STEPS}, or 0 "
     "for 1, got -2"),
    ("steps", MAX_STEPS + 1, f"steps must be a whole number of half cycles from 1 to "
     f"{MAX_STEPS}, or 0 for 1, got {MAX_STEPS + 1}"),
    ("step_length", "0.5", f"step_length must be > 0 m, or 0 for {SCENE_DEFAULT}, got '0.5'"),
    ("speed", -1.0, "speed must be > 0 m/s, or 0 for free phase durations, got -1.0"),
    ("speed", math.nan, "speed must be > 0 m/s, or 0 for free phase durations, got nan"),
    ("slope", math.inf, "slope must be a finite number deg, or 0 for level ground, got inf"),
    ("step_height", "0.1", "step_height must be a finite number m, or 0 for no stairs, got '0.1'"),
]


@pytest.mark.parametrize("name, value, message", REFUSED)
def test_a_bad_number_is_refused_the_same_way_everywhere(name, value, message):
    with pytest.raises(RequestError) as from_fields:
        plan_request(scene="compass", **{name: value})
    assert str(from_fields.value) == message
    with pytest.raises(RequestError) as from_pipeline:  # the path of `gait-planner plan`
        resolve(PlanRequest(scene="compass", **{name: value}))
    assert str(from_pipeline.value) == message


def test_zero_and_empty_fields_are_the_defaults():
    message = SimpleNamespace(scene="", step_length=0.0, cost="", friction_coefficient=0.0,
                              intervals_per_phase=0, max_solve_time=0.0, output_name="",
                              cold_start=False, steps=0, posture="", speed=0.0, slope=0.0,
                              step_height=0.0, gait="")
    assert set(vars(message)) == set(FIELDS)
    request = plan_request(message, default_scene="walker2d", default_max_solve_time=60.0,
                           compiled=True)
    assert request == PlanRequest(scene="walker2d", max_solve_time=60.0, compiled=True)
    # `plan` (no node): 0 is the scene's value and GaitSettings' time limit
    problem = resolve(PlanRequest(scene="compass", step_length=0.0,
                                                   friction_coefficient=0,
                                                   intervals_per_phase=0, max_solve_time=0.0,
                                                   steps=0))
    scene, settings = problem.scene, problem.settings
    problem = resolve(PlanRequest(scene="compass"))
    default_scene, default = problem.scene, problem.settings
    assert settings == default and scene == default_scene


def test_given_values_pass_unchanged_and_unknown_fields_are_named():
    request = plan_request(scene="compass", step_length=0.31, friction_coefficient=0.7,
                           intervals_per_phase=4, max_solve_time=5.0, steps=3,
                           cost="kinetic_energy", output_name="x", cold_start=True,
                           posture="paper", speed=0.8,
                           default_max_solve_time=60.0)
    assert (request.step_length, request.friction_coefficient, request.intervals_per_phase,
            request.max_solve_time, request.steps, request.speed) == (0.31, 0.7, 4, 5.0, 3, 0.8)
    assert (request.cost, request.output_name, request.cold_start, request.posture) == (
        "kinetic_energy", "x", True, "paper")
    with pytest.raises(TypeError, match="not fields of a plan request: mu"):
        plan_request(scene="compass", mu=0.5)


def test_the_scene_ranges_still_apply_after_the_sign_rule():
    with pytest.raises(RequestError, match=r"step_length = 3.0 is outside the range"):
        resolve(plan_request(scene="compass", step_length=3.0))


class _NoPlanner:
    """A planner that fails the test if anything asks it to build or plan."""

    def plan(self, *args, **kwargs):
        raise AssertionError("a refused request reached the planner")

    prepare = plan


WALKER2D_SPEEDS = "[1.0834, 3.2503] m/s (a half cycle of 0.195 to 0.585 s: sigma within " \
    "scaling_bounds [0.5, 1.5])"


@pytest.mark.parametrize("speed", [1.0, 3.3])
def test_an_unreachable_speed_is_refused_with_its_range_before_anything_is_built(
        speed, tmp_path):
    """walker2d's 0.6338 m step over a half cycle of 0.39 s times sigma in [0.5, 1.5]."""
    with pytest.raises(RequestError) as refused:
        plan_and_record(_NoPlanner(), resolve(plan_request(scene="walker2d", speed=speed,
                                                           step_length=0.6338)), tmp_path)
    assert str(refused.value) == (f"speed = {speed} m/s is outside the range scene 'walker2d' "
                                  f"allows at step_length 0.6338 m: {WALKER2D_SPEEDS}")
    assert not any(tmp_path.iterdir())
    # the range moves with the step length: 1.0 m/s is a 0.5 m step in 0.5 s
    settings = resolve(plan_request(scene="walker2d", step_length=0.5, speed=1.0)).settings
    assert settings.speed == 1.0 and speed_range(settings) == pytest.approx((0.5 / 0.585,
                                                                             0.5 / 0.195))


@pytest.mark.parametrize("speed", [0.5, 5.0])
def test_a_speed_alone_no_step_in_the_bounds_reaches_is_refused(speed, tmp_path):
    """With the step free (no step_length), any step of the scene's step_length_bounds
    [0.4, 0.9] m over the half cycles sigma allows (0.684 to 4.615 m/s), no faster than
    the walk's speed_max (walker2d: 3.5 m/s)."""
    with pytest.raises(RequestError) as refused:
        plan_and_record(_NoPlanner(), resolve(plan_request(scene="walker2d", speed=speed)),
                        tmp_path)
    assert str(refused.value) == (
        f"speed = {speed} m/s is outside the range scene 'walker2d' allows at step lengths "
        f"within [0.4, 0.9] m (the step free): [0.6838, 3.5000] m/s (a half cycle of 0.195 to "
        f"0.585 s: sigma within scaling_bounds [0.5, 1.5]"
        f"; no faster than the gait's speed_max 3.5 m/s, the fastest it was planned at, "
        f"with joint_speed_max 450 deg/s (the scene file says where))")
    assert not any(tmp_path.iterdir())


def test_a_walk_faster_than_the_scene_ever_planned_is_refused_before_building(tmp_path):
    """walker3d's walk declares speed_max 3.0 m/s (3.5 and 4.0 m/s found no plan in 90 s,
    its joint speed rows most violated), below sigma's 3.333 m/s at a 0.9 m step; its run
    declares none, so a run at 3.5 m/s stays a request to plan."""
    with pytest.raises(RequestError) as refused:
        plan_and_record(_NoPlanner(), resolve(plan_request(scene="walker3d", speed=3.2,
                                                           step_length=0.9)), tmp_path)
    assert "[0.7692, 3.0000] m/s" in str(refused.value)  # sigma within [0.5, 3.0] at a speed
    assert "speed_max 3 m/s" in str(refused.value)
    assert not any(tmp_path.iterdir())
    walk = resolve(plan_request(scene="walker3d", speed=3.0, step_length=0.9)).settings
    assert walk.speed == 3.0
    run = resolve(plan_request(scene="walker3d", speed=3.5, gait="run")).settings
    assert run.speed == 3.5 and run.speed_max == 0


def test_a_speed_reaches_the_settings_and_0_leaves_the_durations_free():
    message = SimpleNamespace(scene="", step_length=0.0, cost="", friction_coefficient=0.0,
                              intervals_per_phase=0, max_solve_time=0.0, output_name="",
                              cold_start=False, steps=0, posture="", speed=1.2)  # as received
    settings = resolve(plan_request(message, default_scene="walker2d")).settings
    assert settings.speed == 1.2
    free = resolve(plan_request(scene="walker2d", speed=0.0)).settings
    assert free.speed == 0.0


@pytest.mark.parametrize("scene", ["walker2d", "walker3d"])
def test_the_help_shows_the_speeds_a_scene_reaches(scene):
    slow, fast = speed_range(settings_for(load_scene(scene), speed=2.0))  # sigma at a speed
    assert f"{slow:.3f} to {fast:.3f} m/s" in SPEED_HELP


def test_the_help_names_the_shipped_scenes_gaits():
    listed = GAIT_HELP.split("walker2d and walker3d:")[1]
    for scene in ("walker2d", "walker3d"):
        assert all(gait in listed for gait in load_scene(scene).gaits)
        assert sorted(load_scene(scene).gaits) == ["run", "toe_first"]
