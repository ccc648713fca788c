"""PlanGait's start fields on the real node (issue #62): a transition from a state given in
the request (service) or measured from the robot's /joint_states and /tf (action), onto
walker2d's gait (derivatives compiled, `make setup`); bad starts are answered at once with
what is wrong, and the node keeps serving."""

from __future__ import annotations

import time

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Pose, TransformStamped, Twist
from rclpy.action import ActionClient
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.io.messages import WORLD_FRAME, frame_tree, quaternion_msg
from gait_planner.model.loader import load_scene
from gait_planner.ros.action_server import ACTION
from gait_planner.ros.client import send_goal
from gait_planner.ros.node import SERVICE, TOPIC_JOINT_STATES, TOPIC_TF
from gait_planner_msgs.action import PlanGait as PlanGaitAction
from gait_planner_msgs.srv import PlanGait

pytestmark = pytest.mark.timeout(300)

STAMP = Time(sec=1_700_000_042, nanosec=250_000_000)  # the measured state's time
FAST = 2.0  # s: a refusal arrives within this


def _call(client, spin_until, timeout=240.0, **fields) -> tuple[PlanGait.Response, float]:
    """The node's answer to a PlanGait request and its round trip in s."""
    assert spin_until(client.service_is_ready, timeout=20)
    began = time.monotonic()
    future = client.call_async(PlanGait.Request(**fields))
    assert spin_until(future.done, timeout=timeout), "no answer from the node"
    return future.result(), time.monotonic() - began


def _gait(client, spin_until):
    """walker2d's gait of three half cycles, cold, and its recording."""
    res, _ = _call(client, spin_until, steps=3, cold_start=True, output_name="gait")
    assert res.success, res.message
    return res, read_plan_mcap(res.mcap_path)


def _measured(res, rec) -> tuple[JointState, Pose, Twist, int]:
    """The state a robot walking the gait would publish where its third half cycle begins
    (the first stance again): joint states of the trajectory's point there, the root's pose
    and its twist (central differences of the recording). Also the node's index."""
    n = 2 * (int(rec.metadata["half_cycle_nodes"]) - 2)
    point = res.trajectory.points[n]
    state = JointState(name=list(res.trajectory.joint_names), position=list(point.positions),
                       velocity=list(point.velocities))
    state.header.stamp = STAMP
    scene = load_scene("walker2d")
    i = scene.body_index(frame_tree(scene).root)
    q, t = np.asarray(rec.q, float), np.asarray(rec.times, float)
    D = q[n, 12 * i + 3:12 * i + 12].reshape(3, 3).T
    D_dot = ((q[n + 1] - q[n - 1]) / (t[n + 1] - t[n - 1]))[12 * i + 3:12 * i + 12].reshape(3, 3).T
    W = D_dot @ D.T
    linear = (q[n + 1] - q[n - 1])[12 * i:12 * i + 3] / (t[n + 1] - t[n - 1])
    pose, twist = Pose(), Twist()
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in q[n, 12 * i:12 * i + 3])
    rotation = quaternion_msg(D)
    pose.orientation.x, pose.orientation.y = rotation["x"], rotation["y"]
    pose.orientation.z, pose.orientation.w = rotation["z"], rotation["w"]
    twist.linear.x, twist.linear.y, twist.linear.z = (float(v) for v in linear)
    twist.angular.x, twist.angular.y, twist.angular.z = W[2, 1], W[0, 2], W[1, 0]
    return state, pose, twist, n


def _starts_there(res, state: JointState, rec, n: int) -> None:
    """The answer's first point is the measured state, stamped with its time, and its
    recording's first node is the gait's node n (the transition's node 0 is the start)."""
    assert res.success, res.message
    assert res.trajectory.header.stamp == STAMP
    first = res.trajectory.points[0]
    assert list(res.trajectory.joint_names) == list(state.name)
    assert np.abs(np.subtract(first.positions, state.position)).max() < 1e-9
    joined = read_plan_mcap(res.mcap_path)
    assert np.abs(np.asarray(joined.q[0]) - np.asarray(rec.q[n])).max() < 1e-9
    assert joined.metadata["transition_half_cycles"] == "2"


def test_a_service_request_from_a_given_state_starts_there(planner_node, make_node, executor,
                                                          spin_until):
    planner_node(default_scene="walker2d", compile_derivatives=True)
    node = make_node("start_state_client")
    executor.add_node(node)
    client = node.create_client(PlanGait, SERVICE)
    res, rec = _gait(client, spin_until)
    state, pose, twist, n = _measured(res, rec)

    refusals = {
        "elbow_l": dict(start="state", state=JointState(
            name=state.name[:-1] + ["elbow_l"], position=state.position)),
        "no /joint_states received yet": dict(start="robot"),
        "transition_half_cycles must be 1 to 4": dict(start="state", state=state,
                                                      transition_half_cycles=5),
    }
    for words, fields in refusals.items():
        refused, seconds = _call(client, spin_until, root_pose=pose, **fields)
        assert not refused.success and words in refused.message, (words, refused.message)
        assert seconds < FAST, (words, seconds)

    res, seconds = _call(client, spin_until, start="state", state=state, root_pose=pose,
                         root_twist=twist, output_name="from_state")
    _starts_there(res, state, rec, n)
    print(f"service round trip of the transition from a given state: {seconds:.2f} s, "
          f"{res.iterations} iterations, {len(res.trajectory.points)} nodes")


def test_an_action_goal_from_the_robot_starts_at_its_measured_state(
        planner_node, make_node, executor, spin_until):
    server = planner_node(default_scene="walker2d", compile_derivatives=True)
    node = make_node("start_robot_client")
    executor.add_node(node)
    client = node.create_client(PlanGait, SERVICE)
    res, rec = _gait(client, spin_until)
    state, pose, twist, n = _measured(res, rec)

    transform = TransformStamped(child_frame_id=frame_tree(load_scene("walker2d")).root)
    transform.header.frame_id, transform.header.stamp = WORLD_FRAME, STAMP
    transform.transform.translation.x = pose.position.x
    transform.transform.translation.y = pose.position.y
    transform.transform.translation.z = pose.position.z
    transform.transform.rotation = pose.orientation
    joints = node.create_publisher(JointState, TOPIC_JOINT_STATES, 10)
    tf = node.create_publisher(TFMessage, TOPIC_TF, 100)
    node.create_timer(0.05, lambda: (joints.publish(state),
                                     tf.publish(TFMessage(transforms=[transform]))))
    assert spin_until(lambda: server._joint_state is not None  # noqa: SLF001
                      and transform.child_frame_id in server._transforms)  # noqa: SLF001

    action = ActionClient(node, PlanGaitAction, ACTION)
    assert spin_until(action.server_is_ready, 20), f"{ACTION} not discovered"
    began = time.monotonic()
    handle = send_goal(action, PlanGaitAction.Goal(start="robot", root_twist=twist,
                                                   output_name="from_robot"),
                       lambda: spin_until(lambda: False, 0.05))
    assert handle.accepted
    future = handle.get_result_async()
    assert spin_until(future.done, 240), "no result"
    _starts_there(future.result().result, state, rec, n)
    print(f"action round trip of the transition from the robot: "
          f"{time.monotonic() - began:.2f} s")
