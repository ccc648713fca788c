"""The request's values are parameters of one compiled problem (issue #39): a new slope,
stair height, speed, step length or friction coefficient neither rebuilds nor compiles,
and the parametrised problem plans what the problem with those values folded in as
constants planned."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gait_planner.model.loader import load_scene
from gait_planner.ocp import compile as compile_module
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.ocp.transcription import shape_of

SCENE = load_scene("walker2d")
# walker2d's plans with the ground folded into the compiled code as constants (main at
# d84ca11, compiled derivatives, one fresh Planner per request in this order, 2026-11-28):
# J and joint angles (N+1, na) rad. On stairs down today's code itself reached either of
# two local minima, 21.7057 (145 iterations, as here) or 21.6454 (184 iterations, after
# three other plans in the same process): the round-off of the process's history decides.
CONSTANTS = Path(__file__).parent / "data" / "walker2d_constants.npz"
REQUESTS = (("level", {}), ("ramp", {"slope": 5.0}), ("stairs_up", {"step_height": 0.05}),
            ("stairs_down", {"step_height": -0.05}))


def _settings(**options):
    return settings_for(SCENE, **options).with_solve(compiled=True, max_solve_time=300.0)


def test_requests_of_one_form_share_one_problem():
    """Slope, stair height (of one sign), speed, step length and friction coefficient are
    values of the problem's parameters, not part of its shape."""
    base = _settings(speed=1.2)
    other = _settings(speed=1.45, step_length=0.7, friction_coefficient=0.6)
    assert shape_of(base) == shape_of(other)
    assert shape_of(_settings(slope=4.0)) == shape_of(_settings())
    assert shape_of(_settings(step_height=0.03)) == shape_of(_settings(step_height=0.12))
    assert shape_of(_settings(step_height=0.03)) != shape_of(_settings(step_height=-0.03))
    assert shape_of(_settings(speed=1.2)) != shape_of(_settings())


def test_a_request_never_asked_before_plans_without_the_compiler(monkeypatch):
    """With each form's libraries built (by `make setup`, else here first), a slope, a stair
    height and a speed never asked before are planned by fresh planners (as by a fresh
    process) without calling the C compiler."""
    for options in ({}, {"step_height": 0.02}, {"speed": 1.1}):
        Planner().prepare(SCENE, _settings(**options))

    def refuse(*args, **kwargs):
        raise AssertionError("the C compiler was called")

    monkeypatch.setattr(compile_module, "_build_all", refuse)
    for options in ({"slope": 3.7}, {"step_height": 0.037}, {"speed": 1.234, "slope": -2.1}):
        result = plan_once(Planner(), SCENE, _settings(**options), warm_start=False)
        assert result.success, (options, result.message)
        assert result.settings["derivatives"] == "per-node elements compiled to C"


@pytest.mark.slow
def test_make_setup_built_every_gait_of_the_shipped_scenes(monkeypatch):
    """`gait-planner prepare` (make setup) builds each gait a shipped scene declares (the
    run, the forefoot-first walk) in every shape, not only its walk: building them again
    needs no compiler. (Before, walker3d's first run at 3 m/s on a fresh machine compiled
    its elements during the request: 17 s against 2 s.)"""
    from gait_planner.model.loader import with_gait
    from gait_planner.ocp.prepare_requests import form_requests

    def refuse(*args, **kwargs):
        raise AssertionError("the C compiler was called: run make setup")

    monkeypatch.setattr(compile_module, "_build_all", refuse)
    for name in ("walker3d", "walker2d"):
        scene = load_scene(name)
        assert scene.gaits
        for gait in scene.gaits:
            other = with_gait(scene, gait)
            planner = Planner()
            for shape in form_requests(other, settings_for(other, compiled=True)):
                planner.prepare(other, shape)


def test_a_planner_answers_another_ground_with_the_problem_it_built():
    """One Planner builds one problem for a level and a ramp request: the second costs no
    build, and its plan stands on its own ground (the result names it)."""
    planner = Planner()
    level = plan_once(planner, SCENE, _settings(), warm_start=False)
    ramp = plan_once(planner, SCENE, _settings(slope=4.0), warm_start=False)
    assert level.success and ramp.success
    assert len(planner._built) == 1
    assert ramp.ground.slope == 4.0 and level.ground.slope == 0.0
    assert ramp.settings["slope"] == repr(4.0)
    # the torso climbs the ramp: the mirror image of the start is the step's rise higher
    z = ramp.q[:, 2]
    assert z[-2] - z[0] == pytest.approx(ramp.step_length * np.tan(np.radians(4.0)), abs=1e-9)


@pytest.mark.slow
def test_the_parametrised_problem_plans_what_the_constants_planned():
    """Level, ramp and stairs up: J and every joint angle as with the constants, to the
    solver's tolerance; stairs down: one of the two local minima the constants reached."""
    reference = np.load(CONSTANTS)
    for name, options in REQUESTS:
        result = plan_once(Planner(), SCENE, _settings(**options), warm_start=False)
        assert result.success, (name, result.message)
        if name == "stairs_down":
            assert any(result.cost_value == pytest.approx(float(reference[key]), rel=1e-8)
                       for key in ("stairs_down_J", "stairs_down_other_J")), result.cost_value
            continue
        # to the solver's tolerance (IPOPT tol 1e-8): the path to the optimum depends on the
        # process's history (stairs up: 62 or 100 iterations, J 1.4e-10 apart)
        assert result.cost_value == pytest.approx(float(reference[f"{name}_J"]), rel=1e-8)
        np.testing.assert_allclose(result.joint_angles, reference[f"{name}_angles"],
                                   rtol=0, atol=1e-4)
