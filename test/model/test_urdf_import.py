"""A scene drafted from a URDF (`gait_planner.model.urdf_import`) is the URDF's model.

* Exactness, against Pinocchio's forward kinematics on the original URDF: for any joint
  angles (hypothesis), the drafted scene's configuration puts every joint point and contact
  point where Pinocchio puts it (1e-9 m), for small synthetic bipeds whose joint origins
  turn the link frames (rpy), whose axes are x, y or z of either sign and whose inertias
  are not diagonal in the link frames; every constraint of the drafted multibody holds.
* The angles are the URDF's: zero at the URDF's zero, the scene's joint_angles of that
  configuration return the angles given, the joint names are the URDF's.
* Each refusal names the joint or link and the rule, in well under a second.
* The draft does not depend on the URDF's link frames nor on its base's heading (#61 item
  4): a biped whose leg link frames are turned (any rotations, hypothesis), whose base x
  points backwards or sideways and whose right knee turns about the opposite axis drafts
  the plain biped's scene (that knee's axis and range negated); the walking direction
  follows the soles, or the knees when the soles are centred; an asymmetric robot with
  turned frames is still refused naming the link and the distance; a massless link
  outside the legs is merged.
* The example robots of example-robot-data (a test dependency): G1, Bolt, iCub, Alexander
  and Romeo are drafted (G1's right knee, whose inertia is not its left partner's mirror
  image in the URDF, is written symmetric and the draft says so); Talos is refused as
  asymmetric at the default tolerance, the refusal naming --mirror-tolerance and the value
  that accepts it, and is drafted with that value (the header lists the right links
  written as mirror images).
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.model.angles import configuration, joint_angles
from gait_planner.model.loader import SceneError, load_scene_file, scene_from_text
from gait_planner.model.multibody import Multibody
from gait_planner.model.rotations import rot_z, rpy_matrix
from gait_planner.model.scene import InitialPose
from gait_planner.model.urdf_import import UrdfError, draft_scene
from urdf_bipeds import AXES, biped, turn_link_frames

ROUND_OFF = 1e-9


def _scene_and_model(urdf: str):
    draft = draft_scene(urdf)
    scene = scene_from_text(draft.yaml, "biped.yaml")
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    return draft, scene, model


ANGLE = st.floats(-1.0, 1.0)


@settings(max_examples=40, deadline=None)
@given(tilt=st.floats(-0.6, 0.6), knee_axis=st.sampled_from(sorted(AXES)),
       angles=st.lists(ANGLE, min_size=8, max_size=8))
def test_drafted_kinematics_are_the_urdfs(tilt, knee_axis, angles):
    urdf = biped(tilt=tilt, knee_axis=knee_axis)
    draft, scene, model = _scene_and_model(urdf)
    assert set(draft.joints) == {j.name for j in scene.joints}
    assert draft.locked == {"waist_joint": 0.0}
    values = dict(zip(draft.joints, angles))
    pose = InitialPose(root_position=scene.initial_pose.root_position,
                       root_angles=scene.initial_pose.root_angles,
                       joint_angles={name: (a,) for name, a in values.items()})
    q = configuration(scene, pose)
    mb = Multibody(scene)
    assert np.abs(np.asarray(mb.constraints(q))).max() < ROUND_OFF
    # the scene's angles of that configuration are the ones given (the URDF's convention)
    got = dict(zip([j.name for j in scene.joints], joint_angles(scene, q)))
    assert max(abs(got[n] - values[n]) for n in values) < ROUND_OFF
    # Pinocchio on the original URDF: its base at identity, as the draft's root is in the
    # initial pose (whose root angles are kept), so joint positions agree relative to a hip
    q_pin = pin.neutral(model)
    for name, a in values.items():
        q_pin[model.joints[model.getJointId(name)].idx_q] = a
    data = model.createData()
    pin.forwardKinematics(model, data, q_pin)
    world = {}
    for joint in scene.joints:
        s = mb.block(joint.child).start
        D = q[s + 3:s + 12].reshape(3, 3).T
        world[joint.name] = q[s:s + 3] + D @ np.asarray(scene.body(joint.child).points[
            joint.child_point])
    origin = "left_hip_roll_joint"
    for name in values:
        mine = world[name] - world[origin]
        theirs = data.oMi[model.getJointId(name)].translation - \
            data.oMi[model.getJointId(origin)].translation
        assert np.abs(mine - theirs).max() < ROUND_OFF, name


def test_contact_points_lie_on_the_soles():
    draft, scene, model = _scene_and_model(biped())
    q = configuration(scene)
    mb = Multibody(scene)
    heights = [float((mb.point_matrix(c.body, c.point) @ q)[2]) for c in scene.contacts]
    assert max(abs(h) for h in heights) < ROUND_OFF  # standing: every contact on z = 0
    names = {c.name for c in scene.contacts}
    assert names == {"foot_l_heel", "foot_l_forefoot", "foot_r_heel", "foot_r_forefoot"}
    assert [p.name for p in scene.gait.phases][0] == "right_full"


def test_effort_limits_and_ranges_come_from_the_urdf():
    draft, scene, _ = _scene_and_model(biped())
    options = scene.gait.options
    assert options["effort_limits"]["left_knee_joint"] == 120.0
    assert options["joint_limits"]["left_ankle_joint"] == pytest.approx(
        [np.degrees(-0.8), np.degrees(0.6)], abs=1e-5)
    assert options["joint_speed_max"] == pytest.approx(np.degrees(20.0), abs=1e-5)


@pytest.mark.parametrize("urdf, named", [
    (biped().replace('<joint name="waist_joint"',
                     '<joint name="extra" type="fixed"><parent link="left_hip_link"/>'
                     '<child link="right_foot_link"/></joint><joint name="waist_joint"'),
     "right_foot_link"),
    (biped(knee_type="prismatic"), "left_knee_joint"),
    (biped(knee_mass=0.0), "left_shin_link"),
    (biped(foot_geometry=""), "foot_link"),
    (biped(foot_geometry='<collision><geometry><mesh filename="package://nowhere/foot.stl"/>'
                         '</geometry></collision>'), "foot.stl"),
    (biped(right_knee_mass=1.5), "right_shin_link"),
    (biped(base_y=0.05), "base_link"),
    ('<robot name="r"><link name="a"/></robot>', "feet"),
    ("<robot", "XML"),
])
def test_refusals_name_the_joint_or_link(urdf, named):
    start = time.perf_counter()
    with pytest.raises(UrdfError, match=named):
        draft_scene(urdf)
    assert time.perf_counter() - start < 5.0  # before anything is built


def test_feet_given_against_the_walking_direction_are_refused():
    with pytest.raises(UrdfError, match="--feet gives the foot below joint 'right_ankle_joint' "
                                        "as the left one, but the soles"):
        draft_scene(biped(), feet=["right_foot_link", "left_foot_link"])
    assert draft_scene(biped(), feet=["left_foot_link", "right_foot_link"]).yaml == \
        draft_scene(biped()).yaml


def test_non_physical_inertia_is_refused():
    urdf = biped().replace('<mass value="1.0"/><inertia ixx="0.02" iyy="0.03" izz="0.04"',
                           '<mass value="1.0"/><inertia ixx="0.02" iyy="0.03" izz="0.09"')
    with pytest.raises(UrdfError, match="link 'left_shin_link' has a non-physical inertia"):
        draft_scene(urdf)


# ----------------------------------------------------------------------------- link frames

LEG_LINKS = tuple(f"{side}_{part}_link" for side in ("left", "right")
                  for part in ("hip", "thigh", "shin", "foot"))
TURN = st.tuples(st.floats(-3.1, 3.1), st.floats(-1.5, 1.5), st.floats(-3.1, 3.1)).map(
    rpy_matrix)


def _draft_data(urdf: str) -> tuple[dict, dict]:
    """(the draft's scene data without its robot section, the robot section's links)."""
    data = yaml.safe_load(draft_scene(urdf).yaml)
    return data, data.pop("robot")["links"]


def _assert_same(a, b, where: str = "scene") -> None:
    """Equal data, numbers to 1e-9."""
    if isinstance(a, dict):
        assert list(a) == list(b), where
        for key in a:
            _assert_same(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert abs(a - b) < ROUND_OFF, f"{where}: {a} != {b}"
    else:
        assert a == b, where


def test_turned_leg_frames_and_a_backward_x_draft_the_plain_scene():
    """iCub's case: its base x points backwards, its right leg's link frames are not its
    left leg's mirrored and a right joint turns about the opposite axis; the draft is the
    plain robot's, that joint's axis and range negated."""
    turns = {"base_link": rot_z(np.pi), "right_hip_link": rpy_matrix([np.pi / 2, 0, 0]),
             "right_thigh_link": rpy_matrix([0, 0, np.pi]),
             "right_shin_link": rpy_matrix([0.3, -1.2, 2.0]),
             "right_foot_link": rpy_matrix([0, np.pi / 2, np.pi / 2])}
    plain, _ = _draft_data(biped())
    turned, _ = _draft_data(turn_link_frames(biped(), turns, flipped=("right_knee_joint",)))
    knee = next(j for j in plain["joints"] if j["name"] == "right_knee_joint")
    knee["axis"] = [-x for x in knee["axis"]]
    limits = plain["gait"]["options"]["joint_limits"]
    limits["right_knee_joint"] = [-x for x in limits["right_knee_joint"][::-1]]
    for phase in plain["gait"]["options"]["phase_joint_limits"].values():  # the envelope's
        if "right_knee_joint" in phase:
            phase["right_knee_joint"] = [-x for x in phase["right_knee_joint"][::-1]]
    _assert_same(plain, turned)


@settings(max_examples=25, deadline=None)
@given(yaw=st.floats(-np.pi, np.pi).filter(  # a heading within 1e-4 rad of an axis is it
    lambda a: abs(a / (np.pi / 2) - round(a / (np.pi / 2))) * np.pi / 2 > 1e-3),
       turns=st.lists(TURN, min_size=8, max_size=8))
def test_any_leg_link_frames_and_base_heading_draft_the_plain_scene(yaw, turns):
    """The draft does not depend on the URDF's link frames nor on its base's heading: each
    body's link frame in the robot section is the plain one turned, everything else is
    the plain draft."""
    rotations = {"base_link": rot_z(yaw), **dict(zip(LEG_LINKS, turns))}
    plain, plain_links = _draft_data(biped())
    turned, turned_links = _draft_data(turn_link_frames(biped(), rotations))
    _assert_same(plain, turned)
    for link, Q in rotations.items():
        position, rpy = np.reshape(plain_links[link], (2, 3))
        assert np.abs(np.asarray(turned_links[link][:3]) - position).max() < ROUND_OFF
        assert np.abs(rpy_matrix(turned_links[link][3:]) - rpy_matrix(rpy) @ Q).max() < \
            ROUND_OFF, link


CENTRED_FEET = "".join(  # soles centred under the ankles: they do not tell forward
    f'<collision><origin xyz="{x} {y} -0.06"/><geometry><sphere radius="0.005"/></geometry>'
    f'</collision>' for x in (-0.08, 0.08) for y in (-0.03, 0.03))


@pytest.mark.parametrize("feet, cue", [(None, "the soles"), (CENTRED_FEET, "the knees")])
def test_the_walking_direction_follows_the_feet_or_the_knees(feet, cue):
    """With its base turned (x backwards, or sideways) the robot walks as the plain one
    does: the soles tell forward (the toes reach further than the heels), or, with soles
    centred under the ankles, the knees (flexing moves the feet back); the header says
    which."""
    plain, _ = _draft_data(biped(foot_geometry=feet))
    assert "Walking direction" not in draft_scene(biped(foot_geometry=feet)).yaml  # its x
    for yaw in (np.pi, np.pi / 2):
        urdf = turn_link_frames(biped(foot_geometry=feet), {"base_link": rot_z(yaw)})
        turned, _ = _draft_data(urdf)
        _assert_same(plain, turned)
        assert f"told by {cue}" in draft_scene(urdf).yaml


def test_a_heading_within_the_snap_of_an_axis_is_drawn_along_it_and_listed():
    """A base turned by 5e-5 rad (iCub's feet stand 4.7e-5 rad off its base's axes) walks
    along the URDF's x; the header lists the turn."""
    draft = draft_scene(turn_link_frames(biped(), {"base_link": rot_z(5e-5)}))
    assert "Walking direction" not in draft.yaml
    assert "#   walking frame: turned by 5e-05 rad and moved by " in draft.yaml


def test_an_asymmetric_robot_with_turned_frames_is_refused_naming_the_link():
    urdf = biped().replace('<origin xyz="0 0 -0.15" rpy="-0.1 -0.2 -0.3"/>',
                           '<origin xyz="0 0 -0.17" rpy="-0.1 -0.2 -0.3"/>')
    turns = {"base_link": rot_z(np.pi), "right_shin_link": rpy_matrix([0.3, -1.2, 2.0])}
    with pytest.raises(UrdfError, match=r"right_shin_link's centre of mass is 20 mm from "
                                        r"left_shin_link's mirror image"):
        draft_scene(turn_link_frames(urdf, turns))


def test_a_massless_link_outside_the_legs_is_merged_into_the_base():
    """A locked link without mass (an IMU or a handle frame on a joint) adds nothing: the
    draft is the robot's without that link."""
    plain = biped()
    arm = plain[plain.index('<link name="arm_link">'):plain.index("</link>", plain.index(
        '<link name="arm_link">')) + len("</link>")]
    massless, _ = _draft_data(plain.replace(arm, '<link name="arm_link"/>'))
    without = biped().replace(arm, "")
    without = without[:without.index('<joint name="waist_joint"')] + without[
        without.index("</joint>", without.index('<joint name="waist_joint"')) + len("</joint>"):]
    bare, _ = _draft_data(without)
    massless["description"] = bare["description"]  # it counts the locked joints
    _assert_same(bare, massless)


# ----------------------------------------------------------------------------- example robots


@pytest.mark.parametrize("path, joints", [
    ("g1_description/urdf/g1_29dof_rev_1_0.urdf", 12),
    ("bolt_description/robots/bolt.urdf", 6),
    ("icub_description/robots/icub_reduced.urdf", 12),  # x backwards, right leg turned
    ("alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf", 12),  # LEFT_/RIGHT_
    ("romeo_description/urdf/romeo_small.urdf", 12),  # LAnkleRoll/RAnkleRoll
])
def test_example_robots_are_drafted(example_robots, path, joints):
    urdf = (example_robots / path).read_text()
    draft = draft_scene(urdf, package_dirs=[str(example_robots.parents[1])])
    scene = scene_from_text(draft.yaml, path)
    assert len(scene.joints) == joints
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    assert all(model.existJointName(j.name) for j in scene.joints)
    q = configuration(scene)
    assert np.abs(np.asarray(Multibody(scene).constraints(q))).max() < ROUND_OFF


def test_talos_is_refused_at_the_default_tolerance_and_drafted_when_asked(example_robots):
    urdf = (example_robots / "talos_data/robots/talos_reduced.urdf").read_text()
    dirs = [str(example_robots.parents[1])]
    with pytest.raises(UrdfError, match=r"leg_right_2_link's inertia is 5\.35 % from "
                       r"leg_left_2_link's mirror image .*--mirror-tolerance 0\.06 accepts it"):
        draft_scene(urdf, package_dirs=dirs)
    draft = draft_scene(urdf, package_dirs=dirs, mirror_tolerance=0.06)
    header = [line for line in draft.yaml.splitlines() if line.startswith("#")]
    assert "# Made mirror-symmetric (the URDF's own data differ; --mirror-tolerance 0.06):" \
        in header
    assert "#   leg_right_2_link: inertia moved by 0.000226 (5.35 %) to be leg_left_2_link's " \
        "mirror image" in header
    scene = scene_from_text(draft.yaml, "talos.yaml")
    right, left = scene.body("leg_right_2_link"), scene.body("leg_left_2_link")
    assert right.mass == left.mass and right.inertia == left.inertia
    with pytest.raises(UrdfError, match=r"--mirror-tolerance takes a fraction in \[0, 1\)"):
        draft_scene(urdf, package_dirs=dirs, mirror_tolerance=6)


def test_the_robot_section_names_the_urdf(tmp_path):
    urdf = biped()
    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "biped.urdf").write_text(urdf)
    draft = draft_scene(urdf, locked={"waist_joint": 0.25}, urdf_file="robots/biped.urdf")
    (tmp_path / "biped.yaml").write_text(draft.yaml)
    scene = load_scene_file(tmp_path / "biped.yaml")
    assert scene.robot.urdf == urdf and dict(scene.robot.locked) == {"waist_joint": 0.25}
    assert set(scene.robot.links) == {b.name for b in scene.bodies}
    assert scene_from_text(draft.yaml, "biped.yaml").robot.urdf == ""  # no folder: not read
    (tmp_path / "robots" / "biped.urdf").unlink()
    with pytest.raises(SceneError, match=r"robot\.urdf: the robot's URDF .*biped\.urdf"):
        load_scene_file(tmp_path / "biped.yaml")
    broken = draft.yaml.replace("    base_link: [", "    no_such_body: [")
    with pytest.raises(SceneError, match="unknown body 'no_such_body'"):
        scene_from_text(broken, "broken.yaml")
