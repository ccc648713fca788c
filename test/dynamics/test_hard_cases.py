"""Hard cases of the simulator: stretched knees, large steps, angle-chart singularities and
the paper's non-realisable torso inertia.

* A knee at exactly 0 (fully stretched) and motions through 0 are regular: Newton converges
  in a few iterations, constraints hold to round-off, momentum is conserved; also in double
  support (a closed loop through both stretched legs).
* dt = 0.05 s: the trapezoidal discrete Lagrangian's momentum of a body turning by theta
  per step is ~ J sin(theta)/h, at most J/h: a body spinning faster than ~1/h has no next
  configuration (the equations fold; see benchmarks/REPORT.md). The light feet reach that
  in passive chaotic motion, so the simulator must raise SimulationError with a clear
  message; a moderate motion runs many steps at dt = 0.05.
* Joint angles next to the gimbal lock along a simulated motion still rebuild the rotations.
* The paper's torso (E1 < 0, M indefinite): the reduced mass matrix P^T M P is positive
  definite and equals the rigid-body mass matrix (sum m v.v + w.J w) at random q.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.dynamics.free_motion import energies, momenta, random_velocity, run_free_motion
from gait_planner.dynamics.forward import SimulationError, Simulator
from gait_planner.model.angles import configuration, joint_angles, spherical_rotation
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import InitialPose


def without_gravity(m):
    scene = dataclasses.replace(m.scene, gravity=0.0)
    mb = Multibody(scene)
    return scene, mb, DiscreteMechanics(mb)


def rate_index(mb, joint, component=0):
    return mb.root_dof + mb.joint_slices[joint].start + component


def assert_regular(mb, sim, traj, mech=None):
    assert traj.newton_iterations.max() <= 5
    g = np.array(mb.constraints.map(traj.q.shape[0])(traj.q.T))
    assert np.abs(g).max() <= 1e-12
    if mech is not None:  # free and without gravity: momentum conserved
        L, J = momenta(mech, traj)
        assert np.abs(L - L[0]).max() <= 1e-10 * max(1.0, np.abs(traj.p).max())
        assert np.abs(J - J[0]).max() <= 1e-10 * max(1.0, np.abs(traj.p).max())


# ---- stretched knee ------------------------------------------------------------------


def test_stretched_knee_and_motion_through_it(model):
    scene, mb, mech = without_gravity(model("walker3d"))
    pose = InitialPose(scene.initial_pose.root_position, joint_angles={"knee_l": (0.03,)})
    q0 = configuration(scene, pose)
    assert joint_angles(scene, q0)[mb.joint_slices["knee_r"]] == 0.0  # exactly stretched
    nu0 = np.zeros(mb.ndof)
    nu0[rate_index(mb, "knee_r")] = 1.5  # bends from exactly 0
    nu0[rate_index(mb, "knee_l")] = -1.5  # passes through 0 at t ~ 0.02 s
    sim = Simulator(mech)
    traj = sim.run(q0, nu0, np.full(100, 0.002))
    knees = joint_angles(scene, traj.q)[:, [mb.joint_slices["knee_r"].start,
                                            mb.joint_slices["knee_l"].start]]
    assert knees[0, 0] == 0.0 and knees[-1, 0] > 0.2
    assert knees[0, 1] > 0 and knees[-1, 1] < -0.2
    assert_regular(mb, sim, traj, mech)


def test_stretched_knees_in_double_support(model):
    """walker2d standing on its right forefoot and left heel (a closed loop through both
    straight legs) sags under gravity from the stretched pose: knees pass through 0."""
    m = model("walker2d")
    contacts = ("foot_r_forefoot", "foot_l_heel")
    sim = Simulator(m.mech, contacts=contacts)
    q0 = configuration(m.scene)
    C = np.vstack([m.mb.contact_rows(c) for c in contacts])
    CP = C @ np.array(m.mb.null_space(q0))
    free = np.linalg.svd(CP)[2][CP.shape[0]:].T  # rates that keep both points at rest
    nu0 = np.zeros(m.mb.ndof)
    nu0[2] = 0.3  # torso pitch rate
    nu0 = free @ (free.T @ nu0)
    traj = sim.run(q0, nu0, np.full(100, 0.005))
    knees = joint_angles(m.scene, traj.q)[:, [1, 4]]
    assert np.all(knees[0] == 0.0)
    assert np.any(np.diff(np.sign(knees[1:, 0])) != 0)  # the right knee crosses 0
    assert_regular(m.mb, sim, traj)
    assert np.abs(traj.q @ C.T - C @ q0).max() <= 1e-12  # contacts held


# ---- large steps -----------------------------------------------------------------------


def test_passive_chaos_at_dt_005_raises_clear_error(model):
    """The case that motivated the investigation: free-floating walker3d with gravity and
    seed-0 random rates. Its light right foot spins up to > 20 rad/s (~1/h) near t = 7.7 s;
    no increment solves step 155."""
    with pytest.raises(SimulationError) as info:
        run_free_motion(model("walker3d").scene, steps=200, dt=0.05, gravity=True, seed=0)
    message = str(info.value)
    assert message.startswith("step 155 (t = 7.75 s)")
    assert "foot_r turned by" in message and "reduce the time step" in message
    assert "\n" not in message


@pytest.mark.parametrize("joint_rate, dt, solvable", [
    (15.0, 0.05, True),  # omega h = 0.75
    (25.0, 0.05, False),  # omega h = 1.25: beyond the fold
    (25.0, 0.02, True),  # the same motion with a smaller step
])
def test_single_foot_spin_solvability(model, joint_rate, dt, solvable):
    scene, mb, mech = without_gravity(model("walker3d"))
    q0 = configuration(scene)
    nu0 = np.zeros(mb.ndof)
    nu0[rate_index(mb, "ankle_r", 0)] = joint_rate  # foot pitch about the ankle
    sim = Simulator(mech)
    steps = np.full(int(round(2.0 / dt)), dt)
    if solvable:
        traj = sim.run(q0, nu0, steps)
        assert_regular(mb, sim, traj, mech)
    else:
        with pytest.raises(SimulationError, match=r"^step \d+ \(t = "):
            sim.run(q0, nu0, steps)


def test_moderate_motion_many_steps_at_dt_005(model):
    """Slower random rates (0.3 x): 2000 steps (100 s) at dt = 0.05 run, the momentum is
    conserved and the energy error stays at the few-percent level of so coarse a step
    (it follows how fast the feet spin at the moment; drift is tested in
    test_conservation)."""
    scene, mb, mech = without_gravity(model("walker3d"))
    q0 = configuration(scene)
    nu0 = 0.3 * random_velocity(mb, q0, np.random.default_rng(0))
    sim = Simulator(mech)
    traj = sim.run(q0, nu0, np.full(2000, 0.05))
    assert_regular(mb, sim, traj, mech)
    T, E = energies(mech, traj)
    err = np.abs(E - E[0]) / T.max()
    assert err.max() < 0.05


# ---- angle chart singularity along a motion --------------------------------------------


def test_simulated_motion_through_hip_gimbal_lock(model):
    scene, mb, mech = without_gravity(model("walker3d"))
    pose = InitialPose(scene.initial_pose.root_position,
                       joint_angles={"hip_r": (0.2, np.pi / 2 - 1e-9, -0.4)})
    q0 = configuration(scene, pose)
    nu0 = np.zeros(mb.ndof)
    nu0[rate_index(mb, "hip_r", 1)] = 0.5  # roll rate: through 90 deg
    nu0[rate_index(mb, "hip_r", 2)] = 0.3
    sim = Simulator(mech)
    traj = sim.run(q0, nu0, np.full(50, 0.002))
    assert_regular(mb, sim, traj, mech)
    s = mb.joint_slices["hip_r"]
    for q in traj.q[::5]:
        D_torso = q[mb.block("torso")][3:].reshape(3, 3).T
        D_thigh = q[mb.block("thigh_r")][3:].reshape(3, 3).T
        rebuilt = spherical_rotation(*joint_angles(scene, q)[s])
        assert np.abs(rebuilt - D_torso.T @ D_thigh).max() <= 1e-14


# ---- the paper's torso inertia -----------------------------------------------------------


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_reduced_mass_matrix_positive_definite_with_paper_torso(model, seed):
    m = model("walker3d")
    mb = m.mb
    torso = mb.block("torso")
    assert mb.mass_diagonal[torso].min() < 0  # E1 = -0.0767: M is indefinite
    rng = np.random.default_rng(seed)
    q = np.array(mb.reparametrise(rng.uniform(-3, 3, mb.ndof), configuration(m.scene))).ravel()
    P = np.array(mb.null_space(q))
    reduced = P.T @ (mb.mass_diagonal[:, None] * P)
    assert np.linalg.eigvalsh(reduced).min() > 1e-4
    # equals the rigid-body kinetic energy of the twists: v = phi_dot, w = 1/2 sum d_i x d_i'
    nu = rng.normal(0, 1, mb.ndof)
    qdot = (P @ nu).reshape(mb.nb, 4, 3)
    qb = q.reshape(mb.nb, 4, 3)
    twice_T = 0.0
    for i, body in enumerate(m.scene.bodies):
        w = 0.5 * np.cross(qb[i, 1:], qdot[i, 1:]).sum(axis=0)
        D = qb[i, 1:].T
        twice_T += body.mass * qdot[i, 0] @ qdot[i, 0] + w @ (D @ np.diag(body.inertia) @ D.T) @ w
    assert nu @ reduced @ nu == pytest.approx(twice_T, rel=1e-12)
