"""The node plans for the robot on /robot_description (issue #37, item 4).

A URDF published on /robot_description (std_msgs/String, transient local, as
robot_state_publisher publishes it) is drafted by the node; a request with scene
"robot_description" plans it. One that cannot be planned is answered with the reason and
the node keeps serving. Slow: Unitree G1's description (example-robot-data) is planned and
answered in its own 29 joint names, its locked joints held, with its own URDF recorded.
"""

from __future__ import annotations

import pytest
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.ros.node import SERVICE, TOPIC_DESCRIPTION
from gait_planner_msgs.srv import PlanGait
from urdf_bipeds import biped

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


def _describe(make_node, executor, urdf: str):
    """A robot_state_publisher stand-in: `urdf` latched on /robot_description; a client."""
    publisher_node = make_node("robot_state_publisher")
    publisher_node.create_publisher(String, TOPIC_DESCRIPTION, LATCHED).publish(String(data=urdf))
    executor.add_node(publisher_node)
    return publisher_node.create_client(PlanGait, SERVICE)


def _call(client, spin_until, timeout: float, **fields) -> PlanGait.Response:
    """The answer to a request once the node has the description (the latched message
    and the service are discovered independently: the first request may beat it)."""
    assert spin_until(client.service_is_ready, timeout=20)
    for _ in range(50):
        future = client.call_async(PlanGait.Request(**fields))
        assert spin_until(future.done, timeout=timeout), "no answer from the node"
        if "no URDF received yet" not in future.result().message:
            break
        spin_until(lambda: False, timeout=0.2)
    return future.result()


@pytest.mark.timeout(120)
def test_an_unplannable_description_is_answered_with_its_reason(planner_node, make_node,
                                                                 executor, spin_until):
    planner_node()
    client = _describe(make_node, executor, biped(knee_type="prismatic"))
    answer = _call(client, spin_until, 60, scene="robot_description")
    assert not answer.success
    assert "cannot be planned" in answer.message and "left_knee_joint" in answer.message
    answer = _call(client, spin_until, 60, scene="no_such_scene")  # still serving
    assert not answer.success and "no_such_scene" in answer.message


@pytest.mark.slow
@pytest.mark.alone  # 12.6 GB at its peak, in the node's process: with nothing beside it
@pytest.mark.timeout(1500)
def test_g1_on_robot_description_is_planned_in_its_joint_names(
        planner_node, make_node, executor, spin_until, example_robots, tmp_path):
    path = example_robots / "g1_description/urdf/g1_29dof_rev_1_0.urdf"
    urdf = path.read_text()
    planner_node(compile_derivatives=False, robot_package_dirs=[str(example_robots.parents[1])])
    client = _describe(make_node, executor, urdf)
    answer = _call(client, spin_until, 1400, scene="robot_description", output_name="g1",
                   max_solve_time=1200.0)  # the node's default 60 s stops G1's refinement
    assert answer.success, answer.message
    joints = answer.trajectory.joint_names
    assert len(joints) == 29 and joints[:1] == ["left_hip_pitch_joint"]
    assert "waist_yaw_joint" in joints and "right_wrist_yaw_joint" in joints
    held = joints.index("waist_yaw_joint")
    assert all(p.positions[held] == 0.0 and p.velocities[held] == 0.0
               for p in answer.trajectory.points)
    rec = read_plan_mcap(answer.mcap_path)
    assert rec.urdf == urdf  # the robot's own description, not the draft's
    assert "on its URDF" in answer.continuous_dynamics and answer.continuous_dynamics.endswith("OK")
    assert (tmp_path / "robot_description/g1_29dof_rev_1_0/robot.urdf").read_text() == urdf
