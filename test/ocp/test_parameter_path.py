"""A request planned along a path of parameters from a kept optimum of another request
(`gait_planner.parameter_path`): the path's geometry, and the plans it reaches being the
plans a cold start reaches."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings as hyp_settings, strategies as st

from gait_planner.model.loader import load_scene
from gait_planner.ocp.prepare_requests import anchor_requests
from gait_planner.ocp.settings import SettingsError, settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.parameter_path import (PATH_STEP, _between, distance, nearest, point_of,
                                         start_point)
from gait_planner.strategies import plan_once

WALKER2D = load_scene("walker2d")
WALKER3D = load_scene("walker3d")
# walker2d's cold plans with the ground as constants (test_ocp_parameters.py)
CONSTANTS = Path(__file__).parent / "data" / "walker2d_constants.npz"

values = st.fixed_dictionaries({
    "slope": st.floats(-10, 10), "step_height": st.floats(-0.15, 0.15),
    "step_length": st.floats(0.4, 0.9), "friction_coefficient": st.floats(0.4, 1.2),
    "speed": st.one_of(st.just(0.0), st.floats(0.8, 1.6))})


@hyp_settings(max_examples=60, deadline=None)
@given(a=values, b=values, f=st.floats(0.0, 1.0))
def test_a_path_ends_at_the_request_and_no_step_is_longer_than_its_bound(a, b, f):
    """The path's point at f lies on the segment from a to b, the end is the request
    itself, and ceil(distance) steps keep every parameter's change within PATH_STEP."""
    end = settings_for(WALKER2D, **{k: v for k, v in b.items() if k not in ("speed",
                                                                             "step_height")})
    b = {**point_of(end), "speed": 0.0}
    a = {**a, "speed": 0.0}
    assert _between(end, a, b, 1.0) is end
    steps = max(1, math.ceil(distance(a, b) - 1e-9))
    first = point_of(_between(end, a, b, 1.0 / steps)) if steps > 1 else b
    for field, bound in PATH_STEP.items():
        assert abs(first[field] - a[field]) <= bound * (1 + 1e-9)
    middle = point_of(_between(end, a, b, f)) if f < 1.0 else b
    for field in PATH_STEP:
        assert middle[field] == pytest.approx(a[field] + f * (b[field] - a[field]), abs=1e-12)


def test_another_problem_shape_is_one_step_farther():
    a = {"slope": 0.0, "step_height": 0.0, "step_length": 0.6, "friction_coefficient": 0.8,
         "speed": 0.0}
    assert distance(a, a) == 0.0
    assert distance(a, {**a, "slope": 5.0}) == pytest.approx(2.0)
    assert distance(a, {**a, "step_height": 0.025}, same_shape=False) == pytest.approx(2.0)


def test_a_free_plan_heading_for_a_speed_starts_at_its_own_speed():
    """A plan with free durations has the speed of its step over its half cycle; a plan
    at a speed heading for free durations lets its speed go."""
    planner = Planner()
    settings = settings_for(WALKER2D, compiled=True)
    assert plan_once(planner, WALKER2D, settings, warm_start=False).success
    plan = planner.stored_plans(WALKER2D, settings)[-1]
    tr = planner.build(WALKER2D, settings, ())
    result_duration = tr.duration(plan.x)
    assert start_point(plan, result_duration, True)["speed"] == pytest.approx(
        plan.step / result_duration)
    assert start_point(plan, result_duration, False)["speed"] == 0.0
    # the duration is the speed row's: sigma times base_time_step over the first N-1
    sigma = plan.x[-int(tr.S.shape[0]):]
    scaling = [WALKER2D.gait.phases[k].scaling for k in tr.phase_of_interval[: tr.N - 1]]
    assert result_duration == pytest.approx(settings.base_time_step * sigma[scaling].sum())


def test_the_path_reaches_the_plans_a_cold_start_reaches():
    """walker2d: a ramp of 5 deg and stairs 0.05 m up, each continued from the level plan
    (another ground, and for the stairs another problem shape), reach J and the joint
    angles of the cold plans of the same requests, to the solver's tolerance."""
    reference = np.load(CONSTANTS)
    planner = Planner()
    level = settings_for(WALKER2D, compiled=True)
    assert plan_once(planner, WALKER2D, level, warm_start=False).success
    for name, options in (("ramp", {"slope": 5.0}), ("stairs_up", {"step_height": 0.05})):
        settings = settings_for(WALKER2D, compiled=True, **options)
        assert nearest(planner, WALKER2D, settings) is not None
        result = plan_once(planner, WALKER2D, settings)
        assert result.success, (name, result.message)
        assert "along a parameter path" in result.settings["initial_guess"]
        assert result.cost_value == pytest.approx(float(reference[f"{name}_J"]), rel=1e-7)
        np.testing.assert_allclose(result.joint_angles, reference[f"{name}_angles"],
                                   rtol=0, atol=1e-3)


def test_the_anchors_are_a_list_of_requests_and_no_setting_of_a_plan():
    anchors = anchor_requests(WALKER3D)
    assert {"slope": 10} in anchors and {"step_height": -0.1, "speed": 1.2} in anchors
    for anchor in anchors:  # each one a request the scene plans
        settings_for(WALKER3D, **anchor)
    with pytest.raises(SettingsError, match="unknown gait option"):
        settings_for(WALKER3D, warm_start_anchors=[{"slope": 1.0}])


@pytest.mark.parametrize("anchors, words", [
    ({"slope": 5}, "must be a list"),
    ([{"slant": 5}], "is not a request"),
    ([{"slope": float("nan")}], "is not a request"),
    ([{}], "is not a request"),
])
def test_a_broken_anchor_list_is_refused_naming_it(anchors, words):
    import dataclasses
    from types import MappingProxyType

    gait = dataclasses.replace(WALKER3D.gait, options=MappingProxyType(
        {**WALKER3D.gait.options, "warm_start_anchors": anchors}))
    with pytest.raises(SettingsError, match=words):
        anchor_requests(dataclasses.replace(WALKER3D, gait=gait))


def test_a_slow_pace_of_a_long_step_is_planned_not_refused():
    """walker3d at a requested speed lets sigma reach 3.0 (`speed_scaling_bounds`): 0.98
    m/s at a 0.73 m step is within reach; free durations keep the scene's 1.5."""
    assert settings_for(WALKER3D, speed=0.979, step_length=0.73).scaling_bounds == (0.5, 3.0)
    assert settings_for(WALKER3D).scaling_bounds == (0.5, 1.5)
    assert settings_for(WALKER3D, step_height=-0.1).scaling_bounds == (0.5, 2.0)
    assert settings_for(WALKER3D, step_height=-0.1, speed=1.0).scaling_bounds == (0.5, 3.0)
    with pytest.raises(SettingsError, match="speed = 0.5 m/s is outside"):
        settings_for(WALKER3D, speed=0.5, step_length=0.9)


def test_a_failed_path_is_planned_cold_and_says_so(monkeypatch):
    """With each path step capped at one iteration the path fails (every step halved down
    to 1/16 of the way), and the request is planned cold from its guess, as without a
    kept plan; its origin names both."""
    from gait_planner.ocp import solve

    planner = Planner()
    assert plan_once(planner, WALKER2D, settings_for(WALKER2D, compiled=True),
                     warm_start=False).success
    monkeypatch.setitem(solve.VARIANTS, "continued",
                        {**solve.VARIANTS["continued"], "ipopt.max_iter": 1})
    result = plan_once(planner, WALKER2D, settings_for(WALKER2D, compiled=True, slope=5.0))
    assert result.success, result.message
    origin = result.settings["initial_guess"]
    assert "along a parameter path (failed after" in origin and "kinematic guess" in origin
    reference = np.load(CONSTANTS)
    assert result.cost_value == pytest.approx(float(reference["ramp_J"]), rel=1e-7)


def test_no_path_runs_from_a_ramp_onto_stairs():
    """A kept ramp plan is never the start of a request on stairs (or a stairs plan of a
    ramp's): the path between them would cross grounds with both, which the planner does
    not build; the level default is taken instead, however the store orders them."""
    from gait_planner.ocp.warm_starts import StoredPlan
    from gait_planner.parameter_path import buildable

    level = {"slope": 0.0, "step_height": 0.0, "step_length": 0.6, "friction_coefficient": 0.8,
             "speed": 0.0}
    assert buildable(level, {**level, "slope": 5.0})
    assert buildable({**level, "step_height": -0.05}, {**level, "step_height": 0.1})
    assert not buildable({**level, "slope": 2.5}, {**level, "step_height": 0.025})
    assert not buildable({**level, "step_height": 0.025}, {**level, "slope": -2.5})

    settings = settings_for(WALKER2D, step_height=0.025)
    empty = np.zeros(1)
    ramp = StoredPlan(settings.step_length, settings.friction_coefficient, empty, empty, empty,
                      empty, slope=2.5)
    default = StoredPlan(settings.step_length, settings.friction_coefficient, empty, empty,
                         empty, empty)

    class Kept:  # a planner that keeps the ramp's plan first
        def build(self, scene, s, variants):
            return type("Built", (), {"duration": staticmethod(lambda x: 0.6)})()

        def all_plans(self, scene, s):
            return [ramp, default]

    assert nearest(Kept(), WALKER2D, settings)[0] is default
