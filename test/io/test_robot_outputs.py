"""What a plan of a URDF-drafted scene publishes is the robot's own (issue #37, item 3).

* /tf and /tf_static (`gait_planner.io.robot_tree`): composed from ``world`` as a tf
  listener does, every link of the original URDF lands where Pinocchio's forward kinematics
  of that URDF puts it (1e-9 m), for any joint angles, root pose, tilted joint frames and a
  locked joint away from zero (hypothesis), and for walker3d's own URDF imported back (its
  hips and ankles fused into spherical joints); each contact frame lands on the plan's
  contact point.
* The JointTrajectory carries the locked joints after the planned ones, held at their
  angle with the efforts the URDF certificate computed, and refuses to publish without them.
* The certificate on the original URDF (`gait_planner.verify.robot`) and the one on the
  draft (`gait_planner.verify.continuous`) are two independent inverse dynamics of two
  descriptions of one robot: on a smooth motion they give the same joint torques and base
  residual (the draft is exact for a symmetric robot; a waist locked at a yaw is not
  symmetric, and the draft's mirror-symmetric data then differ from the URDF's).
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.io.messages import published_joints
from gait_planner.io.robot_tree import robot_tree
from gait_planner.model.angles import angle_names, configuration
from gait_planner.io.urdf import scene_to_urdf
from gait_planner.model.loader import load_scene, scene_from_text
from gait_planner.model.rotations import rot_axis, rpy_matrix
from gait_planner.model.scene import InitialPose
from gait_planner.model.urdf_import import draft_scene
from gait_planner.verify.continuous import certificate
from gait_planner.verify.mechanics import parse_scene
from gait_planner.verify.robot import robot_certificate
from urdf_bipeds import biped

ROUND_OFF = 1e-9
LOCK = 0.3  # rad, the waist's locked angle


def _robot_scene(tilt: float = 0.2, lock: float = LOCK):
    urdf = biped(tilt=tilt)
    draft = draft_scene(urdf, locked={"waist_joint": lock})
    scene = scene_from_text(draft.yaml, "biped.yaml")  # no folder: the URDF is not read
    return urdf, draft, dataclasses.replace(scene, robot=dataclasses.replace(scene.robot,
                                                                             urdf=urdf))


def _pose(scene, angles, root) -> np.ndarray:
    values, k = {}, 0
    for joint in scene.joints:  # angles in the order of angle_names(scene)
        values[joint.name], k = tuple(angles[k:k + joint.dof]), k + joint.dof
    return configuration(scene, InitialPose(
        root_position=tuple(np.asarray(scene.initial_pose.root_position) + root[:3]),
        root_angles=tuple(root[3:]), joint_angles=values))


def _tf_world(scene, q: np.ndarray, angles) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """link -> (position, rotation) in world, composing the tree's transforms as tf does."""
    tree = robot_tree(scene)
    root = scene.body_index(tree.root)
    phi, D = q[12 * root:12 * root + 3], q[12 * root + 3:12 * root + 12].reshape(3, 3).T
    world = {tree.root: (phi + D @ tree.root_pose[0], D @ tree.root_pose[1])}
    pending = list(tree.joints)
    while pending:
        joint = next(j for j in pending if j.parent in world)
        pending.remove(joint)
        p, R = world[joint.parent]
        turn = rpy_matrix(joint.rpy)
        if not joint.fixed:
            turn = turn @ rot_axis(np.asarray(joint.axis), angles[joint.angle_index])
        world[joint.child] = (p + R @ np.asarray(joint.origin), R @ turn)
    return world


def _walker3d_round_trip():
    urdf = scene_to_urdf(load_scene("walker3d"))
    scene = scene_from_text(draft_scene(urdf).yaml, "walker3d_urdf.yaml")
    return urdf, None, dataclasses.replace(scene, robot=dataclasses.replace(scene.robot,
                                                                            urdf=urdf))


@settings(max_examples=15, deadline=None)
@given(tilt=st.floats(-0.6, 0.6), angles=st.lists(st.floats(-1, 1), min_size=14, max_size=14),
       root=st.lists(st.floats(-0.5, 0.5), min_size=6, max_size=6),
       walker3d=st.booleans())
def test_tf_puts_every_link_where_pinocchio_does(tilt, angles, root, walker3d):
    """The synthetic biped (8 revolute joints, a waist locked at LOCK) or walker3d's own
    export imported back (hips and ankles fused into spherical joints, 14 angles)."""
    urdf, _, scene = _walker3d_round_trip() if walker3d else _robot_scene(tilt)
    angles = angles[:len(angle_names(scene))]
    q = _pose(scene, angles, np.asarray(root))
    world = _tf_world(scene, q, angles)
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    base_p, base_R = world[scene.root.body]
    q_pin = pin.neutral(model)
    q_pin[:3], q_pin[3:7] = base_p, pin.Quaternion(base_R).coeffs()
    for name, a in list(zip(angle_names(scene), angles)) + list(scene.robot.locked.items()):
        joint = model.joints[model.getJointId(name)]  # continuous joints: (cos, sin)
        q_pin[joint.idx_q:joint.idx_q + joint.nq] = (np.cos(a), np.sin(a)) if joint.nq == 2 \
            else a
    data = model.createData()
    pin.framesForwardKinematics(model, data, q_pin)
    links = [f for f in model.frames if f.type == pin.FrameType.BODY]
    assert {f.name for f in links} <= set(world)
    for frame in links:
        placement = data.oMf[model.getFrameId(frame.name)]
        p, R = world[frame.name]
        assert np.abs(p - placement.translation).max() < ROUND_OFF, frame.name
        assert np.abs(R - placement.rotation).max() < ROUND_OFF, frame.name
    for contact in scene.contacts:  # contact frames on the plan's contact points
        i = scene.body_index(contact.body)
        point = q[12 * i:12 * i + 3] + q[12 * i + 3:12 * i + 12].reshape(3, 3).T @ \
            np.asarray(scene.body(contact.body).points[contact.point])
        assert np.abs(world[contact.name][0] - point).max() < ROUND_OFF, contact.name


def _result(scene, n: int = 4, held: dict | None = None):
    na = len(angle_names(scene))
    rows = np.linspace(0.0, 0.3, n * na).reshape(n, na)
    return SimpleNamespace(scene=scene, joint_angle_names=angle_names(scene), n_nodes=n,
                           joint_angles=rows, joint_velocities=2 * rows,
                           joint_accelerations=3 * rows, tau=np.zeros((n, na)),
                           held_efforts={} if held is None else held)


def test_joint_trajectory_holds_the_locked_joints():
    _, _, scene = _robot_scene()
    result = _result(scene, held={"waist_joint": np.array([1.0, 2.0, 3.0, 4.0])})
    names, position, velocity, acceleration, effort = published_joints(result)
    assert names == list(angle_names(scene)) + ["waist_joint"]
    assert np.all(position[:, -1] == LOCK) and not velocity[:, -1].any()
    assert not acceleration[:, -1].any() and list(effort[:, -1]) == [1.0, 2.0, 3.0, 4.0]
    with pytest.raises(ValueError, match="no held efforts.*waist_joint"):
        published_joints(_result(scene))


def test_certificate_on_the_urdf_agrees_with_the_drafts():
    # waist at zero: a yawed waist makes the robot asymmetric, and the draft symmetric
    urdf, draft, scene = _robot_scene(lock=0.0)
    times = np.linspace(0.0, 0.4, 41)
    wave = np.sin(2 * np.pi * times / 0.4)[:, None]
    angles = 0.3 * wave * np.linspace(0.5, 1.0, 8)[None, :]
    root = np.hstack([0.1 * wave, 0.05 * wave, 0.02 * wave, 0.1 * wave, 0.05 * wave,
                      0.08 * wave])
    q = np.array([_pose(scene, a, r) for a, r in zip(angles, root)])
    zero = np.zeros_like(angles)
    data = parse_scene(draft.yaml)
    active = [()] * len(times)
    on_draft = certificate(data, times, q, zero, {}, active)
    on_urdf, held = robot_certificate(data, urdf, times, q, angles, zero, {}, active)
    assert np.abs(on_urdf.torque_error - on_draft.torque_error).max() < 1e-7
    assert np.abs(on_urdf.base_force - on_draft.base_force).max() < 1e-7
    assert np.abs(on_urdf.base_moment - on_draft.base_moment).max() < 1e-7
    assert on_urdf.base_force.max() > 1.0  # a motion without ground forces: not trivial
    assert set(held) == {"waist_joint"} and held["waist_joint"].shape == times.shape
