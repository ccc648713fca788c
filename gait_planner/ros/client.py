"""A minimal client of the node (ros2cli is not on PyPI): ``gait-planner call [--action]``."""

from __future__ import annotations

import argparse
import math
import sys
import time
import uuid
from typing import Callable, TextIO

import rclpy
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.action.client import ClientGoalHandle
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from unique_identifier_msgs.msg import UUID

from gait_planner.ros.action_server import ACTION
from gait_planner.ros.node import SERVICE
from gait_planner_msgs.action import PlanGait as PlanGaitAction
from gait_planner_msgs.srv import PlanGait

REJECTED = ("rejected: busy (the node plans one request at a time and is planning another "
            "one; try again later)")
CANCEL_WAIT = 10.0  # s to wait for the node to answer a cancel request
GOAL_RESPONSE_WAIT = 5.0  # s to wait for a goal's acceptance before sending the goal again
GOAL_ATTEMPTS = 3


def request_msg(args: argparse.Namespace, kind=PlanGait.Request):
    """PlanGait.Request (or the action's Goal: `kind`) from command-line options (unset = the
    node's/scene's defaults)."""
    req = kind()
    req.scene = args.scene or ""
    req.step_length = float(args.step_length or 0.0)
    req.cost = args.cost or ""
    req.friction_coefficient = float(args.mu or 0.0)
    req.intervals_per_phase = int(args.intervals or 0)
    req.max_solve_time = float(args.max_time or 0.0)
    req.output_name = args.output_name
    req.cold_start = bool(args.cold)
    req.steps = int(args.steps or 0)
    req.posture = args.posture or ""
    return req


def answer_dict(res) -> dict:
    """The scalar fields of a PlanGait response or action result as a dict."""
    return {
        "success": res.success, "message": res.message, "solver_status": res.solver_status,
        "cost": res.cost, "step_length": res.step_length, "duration": res.duration,
        "phase_scaling": list(res.phase_scaling), "solve_time": res.solve_time,
        "iterations": res.iterations,
        "max_constraint_violation": res.max_constraint_violation,
        "max_dynamics_residual": res.max_dynamics_residual,
        "max_friction_violation": res.max_friction_violation,
        "trajectory_points": len(res.trajectory.points), "mcap_path": res.mcap_path,
        "continuous_torque_error": res.continuous_torque_error,
        "continuous_torque_error_at_switches": res.continuous_torque_error_at_switches,
        "continuous_base_force": res.continuous_base_force,
        "continuous_dynamics": res.continuous_dynamics,
    }


def call_plan_gait(args: argparse.Namespace, *, timeout: float) -> dict:
    """Call the service once and return the response's scalar fields as a dict."""
    rclpy.init()
    node = rclpy.create_node("gait_planner_client")
    try:
        client = node.create_client(PlanGait, SERVICE)
        if not client.wait_for_service(timeout_sec=min(timeout, 10.0)):
            raise RuntimeError(f"no service {SERVICE}: is `gait-planner node` running "
                               "(same ROS_DOMAIN_ID)?")
        future = client.call_async(request_msg(args))
        rclpy.spin_until_future_complete(node, future, timeout_sec=timeout)
        if not future.done():
            raise RuntimeError(f"no answer from {SERVICE} within {timeout} s")
        return answer_dict(future.result())
    finally:
        node.destroy_node()
        rclpy.shutdown()


def feedback_line(feedback: PlanGaitAction.Feedback) -> str:
    """One line per feedback message: elapsed s, phase, and (once the solver iterates)
    iteration, cost and constraint violation."""
    line = f"{feedback.elapsed:7.2f} s  {feedback.phase}"
    if not math.isnan(feedback.cost):  # NaN: a phase change, no iteration yet
        line += (f"  iteration {feedback.iteration}  cost {feedback.cost:.6g}  "
                 f"violation {feedback.constraint_violation:.2e}")
    return line


def _spin_until(node: Node, done: Callable[[], bool], timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not done():
        if time.monotonic() > deadline:
            raise RuntimeError(f"no {what} from {ACTION} within {timeout:g} s")
        rclpy.spin_once(node, timeout_sec=0.1)


def send_goal(action: ActionClient, goal: PlanGaitAction.Goal, spin_once: Callable[[], None],
              feedback_callback: Callable | None = None, note: Callable[[str], None] | None = None,
              wait: float = GOAL_RESPONSE_WAIT, attempts: int = GOAL_ATTEMPTS) -> ClientGoalHandle:
    """Send `goal` to the node's action and return its goal handle, accepted or rejected
    (busy), calling `spin_once()` (a short spin of the client's node) meanwhile.

    Fast DDS drops the answer to a request that arrives before the node has discovered the
    client's response reader (it waits 100 ms; rclpy warns "failed to send response
    (timeout)"), which can happen to a goal sent as soon as the client discovered the action:
    the goal then runs while its client waits. A goal whose feedback arrives without its
    acceptance is therefore taken as accepted (the node publishes feedback from the start of
    a plan). A goal with neither for `wait` s is sent again as a new goal, `attempts` goals in
    all, each sending told to `note` (if the node dropped the first, its hold lapses after
    `gait_planner.ros.worker.RESERVATION_TIMEOUT` s). Raises RuntimeError if no goal is
    answered."""
    sent: list[tuple[UUID, object, list]] = []  # (goal id, response future, its feedback)
    deadline = 0.0
    while True:
        for goal_id, future, heard in sent:
            if future.done() and future.result().accepted:
                return future.result()
            if heard and not future.done():  # running: its acceptance was lost on the way
                if note is not None:
                    note("the goal's acceptance was lost on the way; it runs (its feedback "
                         "arrives)")
                return ClientGoalHandle(action, goal_id, PlanGaitAction.Impl.SendGoalService
                                        .Response(accepted=True))
        if sent and all(future.done() for _, future, _ in sent):
            return sent[-1][1].result()  # rejected: busy
        if time.monotonic() >= deadline:
            if len(sent) == attempts:
                raise RuntimeError(f"no goal response from {ACTION} within {wait:g} s, "
                                   f"{attempts} goals sent")
            if sent and note is not None:
                note(f"no answer to the goal within {wait:g} s; sending it again")
            goal_id, heard = UUID(uuid=list(uuid.uuid4().bytes)), []

            def on_feedback(message, heard=heard) -> None:
                heard.append(message)
                if feedback_callback is not None:
                    feedback_callback(message)

            sent.append((goal_id, action.send_goal_async(goal, feedback_callback=on_feedback,
                                                         goal_uuid=goal_id), heard))
            deadline = time.monotonic() + wait
        spin_once()


def call_plan_gait_action(args: argparse.Namespace, *, timeout: float,
                          out: TextIO = sys.stderr) -> dict:
    """Send one goal to the action, print each feedback to `out` as it arrives, and return
    the result's scalar fields plus "status" (succeeded, aborted, canceled, rejected).
    Ctrl-C (KeyboardInterrupt) cancels the goal and waits for its result (canceled); a
    second Ctrl-C leaves at once."""
    # Python's own SIGINT handler, so that Ctrl-C raises here and the cancel can still be sent
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("gait_planner_action_client")
    try:
        client = ActionClient(node, PlanGaitAction, ACTION)
        if not client.wait_for_server(timeout_sec=min(timeout, 10.0)):
            raise RuntimeError(f"no action {ACTION}: is `gait-planner node` running "
                               "(same ROS_DOMAIN_ID)?")
        goal = send_goal(
            client, request_msg(args, PlanGaitAction.Goal),
            lambda: rclpy.spin_once(node, timeout_sec=0.1),
            feedback_callback=lambda msg: print(feedback_line(msg.feedback), file=out,
                                                flush=True),
            note=lambda text: print(text, file=out, flush=True))
        if not goal.accepted:
            return {"status": "rejected", "success": False, "message": REJECTED}
        result = goal.get_result_async()
        try:
            _spin_until(node, result.done, timeout, "result")
        except KeyboardInterrupt:
            print("canceling the goal ...", file=out, flush=True)
            canceled = goal.cancel_goal_async()
            _spin_until(node, canceled.done, CANCEL_WAIT, "cancel response")
            print("cancel refused (the plan is being recorded); waiting for the result"
                  if not canceled.result().goals_canceling else
                  "cancel accepted; waiting for the node to stop (a problem being built is "
                  "finished first; Ctrl-C again leaves at once)", file=out, flush=True)
            _spin_until(node, result.done, timeout, "result after the cancel")
        answer = result.result()
        status = {GoalStatus.STATUS_SUCCEEDED: "succeeded", GoalStatus.STATUS_ABORTED: "aborted",
                  GoalStatus.STATUS_CANCELED: "canceled"}.get(answer.status, str(answer.status))
        return {"status": status, **answer_dict(answer.result)}
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
