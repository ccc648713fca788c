"""The verifier can fail: corrupted recordings of real plans are caught by the specific check,
and its mechanics agree with the lead's multibody code without sharing any of it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.model.angles import configuration
from gait_planner.verify import LIMITS, Mechanics, main, parse_scene, verify_plan, verify_result


def _failed(report, *words):
    """The failure sentences containing every word of `words`."""
    return [f for f in report.failures if all(w in f for w in words)]


# --------------------------------------------------------------------- corrupted plans


def test_perturbed_configuration_entry_is_caught(solved):
    r = solved("compass").result
    q = r.q.copy()
    q[10, 12 + 0] += 1e-6  # leg_l, phi_x at node 10
    rep = verify_result(dataclasses.replace(r, q=q))
    assert not rep.ok
    assert rep.max_joint_violation == pytest.approx(1e-6, rel=1e-6)
    assert _failed(rep, "joint hip constraints", "node 10")
    assert rep.worst_dynamics_node in (9, 10, 11)
    assert rep.max_dynamics_residual > 1e3 * LIMITS["dynamics"]
    assert _failed(rep, "Euler-Lagrange", f"node {rep.worst_dynamics_node}")


def test_perturbation_normal_to_the_constraints_is_caught_by_them(solved):
    """d1_y of a planar body moves with no admissible velocity: the Euler-Lagrange residual
    cannot see it (a force along a constraint normal is what multipliers absorb), the
    internal constraints do."""
    r = solved("compass").result
    q = r.q.copy()
    q[10, 12 + 4] += 1e-6  # leg_l, d1_y at node 10
    rep = verify_result(dataclasses.replace(r, q=q))
    assert rep.max_internal_violation == pytest.approx(1e-6, rel=0.1)
    assert _failed(rep, "internal constraints", "node 10")
    assert rep.max_dynamics_residual <= LIMITS["dynamics"]


def test_perturbed_position_breaks_joint_and_contact(solved):
    r = solved("walker2d").result
    q = r.q.copy()
    q[5, 12 * 3 + 0] += 1e-6  # foot_r phi_x at node 5 (full contact)
    rep = verify_result(dataclasses.replace(r, q=q))
    assert _failed(rep, "joint ankle_r", "node 5")
    assert _failed(rep, "moves by", "foot_r")
    assert rep.max_contact_drift == pytest.approx(1e-6, rel=0.1)
    assert _failed(rep, "Euler-Lagrange")


def test_flipped_contact_force_is_caught(solved):
    r = solved("compass").result
    n = 8
    forces = {k: v.copy() for k, v in r.contact_forces.items()}
    forces["foot_r"][n] *= -1.0
    rep = verify_result(dataclasses.replace(r, contact_forces=forces))
    assert _failed(rep, "foot_r pulls on the ground", f"node {n}")
    assert rep.min_normal_force < 0
    assert rep.worst_dynamics_node == n
    assert _failed(rep, "Euler-Lagrange", f"node {n}")


def test_friction_cone_violation_is_caught(solved):
    r = solved("walker2d").result
    forces = {k: v.copy() for k, v in r.contact_forces.items()}
    n = 12  # right forefoot stance
    name = "foot_r_forefoot"
    assert name in r.active_contacts[n]
    forces[name][n, 0] = 2.0 * r.friction_coefficient * forces[name][n, 2]
    rep = verify_result(dataclasses.replace(r, contact_forces=forces))
    assert _failed(rep, "foot_r", f"node {n}", "friction cone")
    assert rep.max_friction_ratio == pytest.approx(2.0, rel=1e-9)


def test_scaled_torque_is_caught(solved):
    """Efforts that no longer produce the recorded generalized force."""
    r = solved("walker2d").result
    tau = r.tau.copy()
    tau[20] *= 1.05
    rep = verify_result(dataclasses.replace(r, tau=tau))
    assert _failed(rep, "efforts", "do not produce")
    assert rep.max_effort_mismatch > 1e-4
    assert not _failed(rep, "Euler-Lagrange")  # q, forces and generalized force untouched


def test_consistently_scaled_torque_breaks_the_dynamics(solved, model):
    """Scaling one node's torque and its generalized force consistently keeps the
    actuation checks happy; the Euler-Lagrange equation of the node fails."""
    r = solved("walker2d").result
    mb = model("walker2d").mb
    n = 20
    h = np.diff(r.times)
    tau, gen = r.tau.copy(), r.generalized_force.copy()
    extra = 0.05 * tau[n]
    tau[n] += extra
    gen[n] += 0.5 * (h[n - 1] + h[n]) * np.array(mb.actuation(r.q[n])) @ extra
    rep = verify_result(dataclasses.replace(r, tau=tau, generalized_force=gen))
    assert rep.max_effort_mismatch <= LIMITS["actuation"]
    assert rep.max_revolute_off_axis <= LIMITS["actuation"]
    assert rep.worst_dynamics_node == n
    assert _failed(rep, "Euler-Lagrange")


def test_external_generalized_force_is_caught(solved):
    r = solved("compass").result
    gen = r.generalized_force.copy()
    gen[6, 0] += 1e-3  # a push on leg_r's centre of mass
    rep = verify_result(dataclasses.replace(r, generalized_force=gen))
    assert _failed(rep, "phi entries", "not internal")


def test_wrong_step_length_cost_and_duration_are_caught(solved):
    r = solved("compass").result
    rep = verify_result(dataclasses.replace(r, step_length=r.step_length + 1e-6))
    assert _failed(rep, "mirror images", "step")
    assert rep.max_periodicity_error == pytest.approx(1e-6, rel=1e-3)
    rep = verify_result(dataclasses.replace(r, cost_value=r.cost_value * (1 + 1e-6)))
    assert _failed(rep, "cost_value")
    rep = verify_result(dataclasses.replace(r, duration=r.duration + 0.01))
    assert _failed(rep, "duration")


def test_command_line(solved, capsys, tmp_path):
    path = solved("compass").path
    assert main([str(path)]) == 0
    out = capsys.readouterr().out
    assert "verdict: all checks passed" in out and "residual, relative" in out
    assert main([str(tmp_path / "missing.mcap")]) == 2


# --------------------------------------------------------------------- the mechanics


@pytest.mark.parametrize("name", ["compass", "walker2d", "walker3d"])
def test_mechanics_agree_with_the_multibody_code(model, name):
    """At random configurations of the lead's nodal reparametrisation: the verifier's
    constraints vanish, its Jacobian matches complex-step differentiation and annihilates
    the lead's null space matrix, and it has full rank m = k - ndof."""
    scene, mb, _ = model(name)
    mech = Mechanics(parse_scene(scene.source))
    assert mech.k == mb.k and mech.m == mb.m
    np.testing.assert_array_equal(mech.mass_diagonal, mb.mass_diagonal)
    rng = np.random.default_rng(3)
    q0 = configuration(scene)
    for _ in range(3):
        q = np.array(mb.reparametrise(rng.normal(scale=0.5, size=mb.ndof), q0)).ravel()
        assert np.abs(mech.constraint_values(q)).max() < 1e-14
        G = mech.constraint_jacobian(q)
        step = 1e-30
        for i in rng.choice(mb.k, size=8, replace=False):
            dq = np.zeros(mb.k, dtype=complex)
            dq[i] = 1j * step
            np.testing.assert_allclose(mech.constraint_values(q + dq).imag / step, G[:, i],
                                       atol=1e-14)
        P = np.array(mb.null_space(q))
        assert np.abs(G @ P).max() < 1e-13
        assert np.linalg.matrix_rank(G) == mech.m == mb.k - mb.ndof
        # the mirror image of a configuration is again a configuration
        assert np.abs(mech.constraint_values(mech.mirror(q, 0.3))).max() < 1e-14
        np.testing.assert_allclose(mech.mirror(mech.mirror(q, 0.3), -0.3), q, atol=1e-15)


def test_verifier_reads_the_plan_alone(solved):
    """verify_plan needs only the decoded recording (the scene comes from its attachment)."""
    rec = read_plan_mcap(solved("compass").path)
    assert verify_plan(rec).ok
