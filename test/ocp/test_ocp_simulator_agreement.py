"""The transcription's dynamics constraints are the forward simulator's equations: a stance
motion of the compass simulated with the foot held satisfies them to round-off."""

from __future__ import annotations

import casadi as ca
import numpy as np

from gait_planner.dynamics.forward import Simulator
from gait_planner.model.angles import configuration
from gait_planner.model.scene import InitialPose
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.transcription import FORCE_SCALE, TORQUE_SCALE, Transcription


def test_simulated_stance_satisfies_the_transcription(model):
    scene, mb, mech = model("compass")
    settings = settings_for(scene)
    tr = Transcription(mech, settings)
    N = tr.N
    assert tr.phase_of_interval[0] == 0 and scene.gait.phases[0].contacts == ("foot_r",)
    stance = [n for n in range(N) if tr.phase_of_interval[n] == 0]  # intervals 0..19
    # nodes 0..N-2 are free (u = 0: q_n = qref_n); q_{N-1}, q_N are mirrored expressions,
    # so the equations of nodes N-2, N-1 and the hold of interval N-2 are excluded
    n_sim = N - 2  # steps: q_0 .. q_{N-2}
    assert max(stance) >= n_sim

    # stance leg leaning back by 0.2 rad and rotating forward over its fixed foot
    pitch, omega = -0.2, 1.2
    com = 0.5 * np.array([np.sin(pitch), 0.0, np.cos(pitch)])  # foot at the origin
    q0 = configuration(scene, InitialPose(root_position=tuple(com), root_angles=(0.0, pitch, 0.0),
                                          joint_angles={"hip": (0.5,)}))
    foot = mb.contact_rows("foot_r") @ q0
    np.testing.assert_allclose(foot, [0.0, 0.0], atol=1e-15)
    v = np.cross([0.0, omega, 0.0], com)
    nu0 = np.array([v[0], v[2], omega, -2.0])  # planar root (v_x, v_z, omega_y), hip rate
    h = settings.base_time_step  # sigma = 1
    sim = Simulator(mech, contacts=("foot_r",))
    traj = sim.run(q0, nu0, [h] * n_sim, torques=lambda t: np.array([8.0 * np.sin(6.0 * t)]))

    # x = (u, tau, lambda, sigma) and p = (qref, step, mu) of the transcription
    U = np.zeros((mb.ndof, N - 1))
    T = np.zeros((mb.nt, N - 1))
    # the simulator applies the paper's interval torques, (tau_{n-1} + tau_n)/2 at node n
    # (uniform steps); the transcription applies node torques
    T[:, 1:n_sim] = 0.5 * (traj.tau[: n_sim - 1] + traj.tau[1:n_sim]).T / TORQUE_SCALE
    lam = []
    for n, size in zip(tr.lam_nodes, tr.lam_sizes):
        lam.append(traj.multipliers[n] / FORCE_SCALE if n < n_sim else np.zeros(size))
        if n < n_sim:
            assert size == sim.nc
    qref = traj.q[: N - 1].T  # (k, N-1): nodes 0..N-2
    x = np.concatenate([U.ravel(order="F"), T.ravel(order="F"), np.concatenate(lam),
                        np.ones(tr.S.shape[0])])
    p = tr.parameters(qref.T, settings)
    g = np.array(ca.Function("g", [tr.x, tr.p], [tr.g])(x, p)).ravel()

    groups, offset = {}, 0
    for name, size, _ in tr.constraint_groups():
        groups.setdefault(name, []).append(g[offset:offset + size])
        offset += size
    dynamics = groups["dynamics[stance_r]"][0].reshape(-1, mb.ndof)  # nodes 1..19, per node
    checked = dynamics[: n_sim - 1]  # nodes 1..N-3
    # the equations read as forces in units of FORCE_SCALE, of the order of the contact
    # force
    assert np.abs(traj.multipliers[1:n_sim, 1]).min() > 10.0
    print("largest dynamics residual (N):", FORCE_SCALE * np.abs(checked).max())
    assert FORCE_SCALE * np.abs(checked).max() <= 1e-9
    # the hold of the stance foot over the simulated intervals 0..N-3
    hold = groups["contact_hold"][0].reshape(-1, 2)[: n_sim]
    assert np.abs(hold).max() <= 1e-12
    # and it is not a test that cannot fail: a node torque off by 1 % breaks its node
    T_bad = T.copy()
    T_bad[:, 5] *= 1.01
    x_bad = np.concatenate([U.ravel(order="F"), T_bad.ravel(order="F"), np.concatenate(lam),
                            np.ones(tr.S.shape[0])])
    g_bad = np.array(ca.Function("g", [tr.x, tr.p], [tr.g])(x_bad, p)).ravel()
    bad = g_bad[: dynamics.size].reshape(-1, mb.ndof)
    broken = np.flatnonzero(FORCE_SCALE * np.abs(bad - dynamics).max(axis=1) > 1e-6) + 1
    assert list(broken) == [5]
