"""The plan against physics (gait_planner.verify.drift): a plan's torques and contact
schedule on the continuous equations of motion (Pinocchio, DOP853).

A motion the continuous simulation itself produced is reproduced to integration tolerance;
the plastic impact map leaves the held points at rest and only removes energy; DMOCC plans
drift less on a finer grid where their motion is smooth (the first phase: roughly second
order in h); torque errors planted in a plan make it drift more; a blow-up is reported, not
raised.
"""

from __future__ import annotations

import dataclasses
import functools
import json

import numpy as np
import pinocchio as pin
import pytest

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.verify.constrained import ConstrainedModel
from gait_planner.verify.mechanics import parse_scene
from gait_planner.verify.drift import PlanSimulation, physics_error


@functools.cache
def plan(name: str, intervals_per_phase: int | None = None, base_time_step: float | None = None,
         compiled: bool = False):
    """The planner's plan of `name`; a finer grid keeps the phase durations reachable by
    scaling the base time step with 1 / intervals_per_phase."""
    scene = load_scene(name)
    settings = settings_for(scene, intervals_per_phase=intervals_per_phase, compiled=compiled)
    if base_time_step is not None:
        settings = dataclasses.replace(settings, base_time_step=base_time_step)
    result = plan_once(Planner(), scene, settings)
    assert result.success, result.message
    return result


@pytest.mark.parametrize("grid", [("compass",), pytest.param(("walker2d", 4, 0.02),
                                                          marks=pytest.mark.slow)],
                         ids=lambda g: g[0])
def test_a_simulated_motion_is_reproduced_to_integration_tolerance(grid):
    """A scene's own continuous motion under its plan's torques and schedule (impacts at
    the switches, open loop: the walker falls), published as a plan with the simulated
    foot forces (a full contact's on its first point): zero drift in both modes."""
    result = plan(*grid)
    sim = PlanSimulation(result)
    run = sim.run("none", rtol=1e-12, atol=1e-12)
    assert not run.failure
    q = np.array([sim.cm.director_configuration(c) for c in run.q])
    forces = {name: np.zeros((sim.N + 1, 3)) for name in sim.scene.contacts}
    for n, held in enumerate(sim.active):
        for body, force in run.forces[n].items():
            forces[min(c for c in held if sim.scene.contacts[c][0] == body)][n] = force
    motion = dataclasses.replace(result, q=q, contact_forces=forces)
    starts = {s: run.v[s] for s, _, _ in sim.segments}
    for reset in ("none", "phase"):
        error = physics_error(motion, reset=reset, start_velocities=starts)
        assert error.ok, error.failure
        assert error.angle_drift_max_deg < 1e-5  # 2e-7 rad after 0.6 s open loop
        assert error.contact_drift_max_mm < 1e-4
        assert error.force_error_relative < 1e-6
        assert error.constraint_error_max < 1e-9
        json.dumps(error.as_dict())


@pytest.mark.parametrize("name", ["walker2d", "walker3d"])
def test_the_plastic_impact_stops_the_held_points_and_only_removes_energy(name):
    cm = ConstrainedModel(parse_scene((load_scene(name).source)))
    rng = np.random.default_rng(5)
    q = pin.integrate(cm.model, pin.neutral(cm.model), 0.3 * rng.standard_normal(cm.nv))
    v_minus = rng.standard_normal(cm.nv)
    blocks = cm.blocks(q, ("foot_r_heel", "foot_r_forefoot", "foot_l_forefoot"))
    v_plus = cm.impact(q, v_minus, blocks)
    J = cm.jacobian(q, blocks)
    M = pin.crba(cm.model, cm.data, q)
    assert np.abs(J @ v_plus).max() < 1e-12 * np.abs(J @ v_minus).max()
    assert np.allclose(cm.impact(q, v_plus, blocks), v_plus, atol=1e-12)  # a projection
    impulse = M @ (v_plus - v_minus)  # = J^T Lambda: the contacts' impulse only
    Lambda = np.linalg.lstsq(J.T, impulse, rcond=None)[0]
    assert np.abs(J.T @ Lambda - impulse).max() < 1e-10 * np.abs(impulse).max()
    assert v_plus @ M @ v_plus < v_minus @ M @ v_minus


@pytest.mark.slow
def test_drift_shrinks_on_a_finer_grid_where_the_plan_is_smooth():
    """walker2d at 4 and 8 intervals per phase, same phase durations (base time step
    0.02 and 0.01 s), reset per phase: the first phase (full contact, no switch at its start)
    drifts ~6x less on the finer grid (second order would be 4x)."""
    coarse = physics_error(plan("walker2d", 4, 0.02), reset="phase")
    fine = physics_error(plan("walker2d", 8, 0.01), reset="phase")
    assert coarse.ok and fine.ok
    assert coarse.segments[0] == (0, 4) and fine.segments[0] == (0, 8)
    assert fine.segment_drift_deg[0] < coarse.segment_drift_deg[0] / 3


@pytest.mark.slow
def test_planted_torque_errors_drift_more():
    """5 N m added to the swing knee at nodes 2..5 of the first phase."""
    result = plan("walker2d", 8, 0.01)
    tau = result.tau.copy()
    tau[2:6, result.joint_angle_names.index("knee_l")] += 5.0
    honest = physics_error(result, reset="phase")
    planted = physics_error(dataclasses.replace(result, tau=tau), reset="phase")
    assert planted.segment_drift_deg[0] > 2 * honest.segment_drift_deg[0]
    assert planted.segment_drift_deg[1:] == honest.segment_drift_deg[1:]  # reset per phase


def test_a_blow_up_is_reported_with_its_reason():
    result = plan("compass")
    error = physics_error(dataclasses.replace(result, tau=1e4 * result.tau), reset="none")
    assert not error.ok
    assert "velocity above" in error.failure
    assert np.isnan(error.angle_drift_deg[-1])
    assert "FAILED" in error.summary()


@pytest.mark.slow
def test_walker3d_plan_on_the_continuous_dynamics():
    """The default walker3d plan (compiled derivatives), reset per phase: the held contacts
    stay put to round-off; on flat feet (double_full: left foot and right forefoot) the
    plan follows the continuous dynamics to about a degree. In the first phase (right foot
    flat) every joint stays within 2.5 deg but the swing foot's yaw about the shank, the
    lightest degree of freedom (0.0007 kg m^2), which drifts at a near-constant rate from
    the phase's start: 8.2 deg after 8 intervals since its edges must clear the ground
    (ocp/clearance.py; 2.1 deg before, when the foot could roll). (The point-contact
    phases drift tens of degrees: a 3D point contact leaves the light foot free to roll
    about it; measured, not asserted.)"""
    error = physics_error(plan("walker3d", compiled=True), reset="phase")
    assert error.ok, error.failure
    assert error.constraint_error_max < 1e-9
    drift = error.segment_drift_deg
    assert drift[0] < 10.0 and drift[3] < 3.0
