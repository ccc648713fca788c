"""The URDF and the /tf frames: structure, inertia, and exact poses of every body from q."""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.cli import main
from gait_planner.io import messages
from gait_planner.io.urdf import (FRAME_LINK_INERTIA, FRAME_LINK_MASS, body_shapes,
                                  kinematic_tree, realisable_inertia, scene_to_urdf)
from gait_planner.model.angles import configuration
from gait_planner.model.loader import load_scene
from gait_planner.model.scene import InitialPose, JointType, Scene

START_NS = 1_700_000_000_123_456_789


def _rotation(q: dict) -> np.ndarray:
    x, y, z, w = q["x"], q["y"], q["z"], q["w"]
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _matrices(tf_message: dict) -> dict[str, tuple[str, np.ndarray]]:
    """child frame -> (parent frame, 4x4 transform parent <- child)."""
    out = {}
    for t in tf_message["transforms"]:
        T = np.eye(4)
        T[:3, :3] = _rotation(t["transform"]["rotation"])
        tr = t["transform"]["translation"]
        T[:3, 3] = [tr["x"], tr["y"], tr["z"]]
        out[t["child_frame_id"]] = (t["header"]["frame_id"], T)
    return out


def _in_world(frame: str, tree: dict[str, tuple[str, np.ndarray]]) -> np.ndarray:
    T = np.eye(4)
    while frame != "world":
        parent, step = tree[frame]
        T = step @ T
        frame = parent
    return T


def _expected_link_origin(scene, body: str) -> np.ndarray:
    """Body-fixed link origin, restated from the scene: COM for the root, else the point
    where the body's parent joint attaches to it."""
    if body == scene.root.body:
        return np.zeros(3)
    joint = next(j for j in scene.joints if j.child == body)
    return np.asarray(scene.body(body).points[joint.child_point])


def test_urdf_parses_with_one_link_per_body_and_angle_named_joints(result):
    scene = result.scene
    robot = ET.fromstring(scene_to_urdf(scene))
    assert robot.tag == "robot" and robot.get("name") == scene.name
    links = {link.get("name"): link for link in robot.findall("link")}
    joints = robot.findall("joint")
    for body in scene.bodies:
        link = links[body.name]
        assert float(link.find("inertial/mass").get("value")) == body.mass
        inertia = link.find("inertial/inertia")  # the paper's torso: its realisable value
        assert [float(inertia.get(k)) for k in ("ixx", "iyy", "izz")] == list(
            realisable_inertia(body.inertia))
        assert all(float(inertia.get(k)) == 0.0 for k in ("ixy", "ixz", "iyz"))
        com = [float(v) for v in link.find("inertial/origin").get("xyz").split()]
        assert np.allclose(com, -_expected_link_origin(scene, body.name), atol=1e-15)
        assert link.find("visual/geometry") is not None
    moving = [j for j in joints if j.get("type") != "fixed"]
    assert [j.get("name") for j in moving] == list(result.joint_angle_names)
    # a tree: every link but the root is the child of exactly one joint
    children = [j.find("child").get("link") for j in joints]
    assert sorted(children) == sorted(set(links) - {scene.root.body})
    assert all(j.find("parent").get("link") in links for j in joints)
    massless = set(links) - {b.name for b in scene.bodies}
    contacts = {c.name for c in scene.contacts}
    assert contacts <= massless
    assert all(links[name].find("inertial") is None for name in contacts)
    for name in massless - contacts:  # spherical joints' links: just above MuJoCo's minimum
        assert float(links[name].find("inertial/mass").get("value")) == FRAME_LINK_MASS


def test_spherical_joint_chain_is_pitch_roll_yaw(result):
    robot = ET.fromstring(scene_to_urdf(result.scene))
    axes = {j.get("name"): [float(v) for v in j.find("axis").get("xyz").split()]
            for j in robot.findall("joint") if j.get("type") != "fixed"}
    for joint in result.scene.joints:
        if joint.type is JointType.SPHERICAL:
            pitch, roll, yaw = joint.angle_names
            assert (axes[pitch], axes[roll], axes[yaw]) == ([0, 1, 0], [1, 0, 0], [0, 0, 1])
        else:
            assert axes[joint.angle_names[0]] == list(joint.axis)


def test_tf_chain_reproduces_every_body_pose_from_q(result):
    scene = result.scene
    static = _matrices(messages.tf_static(result, START_NS))
    for n, tf in enumerate(messages.tf_messages(result, START_NS)):
        tree = {**_matrices(tf), **static}
        for i, body in enumerate(scene.bodies):
            phi = result.q[n, 12 * i:12 * i + 3]
            D = result.q[n, 12 * i + 3:12 * i + 12].reshape(3, 3).T
            T = _in_world(body.name, tree)
            assert np.abs(T[:3, :3] - D).max() < 1e-9, (n, body.name)
            expected = phi + D @ _expected_link_origin(scene, body.name)
            assert np.abs(T[:3, 3] - expected).max() < 1e-9, (n, body.name)
        for contact in scene.contacts:
            T = _in_world(contact.name, tree)
            point = messages.contact_points(result, n, [contact.name])[0]
            assert np.abs(T[:3, 3] - point).max() < 1e-9
        stamps = {t["header"]["stamp"]["sec"] * 10**9 + t["header"]["stamp"]["nanosec"]
                  for t in tf["transforms"]}
        assert stamps == {messages.node_stamps_ns(result, START_NS)[n]}


def test_rerun_urdf_parser_agrees_with_tf(result, tmp_path):
    """rerun's own URDF parser computes each joint's transform from the joint value: it must
    equal the /tf transform of that joint (URDF origins and axes match the tf scheme)."""
    rr = pytest.importorskip("rerun")
    path = tmp_path / "walker.urdf"
    path.write_text(scene_to_urdf(result.scene))
    urdf = rr.urdf.UrdfTree.from_file_path(path)
    by_child = {j.child_link: j for j in urdf.joints()}
    n = 4
    tf = _matrices(messages.tf_messages(result, START_NS)[n])
    checked = 0
    for child, (parent, T) in tf.items():
        if parent == "world":
            continue
        joint = by_child[child]
        assert joint.parent_link == parent
        value = result.joint_angles[n][list(result.joint_angle_names).index(joint.name)]
        transform = joint.compute_transform(float(value), clamp=False)
        translation = np.array(transform.translation.pa_array.to_pylist()[0])
        x, y, z, w = transform.quaternion.pa_array.to_pylist()[0]  # float32 in rerun
        assert np.allclose(translation, T[:3, 3], atol=1e-6)
        assert np.allclose(_rotation({"x": x, "y": y, "z": z, "w": w}), T[:3, :3], atol=1e-6)
        checked += 1
    assert checked == len(result.joint_angle_names)


def test_geometry_and_names(result):
    shapes = body_shapes(result.scene)
    assert shapes["foot_r"].kind == "box" and shapes["thigh_r"].kind == "cylinder"
    assert shapes["foot_r"].size[0] == pytest.approx(0.2433)  # heel to forefoot
    assert shapes["foot_r"].size[2] == pytest.approx(0.0635)  # sole to ankle
    assert shapes["thigh_r"].size[2] == result.scene.body("thigh_r").length
    assert shapes["thigh_r"].side == "right" and shapes["thigh_l"].side == "left"
    assert shapes["torso"].side == "centre"
    tree = kinematic_tree(result.scene)
    assert [j.name for j in tree.moving_joints] == list(result.joint_angle_names)
    assert [j.angle_index for j in tree.moving_joints] == list(range(len(result.joint_angle_names)))


@pytest.mark.parametrize("scene_name", ["walker3d", "walker2d", "compass"])
def test_every_shipped_scene_gets_a_consistent_urdf_and_tf(scene_name, make_result):
    result = make_result(scene_name, intervals=4)
    robot = ET.fromstring(scene_to_urdf(result.scene))
    moving = [j.get("name") for j in robot.findall("joint") if j.get("type") != "fixed"]
    assert moving == list(result.joint_angle_names)
    static = _matrices(messages.tf_static(result, START_NS))
    for n, tf in enumerate(messages.tf_messages(result, START_NS)):
        tree = {**_matrices(tf), **static}
        for i, body in enumerate(result.scene.bodies):
            T = _in_world(body.name, tree)
            D = result.q[n, 12 * i + 3:12 * i + 12].reshape(3, 3).T
            expected = result.q[n, 12 * i:12 * i + 3] + D @ _expected_link_origin(
                result.scene, body.name)
            assert np.abs(T[:3, :3] - D).max() < 1e-9 and np.abs(T[:3, 3] - expected).max() < 1e-9


# ---------------------------------------------------------------- simulators load the URDF

SCENE_NAMES = ("compass", "walker2d", "walker3d")
PAPER_TORSO = (1.6194, 1.0876, 0.3785)


@functools.cache
def _urdf(scene_name: str) -> tuple[Scene, str]:
    scene = load_scene(scene_name)
    return scene, scene_to_urdf(scene)


def _bodies_and_frame_links(scene: Scene) -> tuple[dict[str, str], list[str]]:
    """body -> the URDF joint whose child is its link ('' for the root); and the
    intermediate links of the spherical joints."""
    tree = kinematic_tree(scene)
    joint_of = {j.child: j.name for j in tree.moving_joints}
    bodies = {b.name: joint_of.get(b.name, "") for b in scene.bodies}
    frame_links = [j.child for j in tree.moving_joints if j.child not in bodies]
    return bodies, frame_links


def _expected_inertia(scene: Scene, body: str) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, COM in link coordinates, rotational inertia about the COM in link axes)."""
    b = scene.body(body)
    return b.mass, -_expected_link_origin(scene, body), np.diag(realisable_inertia(b.inertia))


def _moving_axes(scene: Scene) -> dict[str, np.ndarray]:
    """joint angle name -> the axis of its URDF joint (restated from the scene)."""
    axes = {}
    for joint in scene.joints:
        if joint.type is JointType.SPHERICAL:
            axes.update(zip(joint.angle_names, np.eye(3)[[1, 0, 2]]))
        else:
            axes[joint.angle_names[0]] = np.asarray(joint.axis, float)
    return axes


def test_realisable_inertia_is_the_least_change_of_the_offending_moment():
    assert realisable_inertia(PAPER_TORSO) == (1.0876 + 0.3785, 1.0876, 0.3785)
    thigh = (0.1137, 0.1158, 0.0225)
    assert realisable_inertia(thigh) == thigh  # realisable data are kept exactly
    for k in range(3):  # whichever moment offends, only it changes, to the boundary
        given = np.roll(PAPER_TORSO, k)
        written = np.array(realisable_inertia(given))
        assert [i for i in range(3) if written[i] != given[i]] == [k]
        a, b = (k + 1) % 3, (k + 2) % 3
        assert written[k] == given[a] + given[b]
        assert np.abs(written - given).sum() == pytest.approx(given[k] - given[a] - given[b])
        assert all(written[i] <= written[(i + 1) % 3] + written[(i + 2) % 3] for i in range(3))


@pytest.mark.parametrize("scene_name", ["walker3d", "walker2d"])
def test_the_papers_torso_inertia_is_explained_in_the_urdf(scene_name):
    scene, text = _urdf(scene_name)
    assert scene.body("torso").inertia == PAPER_TORSO  # the planner keeps the paper's data
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    torso = ET.fromstring(text, parser=parser).find("link[@name='torso']")
    comments = [c.text for c in torso if c.tag is ET.Comment]
    assert len(comments) == 1
    comment = " ".join(comments[0].split())
    assert "(1.6194, 1.0876, 0.3785)" in comment and "not physically realisable" in comment
    assert "J1 = 1.6194 > J2 + J3 = 1.4661" in comment and "-0.07665" in comment
    assert "nearest realisable value (1.4661, 1.0876, 0.3785)" in comment
    inertia = torso.find("inertial/inertia")
    assert [float(inertia.get(k)) for k in ("ixx", "iyy", "izz")] == [1.4661, 1.0876, 0.3785]


@pytest.mark.parametrize("scene_name", SCENE_NAMES)
def test_urdf_loads_in_mujoco_with_the_scenes_masses_inertias_and_axes(scene_name):
    mujoco = pytest.importorskip("mujoco")
    scene, text = _urdf(scene_name)
    model = mujoco.MjModel.from_xml_string(text)
    bodies, frame_links = _bodies_and_frame_links(scene)
    total = sum(b.mass for b in scene.bodies)
    assert model.body_subtreemass[0] == pytest.approx(total, rel=1e-9, abs=0)
    assert model.body_subtreemass[0] - total == pytest.approx(len(frame_links) * FRAME_LINK_MASS)
    for name in bodies:
        mass, com, inertia = _expected_inertia(scene, name)
        body = model.body(name)
        assert body.mass[0] == mass
        assert np.abs(body.ipos - com).max() < 1e-15
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, body.iquat)
        R = R.reshape(3, 3)
        tensor = R @ np.diag(body.inertia) @ R.T  # principal moments back in link axes
        assert np.abs(tensor - inertia).max() < 1e-14 * np.abs(inertia).max(), name
    for name in frame_links:
        assert model.body(name).mass[0] == FRAME_LINK_MASS
        assert np.all(model.body(name).inertia == FRAME_LINK_INERTIA)
    for contact in scene.contacts:  # fixed frames keep their names, massless
        assert model.body(contact.name).mass[0] == 0.0
    axes = _moving_axes(scene)
    assert {model.joint(j).name for j in range(model.njnt)} == set(axes)
    for name, axis in axes.items():
        joint = model.joint(name)
        assert joint.type[0] == mujoco.mjtJoint.mjJNT_HINGE and joint.limited[0] == 0
        assert np.array_equal(joint.axis, axis)
    # a simulator's walker: the root (welded to the world by the URDF import) set free
    spec = mujoco.MjSpec.from_string(text)
    spec.body(scene.root.body).add_freejoint()
    free = spec.compile()
    data = mujoco.MjData(free)
    mujoco.mj_step(free, data, 10)
    assert free.nq == 7 + len(axes) and np.all(np.isfinite(data.qpos)) and data.qpos[2] < 0


@pytest.mark.parametrize("scene_name", SCENE_NAMES)
def test_urdf_loads_in_pinocchio_with_the_scenes_masses_inertias_and_axes(scene_name):
    pin = pytest.importorskip("pinocchio")
    scene, text = _urdf(scene_name)
    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    bodies, frame_links = _bodies_and_frame_links(scene)
    axes = _moving_axes(scene)
    assert set(model.names) == {"universe", "root_joint", *axes}
    total = sum(b.mass for b in scene.bodies)
    assert pin.computeTotalMass(model) == pytest.approx(total, rel=1e-9, abs=0)
    for name, joint in bodies.items():
        mass, com, inertia = _expected_inertia(scene, name)
        got = model.inertias[model.getJointId(joint or "root_joint")]
        assert got.mass == mass and np.abs(got.lever - com).max() < 1e-15
        assert np.abs(got.inertia - inertia).max() < 1e-15, name
    for name in frame_links:
        joint = next(j.name for j in kinematic_tree(scene).moving_joints if j.child == name)
        assert model.inertias[model.getJointId(joint)].mass == FRAME_LINK_MASS
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    for name, axis in axes.items():
        jid = model.getJointId(name)
        assert model.joints[jid].nq == 2 and model.joints[jid].nv == 1  # unbounded revolute
        motion = np.asarray(data.joints[jid].S).reshape(6)  # (linear, angular)
        assert np.array_equal(motion[3:], axis) and not motion[:3].any()


def _random_pose(scene: Scene, draw) -> InitialPose:
    angle = st.floats(-np.pi, np.pi)
    joints = {j.name: tuple(draw(angle) for _ in range(j.dof)) for j in scene.joints}
    position = tuple(draw(st.floats(-1.0, 1.0)) for _ in range(3))
    return InitialPose(position, tuple(draw(angle) for _ in range(3)), joints)


def _pose_checks(scene: Scene, q: np.ndarray):
    """(frame name, expected rotation, expected origin) of every body link and contact."""
    for i, body in enumerate(scene.bodies):
        phi, D = q[12 * i:12 * i + 3], q[12 * i + 3:12 * i + 12].reshape(3, 3).T
        yield body.name, D, phi + D @ _expected_link_origin(scene, body.name)
    for contact in scene.contacts:
        i = scene.body_index(contact.body)
        phi, D = q[12 * i:12 * i + 3], q[12 * i + 3:12 * i + 12].reshape(3, 3).T
        yield contact.name, D, phi + D @ np.asarray(
            scene.body(contact.body).points[contact.point])


@settings(max_examples=8, deadline=None)
@given(data=st.data())
def test_pinocchio_and_mujoco_kinematics_of_the_urdf_equal_the_planners(data):
    """At random joint angles and root poses, Pinocchio's and MuJoCo's forward kinematics of
    walker3d's URDF put every body's link frame where the planner's configuration puts the
    body (axes = directors, origin = COM or parent-joint point) and every contact frame on
    its contact point."""
    pin = pytest.importorskip("pinocchio")
    mujoco = pytest.importorskip("mujoco")
    scene, text = _urdf("walker3d")
    pose = _random_pose(scene, data.draw)
    q = configuration(scene, pose)
    angles = {}
    for joint in scene.joints:
        angles.update(zip(joint.angle_names, pose.joint_angles[joint.name]))
    root = scene.body_index(scene.root.body)
    phi, D = q[12 * root:12 * root + 3], q[12 * root + 3:12 * root + 12].reshape(3, 3).T

    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    config = pin.neutral(model)
    config[:7] = np.r_[phi, pin.Quaternion(D).coeffs()]  # (x, y, z, w)
    for name, value in angles.items():
        start = model.joints[model.getJointId(name)].idx_q
        config[start:start + 2] = np.cos(value), np.sin(value)
    pdata = model.createData()
    pin.framesForwardKinematics(model, pdata, config)

    spec = mujoco.MjSpec.from_string(text)
    spec.body(scene.root.body).add_freejoint()
    mj = spec.compile()
    mdata = mujoco.MjData(mj)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, D.reshape(-1))
    mdata.qpos[:7] = np.r_[phi, quat]  # (w, x, y, z)
    for name, value in angles.items():
        mdata.qpos[mj.joint(name).qposadr[0]] = value
    mujoco.mj_kinematics(mj, mdata)

    for frame, R, origin in _pose_checks(scene, q):
        placement = pdata.oMf[model.getFrameId(frame)]
        assert np.abs(placement.rotation - R).max() < 1e-12, frame
        assert np.abs(placement.translation - origin).max() < 1e-12, frame
        body = mdata.body(frame)
        assert np.abs(body.xmat.reshape(3, 3) - R).max() < 1e-12, frame
        assert np.abs(body.xpos - origin).max() < 1e-12, frame


# ---------------------------------------------------------------- gait-planner urdf


def test_urdf_command_writes_the_scenes_urdf(tmp_path, capsys):
    assert main(["urdf", "walker3d"]) == 0
    captured = capsys.readouterr()
    assert captured.out == _urdf("walker3d")[1]
    assert "torso's inertia" in captured.err and "nearest realisable" in captured.err
    out = tmp_path / "compass.urdf"
    assert main(["urdf", "compass", "--out", str(out)]) == 0
    assert out.read_text() == _urdf("compass")[1]
    assert str(out) in capsys.readouterr().out


def test_urdf_command_errors_are_one_line(tmp_path, capsys):
    assert main(["urdf", "no_such_scene"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gait-planner: error: unknown scene 'no_such_scene'")
    assert "walker3d" in err and err.count("\n") == 1
    assert main(["urdf", "compass", "--out", str(tmp_path / "missing" / "c.urdf")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gait-planner: error: cannot write") and err.count("\n") == 1
