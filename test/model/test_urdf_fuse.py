"""A URDF's ball joints drafted as spherical joints (`gait_planner.model.urdf_fuse`).

* walker3d exported (`gait-planner urdf`: each spherical joint three revolute joints with
  two 1e-9 kg links) and imported back is walker3d: the same bodies (masses, inertias with
  the torso's written realisable), joints (types, axes, angle names), contact points and
  initial pose, and for any joint angles the same configuration (1e-9).
* URDF joint names other than <joint>_pitch/_roll/_yaw are kept as the spherical joint's
  angle names, by the loader and the verifier.
* What is not exactly a spherical joint is refused, naming the massless link and why:
  axes in another order, axes that do not meet, one massless link alone; links with mass
  are never fused.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.io.urdf import realisable_inertia, scene_to_urdf
from gait_planner.model.angles import configuration, joint_angles
from gait_planner.model.loader import load_scene, scene_from_text
from gait_planner.model.scene import InitialPose, JointType
from gait_planner.model.urdf_import import UrdfError, draft_scene
from gait_planner.verify.mechanics import parse_scene

ROUND_OFF = 1e-9


@pytest.fixture(scope="module")
def walker3d():
    return load_scene("walker3d")


@pytest.fixture(scope="module")
def imported(walker3d):
    draft = draft_scene(scene_to_urdf(walker3d))
    return scene_from_text(draft.yaml, "walker3d draft")


def _points(scene, joint) -> tuple[np.ndarray, np.ndarray]:
    return (np.array(scene.body(joint.parent).points[joint.parent_point]),
            np.array(scene.body(joint.child).points[joint.child_point]))


def test_bodies_joints_and_contacts_are_walker3ds(walker3d, imported):
    assert {b.name for b in imported.bodies} == {b.name for b in walker3d.bodies}
    for body in walker3d.bodies:
        mine = imported.body(body.name)
        inertia = realisable_inertia(body.inertia) if body.name == "torso" else body.inertia
        assert mine.mass == pytest.approx(body.mass, rel=ROUND_OFF), body.name
        np.testing.assert_allclose(mine.inertia, inertia, rtol=ROUND_OFF, err_msg=body.name)
    joints = {j.name: j for j in imported.joints}
    assert set(joints) == {j.name for j in walker3d.joints}
    for joint in walker3d.joints:
        mine = joints[joint.name]
        assert (mine.type, mine.parent, mine.child, mine.angle_names) == \
               (joint.type, joint.parent, joint.child, joint.angle_names), joint.name
        for a, b in zip(_points(imported, mine), _points(walker3d, joint)):
            np.testing.assert_allclose(a, b, atol=ROUND_OFF, err_msg=joint.name)
        if joint.type is JointType.REVOLUTE:
            np.testing.assert_allclose(mine.axis, joint.axis, atol=ROUND_OFF)
            np.testing.assert_allclose(mine.reference, joint.reference, atol=ROUND_OFF)
    assert [(c.name, c.body) for c in imported.contacts] == \
           [(c.name, c.body) for c in walker3d.contacts]
    for contact in walker3d.contacts:
        np.testing.assert_allclose(imported.body(contact.body).points[contact.point],
                                   walker3d.body(contact.body).points[contact.point],
                                   atol=ROUND_OFF, err_msg=contact.name)
    np.testing.assert_allclose(imported.initial_pose.root_position,
                               walker3d.initial_pose.root_position, atol=ROUND_OFF)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-1.2, 1.2), min_size=14, max_size=14))
def test_any_angles_give_walker3ds_configuration(walker3d, imported, values):
    angles, k = {}, 0
    for joint in walker3d.joints:
        angles[joint.name] = tuple(values[k:k + joint.dof])
        k += joint.dof
    pose = InitialPose((0.1, -0.2, 1.0), (0.3, -0.2, 0.1), angles)
    q_w, q_i = configuration(walker3d, pose), configuration(imported, pose)
    for i, body in enumerate(walker3d.bodies):
        j = imported.body_index(body.name)
        np.testing.assert_allclose(q_i[12 * j:12 * j + 12], q_w[12 * i:12 * i + 12],
                                   atol=ROUND_OFF, err_msg=body.name)
    mine = dict(zip([n for j in imported.joints for n in j.angle_names],
                    joint_angles(imported, q_i)))
    theirs = dict(zip([n for j in walker3d.joints for n in j.angle_names],
                      joint_angles(walker3d, q_w)))
    assert mine.keys() == theirs.keys()
    np.testing.assert_allclose([mine[n] for n in theirs], list(theirs.values()), atol=1e-8)


# ---------------------------------------------------------------------------- edited URDFs


def _edit(walker3d, change) -> str:
    robot = ET.fromstring(scene_to_urdf(walker3d))
    change({e.get("name"): e for e in robot.findall("joint")},
           {e.get("name"): e for e in robot.findall("link")})
    return ET.tostring(robot, encoding="unicode")


def test_urdf_names_become_the_spherical_joints_angle_names(walker3d):
    names = {"hip_l": ("hip_l_flexion", "hip_l_abduction", "hip_l_rotation"),
             "hip_r": ("hip_r_flexion", "hip_r_abduction", "hip_r_rotation")}

    def rename(joints, _links):
        for joint, new in names.items():
            for axis, name in zip(("pitch", "roll", "yaw"), new):
                joints[f"{joint}_{axis}"].set("name", name)

    draft = draft_scene(_edit(walker3d, rename))
    data = yaml.safe_load(draft.yaml)
    data["gait"]["options"]["joint_limits"] = {"hip_l_abduction": [-10, 10]}
    scene = scene_from_text(yaml.safe_dump(data), "renamed")
    angles = {j.name: j.angle_names for j in scene.joints}
    assert angles["hip_l_flexion"] == names["hip_l"]
    assert angles["hip_r_flexion"] == names["hip_r"]
    assert angles["ankle_r"] == ("ankle_r_pitch", "ankle_r_roll", "ankle_r_yaw")
    verifier = {j.name: j.angles for j in parse_scene(draft.yaml).joints}
    assert verifier == angles


def _swap_roll_and_yaw(joints, _links):
    roll, yaw = joints["hip_r_roll"].find("axis"), joints["hip_r_yaw"].find("axis")
    roll_xyz = roll.get("xyz")
    roll.set("xyz", yaw.get("xyz"))
    yaw.set("xyz", roll_xyz)


def _move_roll(joints, _links):  # on both sides: the robot stays symmetric
    for side in "lr":
        joints[f"ankle_{side}_roll"].find("origin").set("xyz", "0 0 0.01")


def _one_massless_link(joints, _links):
    joints["hip_r_roll"].set("type", "fixed")


def _turn_thighs(_joints, links):
    for side, angle in (("l", 0.1), ("r", -0.1)):  # mirror images: principal axes turned
        links[f"thigh_{side}"].find("inertial/origin").set("rpy", f"0 0 {angle}")


@pytest.mark.parametrize("change, named", [
    (_swap_roll_and_yaw, r"'hip_r_pitch', 'hip_r_roll', 'hip_r_yaw'.*hip_r_pitch_link.*"
                         r"not the scene's spherical joint's"),
    (_move_roll, r"ankle_l_pitch_link.*do not meet in one point \(0.005 m"),
    (_one_massless_link, r"link 'hip_r_pitch_link' .* massless .* 1 massless link\(s\) in a "
                         r"row, not two"),
    (_turn_thighs, r"'thigh_l''s directors .* not 'torso''s at the URDF's zero pose"),
])
def test_what_is_not_a_spherical_joint_is_refused(walker3d, change, named):
    with pytest.raises(UrdfError, match=named):
        draft_scene(_edit(walker3d, change))


def test_links_with_mass_are_never_fused(walker3d):
    def weigh(_joints, links):
        for name in ("hip_l_pitch_link", "hip_l_roll_link", "hip_r_pitch_link",
                     "hip_r_roll_link"):
            inertial = links[name].find("inertial")
            inertial.find("mass").set("value", "0.5")
            for axis in ("ixx", "iyy", "izz"):
                inertial.find("inertia").set(axis, "1e-4")

    scene = scene_from_text(draft_scene(_edit(walker3d, weigh)).yaml, "heavy hips")
    types = {j.name: j.type for j in scene.joints}
    assert all(types[f"hip_{s}_{a}"] is JointType.REVOLUTE for s in "lr"
               for a in ("pitch", "roll", "yaw"))
    assert types["ankle_r"] is JointType.SPHERICAL
    assert scene.body("hip_r_roll_link").mass == 0.5
