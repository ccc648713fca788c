"""A run (`gait: run`, a scene's `gaits:`): forefoot stance, a flight phase with no
contact force at all, the other forefoot's stance; certified and verified at 3 m/s.
walker2d here (compiled, ~10 s); walker3d in the slow tests (~35 s)."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from gait_planner.strategies import plan_certified
from gait_planner.ocp.solve import Planner
from gait_planner.request import PlanRequest, RequestError
from gait_planner.verify import verify_result
from gait_planner.problem import resolve


@functools.cache
def _run(scene: str, speed: float):
    problem = resolve(PlanRequest(scene=scene, gait="run", speed=speed,
                                                   compiled=True))
    scene, settings = problem.scene, problem.settings
    return plan_certified(Planner(), scene, settings, warm_start=False)


def _check_run(result, certificate):
    assert result.success, result.message
    assert certificate.ok, certificate.summary
    assert result.duration == pytest.approx(1.0 / 3.0, rel=1e-9)  # 1.0 m at 3 m/s
    flight = [n for n, p in enumerate(result.phases) if p == "flight"]
    assert len(flight) >= 5
    for n in flight:
        assert result.active_contacts[n] == ()
        assert all(np.all(f[n] == 0.0) for f in result.contact_forces.values())
    report = verify_result(result)
    assert report.ok, report.failures


def test_walker2d_runs_at_3_m_s_with_a_flight_phase():
    _check_run(*_run("walker2d", 3.0))


@pytest.mark.slow
def test_walker3d_runs_at_3_m_s_with_a_flight_phase():
    _check_run(*_run("walker3d", 3.0))


def test_a_gait_the_scene_does_not_declare_is_refused_before_anything_is_built():
    with pytest.raises(RequestError, match="scene 'compass' has no gait 'run'; its gaits: walk"):
        resolve(PlanRequest(scene="compass", gait="run"))
