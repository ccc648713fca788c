"""The URDF and the /tf frames: structure, inertia, and exact poses of every body from q."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from gait_planner.io import messages
from gait_planner.io.urdf import body_shapes, kinematic_tree, scene_to_urdf
from gait_planner.model.scene import JointType

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
        inertia = link.find("inertial/inertia")
        assert [float(inertia.get(k)) for k in ("ixx", "iyy", "izz")] == list(body.inertia)
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
    assert all(links[name].find("inertial") is None for name in massless)
    assert {c.name for c in scene.contacts} <= massless


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
