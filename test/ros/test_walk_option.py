"""Walking each plan after it is made (issue #25): the node's parameter walk_steps (checked
when set; the walk runs in the plan thread as the action phase "walking", told at each half
cycle's end, a cancel is refused then, and the answer's walk_* fields say how it went, also
when the walk cannot run) and `gait-planner plan/run --walk K` (a line per half cycle). The
walks are of walker2d's default plan, which the reference controller walks
(test/walk/test_walk.py); compass has no feet to walk on."""

from __future__ import annotations

import json
import math

import pytest
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.exceptions import InvalidParameterValueException
from rclpy.parameter import Parameter

from gait_planner.cli import main
from gait_planner.ros.action_server import ACTION
from gait_planner.ros.client import send_goal
from gait_planner.ros.node import SERVICE, GaitPlannerNode
from gait_planner_msgs.action import PlanGait as PlanGaitAction
from gait_planner_msgs.srv import PlanGait

pytestmark = pytest.mark.timeout(300)

NO_FEET = "has no foot with two contact points"  # gait_planner.walk.walk_plan's reason


# ---------------------------------------------------------------------- the parameter


def test_walk_steps_is_off_by_default_and_declared_with_its_range(planner_node):
    node = planner_node()
    assert node.get_parameter("walk_steps").value == 0
    descriptor = node.describe_parameter("walk_steps")
    assert "0 = no walk" in descriptor.description
    assert (descriptor.integer_range[0].from_value, descriptor.integer_range[0].to_value) == (0, 100)


@pytest.mark.parametrize("value, words", [
    (-1, "Parameter walk_steps out of range. Min: 0, Max: 100, value: -1"),
    (101, "Parameter walk_steps out of range. Min: 0, Max: 100, value: 101"),
    (2.5, "type"),
])
def test_a_bad_walk_steps_is_refused_with_the_reason_and_the_old_value_stays(
        planner_node, value, words):
    node = planner_node(walk_steps=3)
    result = node.set_parameters([Parameter("walk_steps", value=value)])[0]
    assert not result.successful and words in result.reason, result.reason
    assert node.get_parameter("walk_steps").value == 3
    assert node.set_parameters([Parameter("walk_steps", value=100)])[0].successful


def test_a_bad_walk_steps_at_start_stops_the_node(ros_context, tmp_path):
    with pytest.raises(InvalidParameterValueException, match="walk_steps"):
        GaitPlannerNode(context=ros_context, parameter_overrides=[
            Parameter("output_dir", value=str(tmp_path)),
            Parameter("allowed_output_dirs", value=[str(tmp_path)]),
            Parameter("prepare_on_start", value=False), Parameter("walk_steps", value=-2)])


# ---------------------------------------------------------------------- the node


@pytest.fixture
def clients(make_node, executor):
    """(action client, service client) of the node gait_planner."""
    node = make_node("walk_option_test")
    executor.add_node(node)
    return ActionClient(node, PlanGaitAction, ACTION), node.create_client(PlanGait, SERVICE)


def test_the_node_walks_each_plan_and_answers_how_it_went(
        planner_node, clients, spin_until, wait_for_feedback, tmp_path):
    planner_node(default_scene="walker2d", walk_steps=3)
    action, service = clients
    assert spin_until(action.server_is_ready, 20), f"{ACTION} not discovered"
    feedback: list = []
    handle = send_goal(action, PlanGaitAction.Goal(output_name="walked"),
                       lambda: spin_until(lambda: False, 0.05),
                       feedback_callback=lambda m: feedback.append(m.feedback))
    assert handle.accepted
    # the walk follows the recording, in the plan thread; a cancel is refused while it runs
    wait_for_feedback(feedback, lambda f: f.phase == "walking", timeout=240)
    cancel = handle.cancel_goal_async()
    assert spin_until(cancel.done) and not cancel.result().goals_canceling
    future = handle.get_result_async()
    assert spin_until(future.done, 240), "no result"
    answer = future.result()
    assert answer.status == GoalStatus.STATUS_SUCCEEDED, answer.result.message
    result = answer.result
    assert result.success and result.mcap_path == str(tmp_path / "walked.mcap")
    phases = [f.phase for f in feedback]
    assert phases.index("walking") > phases.index("recording")
    # then each half cycle's end, in order; the heartbeat repeats the last
    assert list(dict.fromkeys(phases[phases.index("walking"):])) == [
        "walking", *(f"walking ({k} of 3 half cycles done)" for k in (1, 2, 3))]
    # walker2d's default plan walks: every half cycle asked, with the feedback a fraction of
    # the plan's torque (a walk with the plan's torques alone falls: test/walk/test_walk.py)
    assert (result.walk_steps, result.walk_half_cycles) == (3, 3), result.walk_stopped
    assert result.walk_stopped == "completed"
    assert 0.0 < result.walk_feedback_share < 2.0
    # walker2d's default plan touches nowhere the plan has a foot in the air (2026-11-29)
    assert (result.walk_touches, result.walk_first_touch) == (0, "")

    # a plan that cannot be walked (compass: no feet) is still a plan; the node keeps serving
    assert spin_until(service.service_is_ready, 20)
    call = service.call_async(PlanGait.Request(scene="compass", output_name="footless"))
    assert spin_until(call.done, 240), "no answer"
    footless = call.result()
    assert footless.success and footless.mcap_path == str(tmp_path / "footless.mcap")
    assert footless.walk_steps == 3 and footless.walk_half_cycles == 0
    assert footless.walk_stopped.startswith("not walked: ") and NO_FEET in footless.walk_stopped
    assert math.isnan(footless.walk_feedback_share)


def test_without_walk_steps_the_walk_fields_stay_empty(planner_node, clients, spin_until):
    planner_node(default_scene="compass")
    _, service = clients
    assert spin_until(service.service_is_ready, 20)
    call = service.call_async(PlanGait.Request(output_name="plain"))
    assert spin_until(call.done, 240), "no answer"
    answer = call.result()
    assert answer.success, answer.message
    assert (answer.walk_steps, answer.walk_half_cycles, answer.walk_stopped,
            answer.walk_touches, answer.walk_first_touch) == (0, 0, "", 0, "")


# ---------------------------------------------------------------------- the command line


def test_plan_walk_walks_the_recorded_plan_and_prints_the_summary(tmp_path, capsys):
    out = tmp_path / "w2d.mcap"
    assert main(["plan", "--scene", "walker2d", "--out", str(out), "--no-rrd",
                 "--walk", "2"]) == 0
    printed = capsys.readouterr()
    assert f"mcap                      {out}" in printed.out
    assert f"walker2d ({out}): walked 2 of 2 half cycles in " in printed.out
    assert "feedback share" in printed.out and "torso drift per half cycle" in printed.out
    assert "joint RMS per half cycle (deg): " in printed.out
    assert ("walking the plan 2 half cycles in MuJoCo ...\n-- walking (1 of 2 half cycles done)"
            "\n-- walking (2 of 2 half cycles done)\n") in printed.err

    ran = tmp_path / "run.mcap"  # `run` (what `make run` calls) walks the same way
    assert main(["run", "--scene", "walker2d", "--out", str(ran), "--no-rrd", "--no-viewer",
                 "--walk", "1"]) == 0
    assert f"walker2d ({ran}): walked 1 of 1 half cycles in " in capsys.readouterr().out

    assert main(["plan", "--scene", "walker2d", "--out", str(out), "--no-rrd", "--walk", "1",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] and data["walk"]["recording"] == data["mcap"]
    assert data["walk"]["steps"] == 1 and data["walk"]["half_cycles_walked"] == 1
    assert data["walk"]["stopped"] == "completed"


def test_plan_walk_refuses_a_negative_count_and_a_scene_without_feet(tmp_path, capsys):
    assert main(["plan", "--scene", "compass", "--out", str(tmp_path / "c.mcap"),
                 "--walk", "-1"]) == 2
    assert capsys.readouterr().err.strip() == (
        "gait-planner: error: --walk must be a number of half cycles >= 0 (0: no walk), got -1")
    assert not list(tmp_path.iterdir())  # refused before planning

    assert main(["plan", "--scene", "compass", "--out", str(tmp_path / "c.mcap"), "--no-rrd",
                 "--walk", "1"]) == 2
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert error.startswith("gait-planner: error: --walk: cannot walk the recorded plan: ")
    assert NO_FEET in error and (tmp_path / "c.mcap").is_file()
