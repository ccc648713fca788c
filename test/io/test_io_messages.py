"""Message layouts of a plan: field names from the definitions, lengths, stamps, values."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from gait_planner.io import messages
from gait_planner.model.angles import conjugate_torques
from gait_planner.io.ros_definitions import STANDARD_DEFINITIONS

from io_msgdef import fields, msg_fields, share_msg_text, srv_response_fields

START_NS = 1_700_000_000_123_456_789  # = the start_ns fixture

NS = 1_000_000_000


def _stamp(header) -> int:
    return header["stamp"]["sec"] * NS + header["stamp"]["nanosec"]


def _std(name: str) -> set[str]:
    return set(fields(STANDARD_DEFINITIONS[name]))


def test_multibody_state_fields_and_values(result):
    states = messages.multibody_states(result, START_NS)
    assert len(states) == result.n_nodes
    nb = len(result.scene.bodies)
    for n, state in enumerate(states):
        assert set(state) == set(msg_fields("MultibodyState"))
        assert set(state["header"]) == _std("std_msgs/Header")
        assert state["header"]["frame_id"] == "world"
        assert state["node"] == n
        assert state["time"] == pytest.approx(result.times[n] - result.times[0], abs=1e-15)
        assert _stamp(state["header"]) == START_NS + round((result.times[n] - result.times[0]) * NS)
        assert state["body_names"] == list(result.body_names)
        assert len(state["q"]) == len(state["generalized_force"]) == 12 * nb
        assert np.array_equal(state["q"], result.q[n])
        assert state["phase"] == result.phases[n]
        assert state["active_contacts"] == list(result.active_contacts[n])
        assert all(type(v) is float for v in state["q"])


def test_contact_forces_only_active_with_world_points(result):
    scene = result.scene
    for n, msg in enumerate(messages.contact_forces(result, START_NS)):
        assert set(msg) == set(msg_fields("ContactForces"))
        assert msg["contact_names"] == list(result.active_contacts[n])
        assert len(msg["points"]) == len(msg["forces"]) == len(msg["contact_names"])
        for name, point, force in zip(msg["contact_names"], msg["points"], msg["forces"]):
            assert set(point) == set(force) == {"x", "y", "z"}
            contact = scene.contact(name)
            i = scene.body_index(contact.body)
            phi, D = result.q[n, 12 * i:12 * i + 3], result.q[n, 12 * i + 3:12 * i + 12]
            X = scene.body(contact.body).points[contact.point]
            expected = phi + X[0] * D[0:3] + X[1] * D[3:6] + X[2] * D[6:9]
            assert np.allclose([point["x"], point["y"], point["z"]], expected, atol=1e-15)
            assert [force["x"], force["y"], force["z"]] == list(result.contact_forces[name][n])
        assert _stamp(msg["header"]) == messages.node_stamps_ns(result, START_NS)[n]


def test_foot_wrench_is_the_sum_of_point_forces_moments_and_roll(result):
    """Each foot's wrench carries the net force, the moments of its point forces about the
    wrench point plus the full contact's roll moment M (d2 x e_z), and a centre of pressure
    about which the horizontal moment vanishes."""
    scene, full_nodes = result.scene, 0
    for n, msg in enumerate(messages.contact_forces(result, START_NS)):
        names = msg["contact_names"]
        feet = [b.name for b in scene.bodies if any(scene.contact(c).body == b.name for c in names)]
        assert msg["wrench_bodies"] == feet
        for body, r, w, cop in zip(feet, msg["wrench_points"], msg["wrenches"],
                                   msg["centers_of_pressure"]):
            r = np.array([r["x"], r["y"], r["z"]])
            F = np.array([w["force"][a] for a in "xyz"])
            M = np.array([w["torque"][a] for a in "xyz"])
            cop = np.array([cop["x"], cop["y"], cop["z"]])
            mine = [i for i, c in enumerate(names) if scene.contact(c).body == body]
            points = [np.array([msg["points"][i][a] for a in "xyz"]) for i in mine]
            forces = [np.array([msg["forces"][i][a] for a in "xyz"]) for i in mine]
            assert np.allclose(r, np.mean(points, axis=0), atol=1e-15)
            assert np.allclose(F, np.sum(forces, axis=0), atol=1e-12)
            i = scene.body_index(body)
            d2 = result.q[n, 12 * i + 6:12 * i + 9]
            roll = result.roll_moments[body][n]
            full_nodes += roll != 0
            expected = sum(np.cross(p - r, f) for p, f in zip(points, forces)) + \
                roll * np.cross(d2, [0.0, 0.0, 1.0])
            assert np.allclose(M, expected, atol=1e-12)
            if F[2] > 0:  # the moment about the centre of pressure has no horizontal part
                assert np.allclose((M - np.cross(cop - r, F))[:2], 0.0, atol=1e-9)
                assert cop[2] == pytest.approx(r[2])
    assert full_nodes > 0  # the synthetic result has full contacts with a roll moment


def test_joint_trajectory_one_point_per_node_and_effort_convention(result):
    traj = messages.joint_trajectory(result, START_NS)
    assert set(traj) == _std("trajectory_msgs/JointTrajectory")
    assert traj["joint_names"] == list(result.joint_angle_names)
    assert _stamp(traj["header"]) == START_NS
    assert len(traj["points"]) == result.n_nodes
    na = len(result.joint_angle_names)
    for n, point in enumerate(traj["points"]):
        assert set(point) == _std("trajectory_msgs/JointTrajectoryPoint")
        assert len(point["positions"]) == len(point["velocities"]) == len(point["effort"]) == na
        assert len(point["accelerations"]) == na
        assert np.array_equal(point["positions"], result.joint_angles[n])
        assert np.array_equal(point["velocities"], result.joint_velocities[n])
        assert np.array_equal(point["accelerations"], result.joint_accelerations[n])
        # conjugate torques of tau of the interval starting at the node; the last node
        # repeats the last interval
        tau = result.tau[min(n, len(result.tau) - 1)]
        expected = conjugate_torques(result.scene, result.joint_angles[n], tau)
        assert np.array_equal(point["effort"], expected)
        t = point["time_from_start"]
        assert t["sec"] * NS + t["nanosec"] == round((result.times[n] - result.times[0]) * NS)


def test_efforts_are_conjugate_to_the_joint_angles(result):
    """effort . angle rate equals the joint power tau . omega_rel of the raw couples."""
    from gait_planner.model.angles import spherical_rotation

    rng = np.random.default_rng(3)
    efforts = messages.node_efforts(result)
    for n in range(result.n_nodes - 1):
        angles, rates = result.joint_angles[n], rng.normal(size=efforts.shape[1])
        tau = result.tau[n]
        power, i = 0.0, 0
        for joint in result.scene.joints:
            if joint.dof == 3:
                p, r, y = angles[i : i + 3]
                eps = 1e-6  # omega_rel by central differences along the rates, parent frame
                R0 = spherical_rotation(p, r, y)
                R1 = spherical_rotation(*(angles[i : i + 3] + eps * rates[i : i + 3]))
                Rm = spherical_rotation(*(angles[i : i + 3] - eps * rates[i : i + 3]))
                W = (R1 - Rm) @ R0.T / (2 * eps)
                omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
                power += tau[i : i + 3] @ omega
            else:
                power += tau[i] * rates[i]
            i += joint.dof
        assert efforts[n] @ rates == pytest.approx(power, rel=1e-8, abs=1e-8)


def test_joint_states_match_trajectory(result):
    states = messages.joint_states(result, START_NS)
    traj = messages.joint_trajectory(result, START_NS)
    assert len(states) == result.n_nodes
    for n, (state, point) in enumerate(zip(states, traj["points"])):
        assert set(state) == _std("sensor_msgs/JointState")
        assert state["name"] == list(result.joint_angle_names)
        assert state["position"] == point["positions"]
        assert state["velocity"] == point["velocities"]
        assert state["effort"] == point["effort"]
        assert _stamp(state["header"]) == messages.node_stamps_ns(result, START_NS)[n]


def test_stamps_are_exact_nanoseconds_and_increasing(result):
    stamps = messages.node_stamps_ns(result, START_NS)
    assert stamps[0] == START_NS
    assert all(b > a for a, b in zip(stamps, stamps[1:]))
    assert messages.time_msg(START_NS) == {"sec": START_NS // NS, "nanosec": START_NS % NS}
    with pytest.raises(ValueError):
        messages.time_msg(-1)


def test_plan_response_fields_match_the_service_definition(result):
    """The plan's fields and the walk's (filled after a walk, `walk_response_fields`) make
    up the response, each field once."""
    fields_ = messages.plan_response_fields(result, "/tmp/plan.mcap", START_NS)
    walk = messages.walk_response_fields(0, None, "off")
    assert not set(fields_) & set(walk)
    assert set(fields_) | set(walk) == set(srv_response_fields("PlanGait"))
    assert fields_["mcap_path"] == "/tmp/plan.mcap"
    assert fields_["cost"] == result.cost_value and fields_["iterations"] == 42
    assert fields_["phase_scaling"] == list(result.phase_scaling)
    assert messages.plan_response_fields(result, None)["mcap_path"] == ""


def test_robot_description_is_the_urdf(result):
    assert messages.robot_description(result)["data"].startswith("<?xml")


def test_embedded_standard_definitions_match_the_installed_ones():
    """The field lines of STANDARD_DEFINITIONS equal the installed .msg files where present
    (tf2_msgs has no wheel and is checked by hand against ROS 2's definition)."""
    checked = 0
    for name, text in STANDARD_DEFINITIONS.items():
        installed = share_msg_text(*name.split("/"))
        if installed is None:
            continue
        assert fields(text) == fields(installed), name
        checked += 1
    if checked == 0:
        pytest.skip("no standard .msg files installed in this environment")
    assert fields(STANDARD_DEFINITIONS["tf2_msgs/TFMessage"]) == {
        "transforms": "geometry_msgs/TransformStamped[]"}


def test_check_result_rejects_nan_and_bad_shapes(result, make_result):
    q = result.q.copy()
    q[2, 5] = np.nan
    with pytest.raises(ValueError, match="q contains NaN"):
        messages.check_result(make_result(q=q))
    with pytest.raises(ValueError, match="tau has shape"):
        messages.check_result(make_result(tau=result.tau[:-1]))
    times = result.times.copy()
    times[3] = times[2]
    with pytest.raises(ValueError, match="strictly increasing"):
        messages.check_result(make_result(times=times))
    messages.check_result(result)


def test_quaternion_of_rotation_matrices():
    rng = np.random.default_rng(1)
    for _ in range(200):
        A, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        R = A * np.sign(np.linalg.det(A))
        q = messages.quaternion_msg(R)
        x, y, z, w = q["x"], q["y"], q["z"], q["w"]
        back = np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        assert np.allclose(back, R, atol=1e-14) and w >= 0
    # rotations by pi (trace = -1) take the diagonal branches
    for R in (np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])):
        q = messages.quaternion_msg(R)
        assert np.isclose(np.linalg.norm([q["x"], q["y"], q["z"], q["w"]]), 1.0)


# ---------------------------------------------------------------------------- fill_message

needs_msgs = pytest.mark.skipif(
    importlib.util.find_spec("trajectory_msgs") is None
    or importlib.util.find_spec("sensor_msgs") is None,
    reason="ROS message packages (ros-trajectory-msgs, ros-sensor-msgs) not installed")


@needs_msgs
def test_fill_message_builds_rclpy_messages(result):
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String
    from trajectory_msgs.msg import JointTrajectory

    traj = messages.fill_message(JointTrajectory(), messages.joint_trajectory(result, START_NS))
    assert list(traj.joint_names) == list(result.joint_angle_names)
    assert len(traj.points) == result.n_nodes
    assert np.array_equal(traj.points[3].effort, messages.node_efforts(result)[3])
    last = traj.points[-1].time_from_start
    assert last.sec * NS + last.nanosec == round((result.times[-1] - result.times[0]) * NS)
    assert traj.header.stamp.sec == START_NS // NS
    state = messages.fill_message(JointState(), messages.joint_states(result, START_NS)[2])
    assert np.array_equal(state.position, result.joint_angles[2])
    text = messages.fill_message(String(), messages.robot_description(result))
    assert text.data.startswith("<?xml")
    with pytest.raises(AttributeError, match="no field 'nonsense'"):
        messages.fill_message(String(), {"nonsense": 1})


@pytest.mark.skipif(importlib.util.find_spec("gait_planner_msgs") is None,
                    reason="gait_planner_msgs is not built/installed (make setup builds it)")
def test_fill_message_builds_our_messages(result):
    from gait_planner_msgs.msg import ContactForces, MultibodyState
    from gait_planner_msgs.srv import PlanGait

    state = messages.fill_message(MultibodyState(), messages.multibody_states(result, START_NS)[1])
    assert np.array_equal(state.q, result.q[1])
    forces = messages.fill_message(ContactForces(), messages.contact_forces(result, START_NS)[1])
    assert list(forces.contact_names) == list(result.active_contacts[1])
    response = messages.fill_message(PlanGait.Response(),
                                     messages.plan_response_fields(result, "/x.mcap"))
    assert response.mcap_path == "/x.mcap" and len(response.trajectory.points) == result.n_nodes


def test_a_requests_start_fields_become_a_start_state():
    """`requested_start` reads PlanGait's start fields (attributes, as rclpy messages have
    them): "" is the periodic gait, "state" the request's state with its stamp, "robot"
    the node's latest joint state and world -> root transform, refused naming the frame
    while that has not arrived, "standing" the scene's standing pose at rest (refused for a
    scene that declares no start phases); other starts are refused."""
    from types import SimpleNamespace as Msg

    from gait_planner.io.messages import WORLD_FRAME, frame_tree, quaternion_msg, requested_start
    from gait_planner.model.angles import angle_names, configuration, joint_angles
    from gait_planner.model.loader import load_scene
    from gait_planner.ocp.transition import StartError
    from gait_planner.request import RequestError

    scene = load_scene("walker3d")
    q = configuration(scene)
    root = scene.body_index(frame_tree(scene).root)
    xyz = lambda v: Msg(x=float(v[0]), y=float(v[1]), z=float(v[2]))  # noqa: E731
    turn = quaternion_msg(q[12 * root + 3:12 * root + 12].reshape(3, 3).T)
    rotation = Msg(**turn)
    state = Msg(name=list(angle_names(scene)), position=list(joint_angles(scene, q)),
                velocity=[], header=Msg(stamp=Msg(sec=7, nanosec=5)))
    still = Msg(linear=xyz([0, 0, 0]), angular=xyz([0, 0, 0]))
    request = Msg(start="state", state=state, root_twist=still, root_pose=Msg(
        position=xyz(q[12 * root:12 * root + 3]), orientation=rotation))
    start, stamp = requested_start(scene, request)
    assert np.abs(start.q - q).max() < 1e-12 and stamp == 7_000_000_005
    assert requested_start(scene, Msg(start="")) == (None, None)
    robot = Msg(start="robot", root_twist=still)
    with pytest.raises(StartError, match="no /joint_states received yet"):
        requested_start(scene, robot)
    with pytest.raises(StartError, match="does not subscribe to /tf"):
        requested_start(scene, robot, state)
    with pytest.raises(StartError, match=rf"no transform {WORLD_FRAME} -> {scene.root.body} "
                                         r"received on /tf yet \(from world: base\)"):
        requested_start(scene, robot, state, {"base": None})
    held = {scene.root.body: Msg(transform=Msg(translation=xyz(q[12 * root:12 * root + 3]),
                                               rotation=rotation))}
    start, stamp = requested_start(scene, robot, state, held)
    assert np.abs(start.q - q).max() < 1e-12 and stamp == 7_000_000_005
    standing, stamp = requested_start(scene, Msg(start="standing"))
    assert standing.standing and stamp is None and not standing.momentum.any()
    assert np.abs(standing.q - q).max() < 1e-12  # the scene's standing pose
    with pytest.raises(StartError, match="'compass' declares no start from standing"):
        requested_start(load_scene("compass"), Msg(start="standing"))
    with pytest.raises(RequestError, match="start must be"):
        requested_start(scene, Msg(start="walking"))
