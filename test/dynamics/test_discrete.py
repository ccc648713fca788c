"""The variational integrator's Functions against the closed forms of docs/design.md section 3,
and simulated trajectories against the full (redundant, 12 nb-dimensional) equations.

* L_d, D1 L_d = -M v - h/2 grad V(q0), D2 L_d = +M v - h/2 grad V(q1) at random q0, q1, h,
  with grad V written here from the masses (m g on each phi_z);
* the discrete Euler-Lagrange residual is D2 L_d + D1 L_d + f+ + f-;
* a simulated trajectory (null space method: only P^T r = 0 is solved) satisfies the full
  equations r_n + w_n G_C^T lambda_C = w_n G^T lambda (lambda_C: the ground forces the
  simulator returns): r_n plus the contact forces lies in the range of G^T to round-off;
* a pinned compass at rest carries its weight on the pin (multiplier = ground force).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.dynamics.free_motion import random_torques, random_velocity
from gait_planner.dynamics.forward import SimulationError, Simulator
from gait_planner.model.angles import configuration

SCENES = ("compass", "walker2d", "walker3d")


def random_configuration(mb, rng):
    return np.array(mb.reparametrise(rng.uniform(-3, 3, mb.ndof), configuration(mb.scene))).ravel()


def gravity_gradient(scene) -> np.ndarray:
    grad = np.zeros(12 * len(scene.bodies))
    for i, body in enumerate(scene.bodies):
        grad[12 * i + 2] = body.mass * scene.gravity
    return grad


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), h=st.floats(1e-4, 0.1))
def test_discrete_lagrangian_closed_forms(model, scene, seed, h):
    mb, mech = model(scene).mb, model(scene).mech
    rng = np.random.default_rng(seed)
    q0 = random_configuration(mb, rng)
    q1 = np.array(mb.reparametrise(rng.uniform(-0.3, 0.3, mb.ndof), q0)).ravel()
    M = mb.mass_diagonal
    grad_v = gravity_gradient(mb.scene)
    v = (q1 - q0) / h
    scale = np.abs(M * v).max() + h * np.abs(grad_v).max()

    Ld = float(mech.discrete_lagrangian(q0, q1, h))
    expected = 0.5 * h * v @ (M * v) - 0.5 * h * (grad_v @ q0 + grad_v @ q1)
    assert Ld == pytest.approx(expected, rel=1e-12, abs=1e-12 * scale)
    D1 = np.array(mech.discrete_lagrangian_d1(q0, q1, h)).ravel()
    D2 = np.array(mech.discrete_lagrangian_d2(q0, q1, h)).ravel()
    assert np.abs(D1 - (-M * v - 0.5 * h * grad_v)).max() <= 1e-12 * scale
    assert np.abs(D2 - (M * v - 0.5 * h * grad_v)).max() <= 1e-12 * scale
    np.testing.assert_array_equal(mech.gravity_gradient, grad_v)


@pytest.mark.parametrize("scene", SCENES)
@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_discrete_euler_lagrange_residual_composition(model, scene, seed):
    mb, mech = model(scene).mb, model(scene).mech
    rng = np.random.default_rng(seed)
    q0 = random_configuration(mb, rng)
    q1 = np.array(mb.reparametrise(rng.uniform(-0.3, 0.3, mb.ndof), q0)).ravel()
    q2 = np.array(mb.reparametrise(rng.uniform(-0.3, 0.3, mb.ndof), q1)).ravel()
    h0, h1 = rng.uniform(0.001, 0.05, 2)
    t0, t1 = rng.normal(0, 50, (2, mb.nt))
    r = np.array(mech.discrete_euler_lagrange(q0, q1, q2, h0, h1, t0, t1)).ravel()
    Bt = np.array(mb.actuation(q1))
    expected = (np.array(mech.discrete_lagrangian_d2(q0, q1, h0)).ravel()
                + np.array(mech.discrete_lagrangian_d1(q1, q2, h1)).ravel()
                + 0.5 * h0 * Bt @ t0 + 0.5 * h1 * Bt @ t1)
    assert np.abs(r - expected).max() <= 1e-12 * np.abs(expected).max()
    Ptr = np.array(mech.reduced_discrete_euler_lagrange(q0, q1, q2, h0, h1, t0, t1)).ravel()
    assert np.abs(Ptr - np.array(mb.null_space(q1)).T @ r).max() <= 1e-12 * np.abs(r).max()


def full_residual_defect(model_, traj, contacts=()):
    """max_n |r_n + w G_C^T lambda_C - G^T lambda| / |M v| with the best lambda."""
    mb, mech = model_.mb, model_.mech
    C = np.vstack([mb.contact_rows(c) for c in contacts]) if contacts else np.zeros((0, mb.k))
    h = np.diff(traj.times)
    worst = 0.0
    for n in range(1, len(h)):
        q0, q1, q2 = traj.q[n - 1 : n + 2]
        r = np.array(mech.discrete_euler_lagrange(
            q0, q1, q2, h[n - 1], h[n], traj.tau[n - 1], traj.tau[n])).ravel()
        w = 0.5 * (h[n - 1] + h[n])
        r = r + w * C.T @ traj.multipliers[n]  # lambda: the ground force on the body
        Gt = np.array(mb.constraint_jacobian(q1)).T
        lam = np.linalg.lstsq(Gt, r, rcond=None)[0]
        scale = np.abs(mb.mass_diagonal * (q2 - q1) / h[n]).max()
        worst = max(worst, np.abs(r - Gt @ lam).max() / scale)
    return worst


def test_trajectory_solves_full_redundant_equations(model):
    m = model("walker3d")
    rng = np.random.default_rng(3)
    q0 = configuration(m.scene)
    sim = Simulator(m.mech)
    traj = sim.run(q0, random_velocity(m.mb, q0, rng), np.full(40, 0.01),
                   random_torques(m.mb, rng))
    assert full_residual_defect(m, traj) <= 1e-10


def test_pinned_trajectory_solves_full_equations_with_contact_forces(model):
    m = model("walker2d")
    rng = np.random.default_rng(4)
    q0 = configuration(m.scene)
    contacts = ("foot_r_forefoot", "foot_l_heel")  # double support: a closed loop
    sim = Simulator(m.mech, contacts=contacts)
    nu0 = np.zeros(m.mb.ndof)
    traj = sim.run(q0, nu0, np.full(40, 0.005), random_torques(m.mb, rng))
    assert full_residual_defect(m, traj, contacts) <= 1e-10
    held = np.vstack([m.mb.contact_rows(c) for c in contacts])
    assert np.abs(traj.q @ held.T - held @ q0).max() <= 1e-12


def test_redundant_contacts_are_refused(model):
    m = model("walker2d")
    sim = Simulator(m.mech, contacts=("foot_r_heel", "foot_r_forefoot"))
    with pytest.raises(SimulationError, match="only 3 are independent"):
        sim.run(configuration(m.scene), np.zeros(m.mb.ndof), [0.01])


def test_pin_carries_the_weight_at_rest(model):
    """The upright compass held at foot_r and at rest stays at rest (an equilibrium), and
    the multiplier is the ground force on the foot: (0, m g) in (x, z)."""
    m = model("compass")
    sim = Simulator(m.mech, contacts=("foot_r",))
    q0 = configuration(m.scene)
    traj = sim.run(q0, np.zeros(m.mb.ndof), np.full(5, 0.01))
    weight = sum(b.mass for b in m.scene.bodies) * m.scene.gravity
    np.testing.assert_allclose(traj.multipliers, np.tile([0.0, weight], (5, 1)),
                               rtol=0, atol=1e-9 * weight)
    assert np.abs(traj.q - q0).max() <= 1e-13
