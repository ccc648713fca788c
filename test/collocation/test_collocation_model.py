"""The minimal-coordinate model of `benchmarks.collocation.minimal`.

* q(theta) is the product's configuration from angles (`model.angles.configuration`) for
  random root poses and joint angles (|middle angle| < 80 deg), satisfies every constraint,
  and `coordinates` (root_angles, joint_angles) inverts it;
* the mirror map on theta is the product's mirror on q (`ocp.mirror`, paper eqs. 7-9);
* the equations of motion agree with Pinocchio's inverse dynamics (`verify.continuous`
  builds the model) at random states, torques included (the product's convention: a
  spherical joint's couple in parent director components, +m on the child);
* the plastic impact map leaves every contact at rest and loses exactly the kinetic energy
  of the velocity jump (Carnot's theorem), the impulse doing no work on the new velocity.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks.collocation.minimal import MinimalModel
from gait_planner.model.angles import configuration, joint_angles
from gait_planner.model.scene import InitialPose, JointType
from gait_planner.ocp.contacts import body_contacts, stacked_rows
from gait_planner.ocp.mirror import configuration_mirror
from gait_planner.verify.continuous import build_model, pin_configuration
from gait_planner.verify.mechanics import parse_scene

SCENES = ("compass", "walker2d", "walker3d")
ANY = st.floats(-3.1, 3.1)
MIDDLE = st.floats(-np.radians(80), np.radians(80))


@st.composite
def thetas(draw, mm: MinimalModel):
    """Random theta with |middle Cardan angle| < 80 deg, and its InitialPose."""
    scene, mb = mm.scene, mm.mb
    position = tuple(draw(st.floats(-2, 2)) for _ in range(3))
    if scene.planar:
        root = [position[0], position[2], draw(MIDDLE)]
        pose_root = (position[0], scene.initial_pose.root_position[1], position[2])
        pose_angles = (0.0, root[2], 0.0)
    else:
        pose_angles = (draw(ANY), draw(MIDDLE), draw(ANY))
        root, pose_root = [*position, *pose_angles], position
    angles, joints = [], {}
    for j in scene.joints:
        values = (draw(ANY), draw(MIDDLE), draw(ANY)) if j.type is JointType.SPHERICAL \
            else (draw(ANY),)
        joints[j.name] = values
        angles += values
    assert len(root) + len(angles) == mb.ndof
    return np.array(root + angles), InitialPose(pose_root, pose_angles, joints)


@pytest.mark.parametrize("name", SCENES)
def test_configuration_is_the_products(minimal, name):
    mm = minimal(name)

    @settings(max_examples=40, deadline=None)
    @given(thetas(mm))
    def check(sample):
        theta, pose = sample
        q = np.array(mm.configuration(theta)).ravel()
        assert np.abs(q - configuration(mm.scene, pose)).max() < 1e-12
        assert np.abs(np.array(mm.mb.constraints(q))).max() < 1e-12
        joints = theta[mm.mb.root_dof:]
        wrapped = np.angle(np.exp(1j * (joint_angles(mm.scene, q) - joints)))
        assert np.abs(wrapped).max() < 1e-9
        back = mm.coordinates(q)
        assert np.abs(np.angle(np.exp(1j * (back - theta)))).max() < 1e-9  # angles mod 2 pi
        assert np.abs(np.array(mm.configuration(back)).ravel() - q).max() < 1e-12

    check()


@pytest.mark.parametrize("name", SCENES)
def test_mirror_is_the_products(minimal, name):
    mm = minimal(name)
    A, shift, _ = configuration_mirror(mm.mb)
    rng = np.random.default_rng(3)
    for _ in range(5):
        theta, w, step = rng.uniform(-0.6, 0.6, mm.n), rng.normal(size=mm.n), rng.uniform(0.2, 1)
        q = np.array(mm.configuration(theta)).ravel()
        image = np.array(mm.mirror(theta, step)).ravel()
        assert np.abs(np.array(mm.configuration(image)).ravel() - (A @ q + step * shift)).max() \
            < 1e-12
        # velocities: q(mirror(theta)) moves as A qdot
        w_image = np.array(mm.mirror_velocity(theta, w)).ravel()
        qdot = np.array(mm.velocity(theta, w)).ravel()
        assert np.abs(np.array(mm.velocity(image, w_image)).ravel() - A @ qdot).max() < 1e-12


def _pinocchio_state(mm, sd, model, theta, w, a, eps=1e-4):
    """Pinocchio (q, v, a) of the motion theta + w t + a t^2 / 2 at t = 0 by central
    differences on the configuration group, and the Jacobian dv/dw (nv, n)."""
    def config(t):
        th = theta + w * t + 0.5 * a * t * t if np.ndim(t) == 0 else theta + t
        return pin_configuration(sd, model, np.array(mm.configuration(th)).ravel())

    c0 = config(0.0)
    forward = pin.difference(model, c0, config(eps)) / eps
    backward = -pin.difference(model, c0, config(-eps)) / eps
    v = pin.difference(model, config(-eps), config(eps)) / (2 * eps)
    jac = np.array([pin.difference(model, config(-eps * e), config(eps * e)) / (2 * eps)
                    for e in np.eye(mm.n)]).T
    return c0, v, (forward - backward) / eps, jac


@pytest.mark.parametrize("name", SCENES)
def test_dynamics_agree_with_pinocchio(minimal, name):
    """J_p^T (RNEA(q, v, a) - tau_pin) = the model's residual, with tau_pin the product's
    torques as Pinocchio joint torques (spherical: D_child^T D_parent tau, child frame)."""
    mm = minimal(name)
    sd = parse_scene(mm.scene.source)
    model, _ = build_model(sd)
    data = model.createData()
    rng = np.random.default_rng(7)
    for _ in range(3):
        theta, w, a = rng.uniform(-0.4, 0.4, mm.n), rng.normal(size=mm.n), rng.normal(size=mm.n)
        tau = 50 * rng.normal(size=mm.mb.nt)
        c0, v, acc, jac = _pinocchio_state(mm, sd, model, theta, w, a)
        q = np.array(mm.configuration(theta)).ravel()
        tau_pin = np.zeros(model.nv)
        for j in mm.scene.joints:
            s, slot = mm.mb.joint_slices[j.name], model.joints[model.getJointId(j.name)].idx_v
            t = tau[s]
            if j.type is JointType.SPHERICAL:
                D = {b: q[mm.mb.block(b).start + 3 : mm.mb.block(b).start + 12].reshape(3, 3).T
                     for b in (j.parent, j.child)}
                t = D[j.child].T @ D[j.parent] @ t
            tau_pin[slot : slot + len(t)] = t
        expected = jac.T @ (pin.rnea(model, data, c0, v, acc) - tau_pin)
        mine = np.array(mm.dynamics(theta, w, a, tau, np.zeros(mm.k))).ravel()
        assert np.abs(mine - expected).max() < 1e-6 * max(1.0, np.abs(mine).max())


@pytest.mark.parametrize("name, contacts", [
    ("walker3d", ("foot_l_heel",)), ("walker3d", ("foot_r_forefoot", "foot_l_heel")),
    ("walker2d", ("foot_l_heel", "foot_l_forefoot")), ("compass", ("foot_l",))])
def test_plastic_impact(minimal, name, contacts):
    mm = minimal(name)
    C = stacked_rows(body_contacts(mm.mb, contacts), mm.k)
    rng = np.random.default_rng(11)
    theta, w_minus = rng.uniform(-0.3, 0.3, mm.n), rng.normal(size=mm.n)
    M = np.array(mm.mass_matrix(theta))
    assert np.linalg.eigvalsh(M).min() > 0  # reduced mass matrix positive definite
    Jc = np.array([C @ np.array(mm.velocity(theta, e)).ravel() for e in np.eye(mm.n)]).T
    r = C.shape[0]
    kkt = np.block([[M, -Jc.T], [Jc, np.zeros((r, r))]])
    solution = np.linalg.solve(kkt, np.concatenate([M @ w_minus, np.zeros(r)]))
    w_plus, impulse = solution[: mm.n], solution[mm.n :]
    residual = np.array(mm.impact(theta, w_minus, w_plus, C.T @ impulse)).ravel()
    assert np.abs(residual).max() < 1e-10 * np.abs(M @ w_minus).max()
    assert np.abs(C @ np.array(mm.velocity(theta, w_plus)).ravel()).max() < 1e-12
    T_minus, T_plus = (float(mm.kinetic_energy(theta, w)) for w in (w_minus, w_plus))
    jump = w_plus - w_minus
    assert T_plus < T_minus
    assert T_minus - T_plus == pytest.approx(0.5 * jump @ M @ jump, rel=1e-10)
    assert abs(impulse @ Jc @ w_plus) < 1e-10 * T_minus
