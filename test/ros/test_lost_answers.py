"""Answers that cannot be sent. Fast DDS refuses to send an answer to a client whose response
reader the node has not discovered 100 ms after the request ("client will not receive
response"), which can happen to a request sent as soon as the client discovered the node
(seen in CI: rclpy 9.1.2 warned "failed to send response (timeout)", the goal ran, and its
client waited for an acceptance that never came). Injected here, both ways rclpy can meet
it: the answer silently not sent (the goal runs: the client takes its feedback as the
acceptance), or an RCLError (rclpy drops the goal: its hold on the node lapses and the
client's next goal is planned; a service answer: the node serves on)."""

from __future__ import annotations

import pytest
import rclpy.service
from rclpy.action import ActionClient
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

from gait_planner.ros.action_server import ACTION
from gait_planner.ros.client import send_goal
from gait_planner.ros.node import SERVICE
from gait_planner.ros.worker import RESERVATION_TIMEOUT
from gait_planner_msgs.action import PlanGait as PlanGaitAction
from gait_planner_msgs.srv import PlanGait

pytestmark = pytest.mark.timeout(120)


def _fail_once(monkeypatch, owner, name: str) -> list:
    """Make ``owner.name`` raise Fast DDS's RCLError on its first call; returns the list of
    calls that failed."""
    original, failed = getattr(owner, name), []

    def send(self, *args):
        if not failed:
            failed.append(args)
            raise _rclpy.RCLError("client will not receive response")
        return original(self, *args)

    monkeypatch.setattr(owner, name, send)
    return failed


def test_a_goal_whose_acceptance_is_lost_runs_and_its_client_follows_it(
        monkeypatch, planner_node, make_node, executor, spin_until):
    planner_node(default_scene="compass", compile_derivatives=False)
    original, skipped = _rclpy.ActionServer.send_goal_response, []

    def send(self, *args):  # rclpy's timeout: warned, nothing sent, the goal goes on
        if not skipped:
            skipped.append(args)
            return None
        return original(self, *args)

    monkeypatch.setattr(_rclpy.ActionServer, "send_goal_response", send)
    client = make_node("unanswered_goal_client")
    executor.add_node(client)
    action = ActionClient(client, PlanGaitAction, ACTION)
    assert spin_until(action.server_is_ready, 20)
    notes: list[str] = []
    feedback: list = []
    handle = send_goal(action, PlanGaitAction.Goal(output_name="unanswered"),
                       lambda: spin_until(lambda: False, 0.05), feedback_callback=feedback.append,
                       note=notes.append)
    assert len(skipped) == 1 and handle.accepted and feedback
    assert len(notes) == 1 and "lost" in notes[0], notes  # one goal sent, followed
    result = handle.get_result_async()
    assert spin_until(result.done, 60)
    assert result.result().result.success, result.result().result.message


def test_a_dropped_goal_lapses_and_the_next_goal_is_planned(
        monkeypatch, planner_node, make_node, executor, spin_until):
    planner_node(default_scene="compass", compile_derivatives=False)
    failed = _fail_once(monkeypatch, _rclpy.ActionServer, "send_goal_response")
    client = make_node("lost_goal_client")
    executor.add_node(client)
    action = ActionClient(client, PlanGaitAction, ACTION)
    assert spin_until(action.server_is_ready, 20)
    notes: list[str] = []
    handle = send_goal(action, PlanGaitAction.Goal(output_name="lost"),
                       lambda: spin_until(lambda: False, 0.05), note=notes.append,
                       wait=RESERVATION_TIMEOUT + 1.0)
    assert len(failed) == 1 and len(notes) == 1, notes
    assert handle.accepted  # not "busy": the first goal's hold lapsed
    result = handle.get_result_async()
    assert spin_until(result.done, 60)
    assert result.result().result.success, result.result().result.message


def test_a_service_answer_that_cannot_be_sent_does_not_end_the_service(
        monkeypatch, planner_node, make_node, executor, spin_until):
    planner_node(default_scene="compass", compile_derivatives=False)
    failed = _fail_once(monkeypatch, rclpy.service.Service, "send_response")
    node = make_node("lost_answer_client")
    executor.add_node(node)
    client = node.create_client(PlanGait, SERVICE)
    assert spin_until(client.service_is_ready, 20)
    bad = PlanGait.Request(scene="no_such_scene")  # answered at once, refused
    lost = client.call_async(bad)
    assert not spin_until(lost.done, 2.0) and len(failed) == 1
    # the executor raises the lost answer's error when the next request wakes it, after it
    # has handed that request on: the request after that one shows whether serving went on
    for _ in range(2):
        answered = client.call_async(bad)
        assert spin_until(answered.done, 10), "the node stopped serving"
        assert not answered.result().success and "no_such_scene" in answered.result().message
