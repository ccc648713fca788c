"""The real node: a PlanGait request plans (compass: ~1 s), records and publishes; bad
requests are answered with success = False and the node keeps serving."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from trajectory_msgs.msg import JointTrajectory

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.ros.node import (SERVICE, TOPIC_FORCES, TOPIC_STATE, TOPIC_TRAJECTORY,
                                   GaitPlannerNode)
from gait_planner_msgs.msg import ContactForces, MultibodyState
from gait_planner_msgs.srv import PlanGait

pytestmark = pytest.mark.timeout(300)


@pytest.fixture
def setup(ros_context, make_node, executor, tmp_path):
    server = GaitPlannerNode(context=ros_context, parameter_overrides=[
        Parameter("output_dir", value=str(tmp_path)),
        Parameter("allowed_output_dirs", value=[str(tmp_path)]),
        Parameter("default_scene", value="compass"), Parameter("warm_start_store", value=False),
        Parameter("prepare_scenes", value=[""])])  # no background preparation
    client_node = make_node("plan_client")
    received = {"trajectory": [], "state": [], "forces": []}
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    client_node.create_subscription(JointTrajectory, TOPIC_TRAJECTORY,
                                    received["trajectory"].append, 10)
    client_node.create_subscription(MultibodyState, TOPIC_STATE, received["state"].append, qos)
    client_node.create_subscription(ContactForces, TOPIC_FORCES, received["forces"].append, qos)
    executor.add_node(server)
    executor.add_node(client_node)
    client = client_node.create_client(PlanGait, SERVICE)
    yield client, received, tmp_path
    server.destroy_node()


def _call(client, spin_until, **fields) -> PlanGait.Response:
    assert spin_until(lambda: client.service_is_ready(), timeout=20)
    future = client.call_async(PlanGait.Request(**fields))
    assert spin_until(future.done, timeout=240), "no answer from the node"
    return future.result()


def test_plan_request_plans_records_and_publishes(setup, spin_until):
    client, received, folder = setup
    res = _call(client, spin_until, output_name="first")
    assert res.success, res.message
    assert res.solver_status == "Solve_Succeeded"
    assert Path(res.mcap_path) == folder / "first.mcap" and Path(res.mcap_path).is_file()
    nodes = len(res.trajectory.points)
    assert nodes > 3 and len(res.phase_scaling) == 1
    assert res.max_constraint_violation < 1e-9 and res.max_dynamics_residual < 1e-6
    assert math.isclose(res.step_length, 0.3)
    # the continuous-dynamics certificate travels in the response and in the recording
    assert res.continuous_torque_error < 0.002 and res.continuous_base_force < 1.0
    assert res.continuous_dynamics.endswith("OK"), res.continuous_dynamics
    recorded = read_plan_mcap(res.mcap_path).metadata
    assert float(recorded["continuous_torque_error"]) == res.continuous_torque_error
    assert spin_until(lambda: len(received["state"]) == nodes
                      and len(received["forces"]) == nodes and received["trajectory"])
    assert [m.node for m in received["state"]] == list(range(nodes))
    assert received["trajectory"][0].joint_names == ["hip"]
    # the rerun recording follows the answer, written by the node's helper process
    assert spin_until((folder / "first.rrd").is_file, timeout=120)
    assert _rerun_entities(folder / "first.rrd") >= {"/world/walker/leg_r", "/plan"}

    # a changed step length re-plans warm from the stored plan
    warm = _call(client, spin_until, step_length=0.32, output_name="second")
    assert warm.success, warm.message
    assert warm.iterations < res.iterations

    # two half cycles joined by the mirror: one trajectory, recorded and certified whole
    walk = _call(client, spin_until, step_length=0.32, steps=2, output_name="walk")
    assert walk.success, walk.message
    assert len(walk.trajectory.points) == 2 * (nodes - 2) + 2
    assert read_plan_mcap(walk.mcap_path).metadata["steps"] == "2"
    assert walk.continuous_dynamics.endswith("OK"), walk.continuous_dynamics
    assert spin_until((folder / "walk.rrd").is_file, timeout=120)
    assert sorted(p.name for p in folder.iterdir()) == [
        f"{stem}.{suffix}" for stem in ("first", "second", "walk") for suffix in ("mcap", "rrd")]


def _rerun_entities(path: Path) -> set[str]:
    """The entity paths of a rerun recording, read by rerun's own reader."""
    from rerun.chunk import RrdReader

    return {chunk.entity_path for chunk in RrdReader(path).stream()}


@pytest.mark.parametrize("fields, words", [
    ({"scene": "../etc/passwd"}, "bare names"),
    ({"scene": "no_such_scene"}, "available"),
    ({"output_name": "../outside"}, "output_name"),
    ({"cost": "speed"}, "unknown cost"),
    ({"step_length": -0.5}, "step_length must be > 0 m, or 0 for the scene's default, got -0.5"),
])
def test_bad_requests_are_refused_and_the_node_keeps_serving(setup, spin_until, fields, words):
    client, _, folder = setup
    res = _call(client, spin_until, **fields)
    assert not res.success
    assert words in res.message
    assert not list(folder.glob("*.mcap"))
    again = _call(client, spin_until, output_name="after_refusal")
    assert again.success, again.message


def _failing_once():
    """A Planner that raises an unexpected error in its first attempt (a bug, not bad input)."""
    from gait_planner.ocp.solve import Planner

    class FailingOnce(Planner):
        calls = 0

        def attempt(self, *args, **kwargs):
            self.calls += 1
            if self.calls == 1:
                raise RuntimeError("simulated fault inside the planner")
            return super().attempt(*args, **kwargs)

    return FailingOnce()


def test_an_unexpected_error_is_answered_and_the_node_keeps_serving(
        ros_context, make_node, executor, tmp_path, spin_until):
    server = GaitPlannerNode(context=ros_context, planner=_failing_once(), parameter_overrides=[
        Parameter("output_dir", value=str(tmp_path)),
        Parameter("allowed_output_dirs", value=[str(tmp_path)]),
        Parameter("default_scene", value="compass"),
        Parameter("prepare_on_start", value=False)])
    client_node = make_node("fault_client")
    executor.add_node(server)
    executor.add_node(client_node)
    client = client_node.create_client(PlanGait, SERVICE)
    try:
        res = _call(client, spin_until)
        assert not res.success
        assert "internal error (RuntimeError): simulated fault" in res.message
        assert not list(tmp_path.glob("*"))
        again = _call(client, spin_until, output_name="after_fault")
        assert again.success, again.message
    finally:
        server.destroy_node()
