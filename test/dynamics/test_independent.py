"""The director simulation against an independent computation of the same motion.

The compass (two 1 m legs joined by a revolute hip, planar) is written here from scratch in
minimal coordinates: absolute leg pitch angles theta about world y (d3 = (sin, 0, cos)) and,
in free flight, the right leg's centre of mass (x, z). The Lagrangian is built by hand from
the centre-of-mass positions (translational energy) and J2 theta_dot^2 / 2 (rotation about
y); CasADi only differentiates it (mass matrix, Coriolis and gravity terms), so nothing is
shared with the director code. scipy's DOP853 (rtol 1e-12) integrates it from the same
initial state: positions from q_0, rates converted from the director velocity P(q_0) nu_0.
The director trajectory at h and h/2 must agree with it to O(h^2) (error ratio ~4).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gait_planner.dynamics.free_motion import pinned_velocity, random_velocity
from gait_planner.dynamics.forward import Simulator
from gait_planner.model.angles import configuration

HORIZON = 0.3  # s
MASS, LENGTH, J_PITCH, GRAVITY = 5.0, 1.0, 0.4167, 9.81  # config/scenes/compass.yaml


def compass_ode(pinned_at):
    """(rhs(t, y), coms(s)) of the compass in minimal coordinates s; y = (s, s_dot).

    Free flight: s = (x, z, theta_r, theta_l); pinned at the right foot: s = (theta_r,
    theta_l) with the right foot fixed at `pinned_at` (x, z)."""
    n = 4 if pinned_at is None else 2
    s, sd = ca.SX.sym("s", n), ca.SX.sym("sd", n)
    th_r, th_l = s[n - 2], s[n - 1]

    def axis(th):  # the leg's d3 in the x-z plane
        return ca.vertcat(ca.sin(th), ca.cos(th))

    half = LENGTH / 2
    com_r = ca.vertcat(s[0], s[1]) if pinned_at is None else ca.DM(pinned_at) + half * axis(th_r)
    hip = com_r + half * axis(th_r)
    com_l = hip - half * axis(th_l)
    v_r, v_l = ca.jtimes(com_r, s, sd), ca.jtimes(com_l, s, sd)
    T = 0.5 * MASS * (ca.dot(v_r, v_r) + ca.dot(v_l, v_l)) \
        + 0.5 * J_PITCH * (sd[n - 2] ** 2 + sd[n - 1] ** 2)
    V = MASS * GRAVITY * (com_r[1] + com_l[1])
    M = ca.hessian(T, sd)[0]
    dT_dsd = ca.gradient(T, sd)
    rhs = ca.gradient(T, s) - ca.mtimes(ca.jacobian(dT_dsd, s), sd) - ca.gradient(V, s)
    accel = ca.Function("accel", [s, sd], [ca.solve(M, rhs)])
    coms = ca.Function("coms", [s], [ca.vertcat(com_r, com_l)])

    def f(t, y):
        return np.concatenate([y[n:], np.array(accel(y[:n], y[n:])).ravel()])

    return f, lambda s_: np.array(coms(s_)).ravel()


def minimal_from_directors(mb, q, qdot=None, pinned=False):
    """(x, z, theta_r, theta_l) (or the angles only) and their rates from director data."""
    out, rates = [], []
    r, lft = mb.block("leg_r").start, mb.block("leg_l").start
    if not pinned:
        out += [q[r], q[r + 2]]
        if qdot is not None:
            rates += [qdot[r], qdot[r + 2]]
    for s in (r, lft):
        d3 = q[s + 9 : s + 12]
        th = np.arctan2(d3[0], d3[2])
        out.append(th)
        if qdot is not None:  # d3_dot = theta_dot (cos, 0, -sin)
            rates.append(qdot[s + 9 : s + 12] @ [np.cos(th), 0.0, -np.sin(th)])
    return np.array(out), np.array(rates)


def director_coms(mb, q):
    r, lft = mb.block("leg_r").start, mb.block("leg_l").start
    return np.column_stack([q[:, r], q[:, r + 2], q[:, lft], q[:, lft + 2]])


@pytest.mark.parametrize("pin", [None, "foot_r"])
def test_compass_agrees_with_minimal_coordinates(model, pin):
    m = model("compass")
    assert m.scene.body("leg_r").mass == MASS and m.scene.body("leg_r").inertia[1] == J_PITCH
    q0 = configuration(m.scene)
    rng = np.random.default_rng(11)
    nu0 = 3.0 * random_velocity(m.mb, q0, rng)
    foot = None
    if pin:
        nu0 = pinned_velocity(m.mb, q0, nu0, pin)
        foot = m.mb.contact_rows(pin) @ q0
    qdot0 = np.array(m.mb.null_space(q0)) @ nu0
    s0, sd0 = minimal_from_directors(m.mb, q0, qdot0, pinned=pin is not None)
    rhs, coms = compass_ode(foot)

    errors = []
    sim = Simulator(m.mech, contacts=(pin,) if pin else ())
    for h in (0.01, 0.005):
        traj = sim.run(q0, nu0, np.full(int(round(HORIZON / h)), h))
        exact = solve_ivp(rhs, (0.0, traj.times[-1]), np.concatenate([s0, sd0]), method="DOP853",
                          rtol=1e-12, atol=1e-12, t_eval=traj.times)
        assert exact.success
        n = s0.size
        exact_coms = np.array([coms(s) for s in exact.y[:n].T])
        angles = np.array([minimal_from_directors(m.mb, q, pinned=pin is not None)[0][-2:]
                           for q in traj.q])
        errors.append(max(np.abs(director_coms(m.mb, traj.q) - exact_coms).max(),
                          np.abs(angles - exact.y[n - 2 : n].T).max()))
    assert errors[0] < 1e-3  # m and rad (measured: 2.4e-4 free, 1.9e-4 pinned)
    print(f"errors at h, h/2: {errors}, ratio {errors[0] / errors[1]:.3f}")
    assert 3.6 < errors[0] / errors[1] < 4.4, errors
