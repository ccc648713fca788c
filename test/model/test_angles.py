"""The joint-angle convention of `gait_planner.model.angles` and configurations from angles.

* configuration(scene, pose) -> joint_angles round-trips (|roll| < 80 deg, elsewhere any
  angle in (-pi, pi)), and the configuration satisfies every constraint;
* next to the gimbal lock of the spherical sequence (roll within 1e-7 rad of +-90 deg) the
  returned angles still rebuild the relative rotation to round-off (same for the root);
* the upright pose has all angles zero; a positive knee angle bends the knee (the calf's
  lower end moves backward), a positive hip pitch swings the leg backward;
* the initial poses stand on the ground: every foot contact point at z = 0.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.model.angles import (
    configuration,
    joint_angles,
    root_angles,
    spherical_angles,
    spherical_rotation,
)
from gait_planner.model.rotations import cross, rot_x, rot_y, rot_z
from gait_planner.model.scene import InitialPose, JointType

ROUND_OFF = 1e-12
SCENES = ("compass", "walker2d", "walker3d")
ANY = st.floats(-3.1, 3.1)  # any angle, away from the +-pi branch cut
MIDDLE = st.floats(-np.radians(80), np.radians(80))  # the middle angle of a Cardan sequence
NEAR_LOCK = st.tuples(st.sampled_from([-1.0, 1.0]), st.floats(0.0, 1e-7)).map(
    lambda sd: sd[0] * (np.pi / 2 - sd[1])
)


def frame(mb, q, body):
    s = mb.block(body).start
    return q[s + 3 : s + 12].reshape(3, 3).T  # [d1 d2 d3]


def point(mb, q, body, name):
    return mb.point_matrix(body, name) @ q


@st.composite
def poses(draw, scene):
    """Random pose: root anywhere, joint angles with |roll| < 80 deg (planar: in-plane)."""
    if scene.planar:
        root_angles_ = (0.0, draw(MIDDLE), 0.0)
        y = scene.initial_pose.root_position[1]
    else:
        root_angles_ = (draw(ANY), draw(MIDDLE), draw(ANY))
        y = draw(st.floats(-2, 2))
    angles = {}
    for joint in scene.joints:
        if joint.type is JointType.SPHERICAL:
            angles[joint.name] = (draw(ANY), draw(MIDDLE), draw(ANY))
        else:
            angles[joint.name] = (draw(ANY),)
    position = (draw(st.floats(-2, 2)), y, draw(st.floats(-2, 2)))
    return InitialPose(position, root_angles_, angles)


@pytest.mark.parametrize("scene_name", SCENES)
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_configuration_joint_angles_round_trip(model, scene_name, data):
    scene, mb = model(scene_name).scene, model(scene_name).mb
    pose = data.draw(poses(scene))
    q = configuration(scene, pose)
    assert np.abs(np.array(mb.constraints(q))).max() <= ROUND_OFF
    expected = np.concatenate([pose.joint_angles[j.name] for j in scene.joints])
    np.testing.assert_allclose(joint_angles(scene, q), expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(root_angles(frame(mb, q, scene.root.body)), pose.root_angles,
                               rtol=0, atol=1e-9)
    # batched form
    assert joint_angles(scene, np.stack([q, q])).shape == (2, expected.size)


@settings(max_examples=60, deadline=None)
@given(pitch=ANY, roll=NEAR_LOCK, yaw=ANY)
def test_spherical_angles_rebuild_rotation_near_gimbal_lock(pitch, roll, yaw):
    R = spherical_rotation(pitch, roll, yaw)
    angles = spherical_angles(R)
    assert abs(angles[1] - roll) <= 1e-14
    assert np.abs(spherical_rotation(*angles) - R).max() <= 1e-14


@settings(max_examples=60, deadline=None)
@given(yaw=ANY, pitch=NEAR_LOCK, roll=ANY)
def test_root_angles_rebuild_rotation_near_gimbal_lock(yaw, pitch, roll):
    R = rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)
    a = root_angles(R)
    assert abs(a[1] - pitch) <= 1e-14
    assert np.abs(rot_z(a[0]) @ rot_y(a[1]) @ rot_x(a[2]) - R).max() <= 1e-14


@settings(max_examples=30, deadline=None)
@given(hip=st.tuples(ANY, NEAR_LOCK, ANY), ankle=st.tuples(ANY, NEAR_LOCK, ANY))
def test_joint_angles_near_gimbal_lock_rebuild_configuration(model, hip, ankle):
    """walker3d with hip_r and ankle_l next to the lock: R_rel rebuilt from the returned
    angles equals D_p^T D_c, and the configuration rebuilt from them equals q."""
    scene, mb = model("walker3d").scene, model("walker3d").mb
    pose = InitialPose((0.0, 0.0, 1.0), (0.3, -0.2, 0.1), {"hip_r": hip, "ankle_l": ankle})
    q = configuration(scene, pose)
    angles = joint_angles(scene, q)
    for joint in scene.joints:
        if joint.type is not JointType.SPHERICAL:
            continue
        R_rel = frame(mb, q, joint.parent).T @ frame(mb, q, joint.child)
        rebuilt = spherical_rotation(*angles[mb.joint_slices[joint.name]])
        assert np.abs(rebuilt - R_rel).max() <= 1e-14
    named = {j.name: tuple(angles[mb.joint_slices[j.name]]) for j in scene.joints}
    q_again = configuration(scene, InitialPose(pose.root_position, pose.root_angles, named))
    assert np.abs(q_again - q).max() <= ROUND_OFF


def test_upright_pose_has_zero_angles(any_model):
    scene = any_model.scene
    upright = InitialPose(scene.initial_pose.root_position)
    assert np.abs(joint_angles(scene, configuration(scene, upright))).max() <= 1e-15
    q = configuration(scene, upright)
    for i in range(any_model.mb.nb):  # every triad is the world triad
        assert np.abs(q[12 * i + 3 : 12 * i + 12] - np.eye(3).ravel()).max() == 0.0


@pytest.mark.parametrize("scene_name", ["walker2d", "walker3d"])
@pytest.mark.parametrize("side", ["r", "l"])
def test_positive_knee_angle_bends_knee(model, scene_name, side):
    scene, mb = model(scene_name).scene, model(scene_name).mb
    upright = configuration(scene, InitialPose(scene.initial_pose.root_position))
    bent = configuration(scene, InitialPose(scene.initial_pose.root_position,
                                            joint_angles={f"knee_{side}": (0.6,)}))
    calf = f"calf_{side}"
    before, after = point(mb, upright, calf, "ankle"), point(mb, bent, calf, "ankle")
    shank = 0.1943 + 0.1810  # knee to ankle
    np.testing.assert_allclose(after - before,
                               [-shank * np.sin(0.6), 0.0, shank * (1 - np.cos(0.6))],
                               atol=1e-12)
    # the knee itself does not move, and the angle reads back
    np.testing.assert_allclose(point(mb, bent, calf, "knee"), point(mb, upright, calf, "knee"),
                               atol=1e-15)
    assert joint_angles(scene, bent)[mb.joint_slices[f"knee_{side}"]] == pytest.approx(0.6)


def test_positive_hip_pitch_swings_leg_backward(model):
    scene, mb = model("walker3d").scene, model("walker3d").mb
    q = configuration(scene, InitialPose(scene.initial_pose.root_position,
                                         joint_angles={"hip_r": (0.4, 0.0, 0.0)}))
    upright = configuration(scene)
    assert point(mb, q, "foot_r", "heel")[0] < point(mb, upright, "foot_r", "heel")[0] - 0.3


def test_initial_poses_stand_on_the_ground(any_model):
    scene, mb = any_model.scene, any_model.mb
    q = configuration(scene)
    for contact in scene.contacts:
        assert point(mb, q, contact.body, contact.point)[2] == pytest.approx(0.0, abs=1e-12)
    if scene.name.startswith("walker"):
        # the torso's centre of mass at the height docs/design.md section 6 implies
        assert q[2] == pytest.approx(0.0133 + 0.0502 + 0.1810 + 0.1943 + 0.2803 + 0.1779
                                     + 0.2398, abs=1e-12)


VECTORS = st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3).map(np.array)


@given(a=VECTORS, b=VECTORS)
def test_the_plain_cross_product_is_numpys(a, b):
    """`model.rotations.cross` (foot wrenches' moments) against np.cross, to round-off."""
    assert np.allclose(cross(a, b), np.cross(a, b), rtol=1e-12, atol=1e-9)
