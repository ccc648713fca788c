"""A requested speed (GaitSettings.speed): the half cycle lasts step_length / speed, in the
DMOCC and in the collocation baseline (`ocp.transcription.speed_row`), the recording passes
every check, and the verifier holds a recording to the speed its metadata asks for.

walker2d reaches 1.083 to 3.250 m/s at its 0.6338 m step (a nominal half cycle of 39
intervals of 10 ms, sigma in [0.5, 1.5]): 1.0 m/s is planned at a 0.55 m step (0.940 to
2.821 m/s there). A walker2d plan at a speed, certified and verified, takes 15-20 s here
(CasADi's derivatives, build included): those tests are slow; the compass's take 3 s.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from benchmarks.collocation import plan_collocation
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import duration_range, settings_for, speed_range
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.ocp.transcription import relaxed_lower_bounds, speed_row
from gait_planner.strategies import plan_certified
from gait_planner.verify import verify_result
from gait_planner.problem import resolve


@functools.cache
def _plan(name: str, speed: float, step_length: float | None = None):
    scene = load_scene(name)
    settings = settings_for(scene, speed=speed, step_length=step_length)
    result, _ = plan_certified(Planner(), scene, settings, warm_start=False)
    return settings, result


def test_the_reachable_speeds_are_the_step_over_the_durations_sigma_allows():
    scene = load_scene("walker2d")
    settings = settings_for(scene)
    assert duration_range(settings) == pytest.approx((0.5 * 0.39, 1.5 * 0.39), rel=1e-12)
    assert speed_range(settings) == pytest.approx((0.6338 / 0.585, 0.6338 / 0.195), rel=1e-12)
    # a finer grid of the same half cycle: 79 intervals of 5 ms
    finer = settings_for(scene, intervals_per_phase=16)
    assert duration_range(finer) == pytest.approx((0.5 * 0.395, 1.5 * 0.395), rel=1e-12)


def test_the_row_is_zero_at_the_speed_and_only_a_lower_bound_on_the_duration_first():
    assert speed_row(0.6, 0.5, 1 / 1.2) == pytest.approx(0.0, abs=1e-15)
    assert speed_row(0.6, 0.4, 1 / 1.2) > 0 > speed_row(0.6, 0.6, 1 / 1.2)  # short, long
    groups = [("pin_x", 1, True), ("speed", 1, True), ("friction_cone", 2, False)]
    lower = relaxed_lower_bounds(groups, np.zeros(4), [])
    assert lower[1] == -np.inf and np.all(lower[[0, 2, 3]] == 0)


def test_both_transcriptions_take_the_duration_of_the_speed():
    """The compass has one sigma: at 0.75 m/s its 0.3 m step takes 0.4 s (sigma 1), free
    it takes the longest half cycle (sigma 1.5, 0.6 s)."""
    settings, planned = _plan("compass", 0.75)
    for result in (planned, plan_collocation(load_scene("compass"), settings)):
        assert result.success, result.message
        assert result.duration == pytest.approx(0.4, rel=1e-9)
        assert result.settings["speed"] == "0.75"
    _, free = _plan("compass", 0.0)
    assert free.success and free.duration == pytest.approx(0.6, rel=1e-6)
    assert free.settings["speed"] == "0.0"


@pytest.mark.slow
@pytest.mark.parametrize("speed, step_length", [(1.0, 0.55), (1.3, None)])
def test_walker2d_walks_at_the_requested_speed_and_passes_verification(speed, step_length):
    settings, result = _plan("walker2d", speed, step_length)
    assert result.success, result.message
    assert result.step_length / result.duration == pytest.approx(speed, rel=1e-9)
    lo, hi = settings.scaling_bounds
    assert np.all(result.phase_scaling >= lo - 1e-8) and np.all(result.phase_scaling <= hi + 1e-8)
    report = verify_result(result)
    assert report.ok, report.failures


def test_the_verifier_fails_a_recording_whose_speed_was_edited():
    _, result = _plan("compass", 0.75)
    assert not [f for f in verify_result(result).failures if "speed" in f]
    edited = dataclasses.replace(result, settings={**result.settings, "speed": "0.76"})
    failures = [f for f in verify_result(edited).failures if "speed" in f]
    assert len(failures) == 1
    assert failures[0].startswith("the half cycle's mean speed step_length / (t_(N-1) - t_0) = ")
    assert failures[0].endswith("m/s differs from the requested speed 0.76 m/s (metadata "
                                "speed; relative limit 1e-09)")


def test_a_speed_alone_takes_the_step_of_least_cost_per_metre():
    """`plan_free_step`: at 1.2 m/s walker2d's step is chosen within the scene's bounds, and
    planning 2 cm shorter or longer costs more per metre (the golden-section search's
    5 mm tolerance is inside that)."""
    from gait_planner.ocp.settings import free_step_range
    from gait_planner.strategies import plan_free_step
    from gait_planner.request import PlanRequest

    problem = resolve(PlanRequest(scene="walker2d", speed=1.2, compiled=True))
    scene, settings = problem.scene, problem.settings
    assert settings.step_length_free and settings.step_length_bounds == (0.4, 0.9)
    planner = Planner()
    result, cert = plan_free_step(planner, scene, settings, warm_start=False)
    assert result.success and cert.ok, result.message
    low, high = free_step_range(settings)
    assert low < result.step_length < high
    assert result.duration == pytest.approx(result.step_length / 1.2, rel=1e-9)
    assert "least J per metre" in result.settings["step_length_search"]
    best = result.cost_value / result.step_length
    for other in (result.step_length - 0.02, result.step_length + 0.02):
        near = plan_once(planner, scene, dataclasses.replace(settings, step_length=other))
        assert near.success and near.cost_value / other > best


def test_a_speed_alone_reaches_what_any_step_within_the_bounds_reaches():
    """0.8 m/s is refused at the default step (1.083 m/s is the slowest there) but planned
    alone (a 0.4 m step reaches 0.684 m/s, up to the walk's speed_max); below that it is
    refused naming the bounds."""
    from gait_planner.request import PlanRequest, RequestError

    with pytest.raises(RequestError, match="at step_length 0.6338 m"):
        resolve(PlanRequest(scene="walker2d", speed=0.8, step_length=0.6338))
    settings = resolve(PlanRequest(scene="walker2d", speed=0.8)).settings
    # sigma's bounds reach 0.9 / 0.195 = 4.6 m/s; the walk's speed_max ends the range
    assert speed_range(settings) == pytest.approx((0.4 / 0.585, settings.speed_max), rel=1e-12)
    assert settings.speed_max == 3.5
    unlimited = dataclasses.replace(settings, speed_max=0.0)
    assert speed_range(unlimited) == pytest.approx((0.4 / 0.585, 0.9 / 0.195), rel=1e-12)
    with pytest.raises(RequestError, match=r"step lengths within \[0.4, 0.9\] m \(the step free\)"):
        resolve(PlanRequest(scene="walker2d", speed=0.5))
