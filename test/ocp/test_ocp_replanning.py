"""Warm starts, failures with reasons, and settings errors that name the field."""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import pytest

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import SettingsError, settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.verify import verify_result

# every status IPOPT can end a failed solve with, in the words of the planner's message
_STATUS_WORDS = ("time limit reached", "locally infeasible", "restoration failed",
                 "iteration limit reached", "search direction became too small",
                 "iterates diverged", "NaN or Inf", "step computation failed",
                 "acceptable but not optimal")
_GROUPS = ("dynamics[", "contact_hold", "contact_establish", "pin_x", "friction_cone",
           "ground_clearance", "torso_lean", "torso_height", "joint_limits", "joint_speed")


def _assert_explained_failure(result, limit: float, elapsed: float):
    assert result.success is False
    assert "IPOPT:" in result.message
    assert any(w in result.message for w in _STATUS_WORDS), result.message
    assert f"({result.stats.status})" in result.message
    assert "most violated:" in result.message
    assert any(g in result.message for g in _GROUPS), result.message
    assert result.stats.most_violated and result.stats.most_violated in result.message
    # the time limit covers guess and solve; building comes on top (plus result assembly)
    assert elapsed <= limit + result.stats.build_time + 1.5, (elapsed, result.stats)


# --------------------------------------------------------------------- warm start


def test_warm_start_replans_a_longer_step_quickly(solved):
    s = solved("walker2d")
    cold = s.result.stats.iterations
    warm = plan_once(s.planner, s.scene,
                     settings_for(s.scene, step_length=1.05 * s.settings.step_length))
    assert warm.success, warm.message
    # speed itself is measured in benchmarks/plan.py; here: far fewer iterations
    assert warm.stats.iterations < cold / 2, (warm.stats.iterations, cold)
    assert "warm start" in warm.settings["initial_guess"]
    assert warm.step_length == pytest.approx(1.05 * s.settings.step_length)
    rep = verify_result(warm)
    assert rep.ok, "\n".join(rep.failures)
    assert rep.max_periodicity_error <= 1e-8


# --------------------------------------------------------------------- failures


@pytest.fixture(scope="module")
def compass_planner():
    """A compass Planner of its own (the shared one keeps only good plans to start from)."""
    scene = load_scene("compass")
    planner = Planner()
    assert plan_once(planner, scene, settings_for(scene)).success
    return scene, planner


@pytest.mark.parametrize("change", [
    {"step_length": 3.0},  # 1 m legs cannot span 3 m
    {"friction_coefficient": 0.01},  # no walking on ice
], ids=["step_3m", "mu_0.01"])
def test_impossible_request_fails_with_reasons(compass_planner, change):
    scene, planner = compass_planner
    limit = 5.0
    start = time.perf_counter()
    result = plan_once(planner, scene, settings_for(scene, max_solve_time=limit, **change),
                       warm_start=False)
    _assert_explained_failure(result, limit, time.perf_counter() - start)


def test_impossible_request_fails_from_a_warm_start_within_the_time_limit(solved):
    """walker2d asked for a 3 m step, warm-started from its plan: stopped at the limit."""
    s = solved("walker2d")
    limit = 4.0
    start = time.perf_counter()
    result = plan_once(s.planner, s.scene, settings_for(s.scene, step_length=3.0,
                                                        max_solve_time=limit))
    _assert_explained_failure(result, limit, time.perf_counter() - start)


def test_time_limit_stops_the_solve(compass_planner):
    scene, planner = compass_planner
    limit = 0.005  # a cold compass plan takes about 12 iterations, 0.04 s
    start = time.perf_counter()
    result = plan_once(planner, scene, settings_for(scene, max_solve_time=limit), warm_start=False)
    _assert_explained_failure(result, limit, time.perf_counter() - start)
    assert "time limit reached" in result.message


def test_scaling_bounds_that_cannot_fit(compass_planner):
    """A half cycle of 21 x 1 ms for a 0.3 m step: the stance foot would have to pull."""
    scene, planner = compass_planner
    limit = 3.0
    settings = dataclasses.replace(settings_for(scene, max_solve_time=limit),
                                   scaling_bounds=(0.05, 0.05))
    start = time.perf_counter()
    result = plan_once(planner, scene, settings, warm_start=False)
    _assert_explained_failure(result, limit, time.perf_counter() - start)


def test_unbuildable_problem_is_a_result_not_a_traceback(compass_planner):
    scene, planner = compass_planner
    result = plan_once(planner, scene, settings_for(scene, intervals_per_phase=1))
    assert result.success is False
    assert "could not build the problem" in result.message and "intervals" in result.message
    assert math.isnan(result.cost_value) and result.times.size == 0


@pytest.mark.parametrize("kwargs, field", [
    ({"step_length": float("nan")}, "step_length"),
    ({"step_length": -0.3}, "step_length"),
    ({"step_length": 0.0}, "step_length"),
    ({"friction_coefficient": float("inf")}, "friction_coefficient"),
    ({"friction_coefficient": -1.0}, "friction_coefficient"),
    ({"cost": "elegance"}, "cost"),
    ({"max_solve_time": 0.0}, "max_solve_time"),
    ({"max_solve_time": float("nan")}, "max_solve_time"),
    ({"torque_regularisation": -1e-4}, "torque_regularisation"),
    ({"no_such_option": 1}, "no_such_option"),
])
def test_bad_settings_raise_naming_the_field(kwargs, field):
    scene = load_scene("compass")
    with pytest.raises(SettingsError, match=field):
        settings_for(scene, **kwargs)


# ------------------------------------------------------------ cold-start fallback


def test_failed_inertia_free_attempt_restarts_with_the_inertia_test(monkeypatch):
    """A cold plan whose inertia-free attempt hits its iteration cap starts again from the
    guess with IPOPT's inertia correction, converges, and says so."""
    from gait_planner.ocp import solve

    monkeypatch.setitem(solve.VARIANTS, "cold", {**solve.VARIANTS["cold"], "ipopt.max_iter": 3})
    scene = load_scene("compass")
    result = plan_once(Planner(), scene, settings_for(scene))
    assert result.success, result.message
    assert "inertia-free attempt stopped (iteration limit reached) after 3 iterations" in \
        result.settings["initial_guess"]
    assert result.stats.iterations > 3
    assert verify_result(result).ok


def test_rotation_increments_are_bounded_translations_are_not():
    from gait_planner.dynamics.discrete import DiscreteMechanics
    from gait_planner.model.multibody import Multibody
    from gait_planner.ocp.transcription import ROTATION_INCREMENT_MAX, Transcription

    for name, translations in (("walker3d", 3), ("walker2d", 2)):
        scene = load_scene(name)
        tr = Transcription(DiscreteMechanics(Multibody(scene)), settings_for(scene))
        lbx, ubx, _, _ = tr.bounds()
        u_upper = ubx[: tr.U.numel()].reshape(tr.N - 1, tr.mb.ndof)
        u_lower = lbx[: tr.U.numel()].reshape(tr.N - 1, tr.mb.ndof)
        assert np.all(np.isinf(u_upper[:, :translations]))
        assert np.all(u_upper[:, translations:] == ROTATION_INCREMENT_MAX)
        assert np.all(u_lower[:, translations:] == -ROTATION_INCREMENT_MAX)
        assert np.all(np.isinf(ubx[tr.U.numel(): -tr.S.shape[0]]))  # torques, forces free
