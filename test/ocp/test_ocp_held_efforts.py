"""The efforts that hold a drafted robot's locked joints (`gait_planner.ocp.held_efforts`),
against Pinocchio's inverse dynamics on the URDF itself (issue #61); what cannot hold is
refused, impacts' impulses are published apart and the verifier judges every published
effort against the URDF's limit.

A synthetic biped (test/urdf_bipeds.py) whose locked waist carries an arm off its axis:
its base moves along a smooth path (a translation and a turn about a skew axis), and the
held effort of the discrete formula at node t (configurations at t - h, t, t + h) is set
beside RNEA's generalized force of the waist with the base's exact velocity and
acceleration: second order in h, and at rest the static effort to round-off.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gait_planner.cli.robot import write_draft
from gait_planner.model.angles import configuration
from gait_planner.model.loader import find_scene, scene_from_text
from gait_planner.model.multibody import Multibody
from gait_planner.model.urdf_import import draft_scene
from gait_planner.ocp.held_efforts import held_efforts, holds_of, static_held_efforts
from gait_planner.problem import resolve
from gait_planner.request import PlanRequest, RequestError
from gait_planner.verify.effort_limits import effort_limit_failures, effort_shares
from gait_planner.verify.robot import split_impulses
from urdf_bipeds import biped

AXIS = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])  # the base's turn


def _robot(waist_axis: str):
    urdf = biped(waist_axis=waist_axis, arm_com="0.05 0.03 0.2", waist_effort=30.0)
    scene = scene_from_text(draft_scene(urdf).yaml, "biped.yaml")
    return urdf, scene, pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())


def _base(t: float):
    """(p, R, v, w, a, dw): the base link's world pose, velocity and acceleration at t."""
    theta, dtheta, ddtheta = 0.4 * np.sin(3 * t), 1.2 * np.cos(3 * t), -3.6 * np.sin(3 * t)
    R0 = pin.rpy.rpyToMatrix(0.1, -0.2, 0.3)
    R = pin.exp3(theta * AXIS) @ R0
    p = np.array([0.5 * t + 0.05 * np.sin(5 * t), 0.03 * np.cos(4 * t), 0.8 + 0.02 * t * t])
    v = np.array([0.5 + 0.25 * np.cos(5 * t), -0.12 * np.sin(4 * t), 0.04 * t])
    a = np.array([-1.25 * np.sin(5 * t), -0.48 * np.cos(4 * t), 0.04])
    return p, R, v, dtheta * AXIS, a, ddtheta * AXIS


def _director_row(scene, t: float) -> np.ndarray:
    """The draft's configuration (k,) with the base at `_base(t)` and every leg at zero."""
    q0, q = configuration(scene), configuration(scene).copy()
    p, R, *_ = _base(t)
    X, R_link = scene.robot.link_pose(scene.root.body)
    D = R @ R_link.T  # the link frame is D R_link, at phi + D X
    i = 12 * scene.body_index(scene.root.body)
    legs = Multibody(scene)
    # legs follow the base rigidly: every body's frame relative to the base's is kept
    D0 = q0[i + 3:i + 12].reshape(3, 3).T
    for b in range(len(scene.bodies)):
        Db = q0[12 * b + 3:12 * b + 12].reshape(3, 3).T
        phi = q0[12 * b:12 * b + 3] - q0[i:i + 3]
        q[12 * b:12 * b + 3] = p - D @ X + D @ D0.T @ phi
        q[12 * b + 3:12 * b + 12] = (D @ D0.T @ Db).T.ravel()
    assert np.abs(np.asarray(legs.constraints(q))).max() < 1e-12
    return q


def _rnea(model, t: float) -> float:
    p, R, v, w, a, dw = _base(t)
    q = pin.neutral(model)
    q[:3], q[3:7] = p, pin.Quaternion(R).coeffs()
    nu, dnu = np.zeros(model.nv), np.zeros(model.nv)
    nu[:3], nu[3:6] = R.T @ v, R.T @ w  # the free flyer's velocity: in the base frame
    wl = R.T @ w
    dnu[:3], dnu[3:6] = R.T @ a - np.cross(wl, R.T @ v), R.T @ dw
    tau = pin.rnea(model, model.createData(), q, nu, dnu)
    return float(tau[model.joints[model.getJointId("waist_joint")].idx_v])


@pytest.mark.parametrize("waist_axis", ["x", "y", "z"])
def test_the_held_effort_is_pinocchios_to_second_order(waist_axis):
    urdf, scene, model = _robot(waist_axis)
    mb = Multibody(scene)
    fn = held_efforts(mb, holds_of(scene))
    errors = []
    for h in (4e-3, 2e-3, 1e-3):
        worst = 0.0
        for t in np.linspace(0.1, 1.9, 7):
            rows = [_director_row(scene, t + d) for d in (-h, 0.0, h)]
            mine = float(fn(*rows, h, h))
            worst = max(worst, abs(mine - _rnea(model, t)))
        errors.append(worst)
    peak = max(abs(_rnea(model, t)) for t in np.linspace(0.1, 1.9, 7))
    assert peak > 0.2  # N m: the motion loads the waist
    assert errors[-1] < 1e-4 * peak
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.8), (errors, orders)


def test_the_static_effort_is_gravitys_moment():
    """At rest in the draft's pose the formula gives RNEA's gravity torque (round-off)."""
    urdf, scene, model = _robot("x")
    q = configuration(scene)
    static = static_held_efforts(Multibody(scene), q)
    X, R_link = scene.robot.link_pose(scene.root.body)
    i = 12 * scene.body_index(scene.root.body)
    D = q[i + 3:i + 12].reshape(3, 3).T
    q_pin = pin.neutral(model)
    q_pin[:3], q_pin[3:7] = q[i:i + 3] + D @ X, pin.Quaternion(D @ R_link).coeffs()
    gravity = pin.computeGeneralizedGravity(model, model.createData(), q_pin)
    expected = gravity[model.joints[model.getJointId("waist_joint")].idx_v]
    assert abs(expected) > 0.1
    assert static["waist_joint"] == pytest.approx(expected, abs=1e-9)


def test_the_draft_bounds_every_locked_joint_with_an_effort_limit():
    _, scene, _ = _robot("y")
    (hold,) = holds_of(scene)
    assert (hold.name, hold.body, hold.side, hold.effort) == \
        ("waist_joint", scene.root.body, 1, 30.0)
    assert hold.mass == pytest.approx(1.0)


def test_a_waist_that_cannot_hold_the_standing_robot_is_refused(tmp_path):
    """The arm's weight 3 cm beside the waist's x axis needs ~0.3 N m standing: a 0.1 N m
    limit is refused before anything is built, naming the joint and what it needs."""
    urdf = biped(waist_axis="x", arm_com="0.05 0.03 0.2", waist_effort=0.1)
    (tmp_path / "biped.urdf").write_text(urdf)
    draft = draft_scene(urdf, urdf_file="biped.urdf")
    scene_file = write_draft(draft, tmp_path / "biped.yaml")
    with pytest.raises(RequestError, match=r"locked joint waist_joint needs 0\.\d+ N m .* "
                                           r"beyond its URDF effort limit 0\.1 N m"):
        resolve(PlanRequest(scene=str(scene_file)), find_scene)
    held = static_held_efforts(Multibody(scene_from_text(draft.yaml, "b.yaml")),
                               configuration(scene_from_text(draft.yaml, "b.yaml")))
    assert abs(held["waist_joint"]) > 0.1


def test_an_impacts_impulse_is_published_apart():
    """At the node where a contact is established the effort is its neighbours' mean and
    the rest, times the node's time step, is the impulse; elsewhere nothing moves."""
    times = np.array([0.0, 0.01, 0.02, 0.035, 0.05, 0.06])
    held = np.array([[1.0, 0.5], [2.0, 0.5], [3.0, 0.5], [90.0, -40.0], [5.0, 0.5],
                     [6.0, 0.5]])
    active = [("a",), ("a",), ("a",), ("a", "b"), ("a", "b"), ("b",)]  # b lands at node 3
    efforts, impulses = split_impulses(held, times, active)
    assert np.array_equal(efforts[[0, 1, 2, 4, 5]], held[[0, 1, 2, 4, 5]])
    assert efforts[3] == pytest.approx([4.0, 0.5])
    assert impulses[3] == pytest.approx([86.0 * 0.015, -40.5 * 0.015])
    assert not impulses[[0, 1, 2, 4, 5]].any()  # a release (node 5) is no impact


def test_the_verifier_fails_an_effort_beyond_the_urdfs_limit():
    urdf = biped(waist_effort=7.5)
    names = ("left_knee_joint", "waist_joint")
    effort = np.array([[10.0, 7.5], [-119.0, -7.0], [0.0, 7.52]])
    shares = effort_shares(urdf, names, effort)
    assert shares["left_knee_joint"] == pytest.approx((119.0 / 120.0, 1, 120.0))
    assert shares["waist_joint"][:2] == pytest.approx((7.52 / 7.5, 2))
    (failure,) = effort_limit_failures(shares)
    assert "joint waist_joint needs 7.52 N m at node 2" in failure
    assert not effort_limit_failures(effort_shares(urdf, names, effort[:2]))
