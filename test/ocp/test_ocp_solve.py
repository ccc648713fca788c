"""`ocp.solve.Planner` solves from the start it is given and decides nothing: an attempt
from a kept optimum ends where it began, the request's clock bounds it and counts for it,
and only a converged result is kept for warm starts (`gait_planner.strategies` chooses
the start and what to do on failure)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Clock, Planner, Start
from gait_planner.strategies import COLD_ATTEMPTS, WARM_ATTEMPTS, guess_start, plan_once


@pytest.fixture(scope="module")
def optimum():
    scene = load_scene("compass")
    settings = settings_for(scene)
    planner = Planner()
    result = plan_once(planner, scene, settings, warm_start=False)
    assert result.success, result.message
    return planner, scene, settings, result


def test_an_attempt_from_an_optimum_stays_there(optimum):
    planner, scene, settings, cold = optimum
    kept = planner.stored_plans(scene, settings)[0]
    before = len(planner.stored_plans(scene, settings))
    clock = Clock.begin(settings.solve.max_solve_time)
    reached = planner.attempt(scene, settings, WARM_ATTEMPTS[0], Start.of(kept, "kept"), clock)
    assert reached.success and clock.iterations <= 3
    assert np.max(np.abs(reached.x - kept.x)) < 1e-6
    again = planner.result(scene, settings, reached, clock, "from the kept optimum")
    assert again.cost_value == pytest.approx(cold.cost_value, rel=1e-9)
    assert again.settings["initial_guess"] == "from the kept optimum"
    assert again.stats.iterations == clock.iterations
    assert len(planner.stored_plans(scene, settings)) == before + 1  # a converged one is kept


def test_the_clock_bounds_and_counts_every_attempt_of_a_request(optimum):
    planner, scene, settings, _ = optimum
    start = guess_start(planner, scene, settings, "kinematic", "guess")
    before = len(planner.stored_plans(scene, settings))
    clock = Clock(time.perf_counter(), time.perf_counter() - 1.0, iterations=7)  # past
    reached = planner.attempt(scene, settings, COLD_ATTEMPTS[0], start, clock)
    assert not reached.success and clock.expired()
    assert 7 <= clock.iterations <= 7 + 1  # stopped within one iteration, counted on top
    failed = planner.result(scene, settings, reached, clock, "guess")
    assert not failed.success and failed.stats.iterations == clock.iterations
    assert len(planner.stored_plans(scene, settings)) == before  # a failure is not kept
