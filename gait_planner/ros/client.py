"""A minimal client of the node (ros2cli is not on PyPI): ``gait-planner call [--action |
--preparation]`` and its Python API.

`call_plan_gait` (the service) and `call_plan_gait_action` (the action: feedback, Ctrl-C
cancels) take the request's fields (`gait_planner.request.FIELDS`; missing, 0 or empty: the
node's or the scene's default), check them as the node will (`plan_request`: RequestError
before anything is sent) and return the answer as a dict with its "status" (succeeded,
failed, refused, rejected, aborted, canceled); `ask_preparation` returns what the node has
prepared (the service /gait_planner/preparation). They raise `CallError` when no answer can
come: no node serves the name within `DISCOVERY_WAIT` s, none answers within the timeout, or
the node left the ROS graph (`NodeGone`: it stopped or died) after it was seen, and stayed
away for `GONE_GRACE` s. A node that stops (SIGTERM, SIGINT) leaves the graph at once; one
that is killed (SIGKILL, a crash) leaves it when its DDS lease ends (`gait-planner node`
announces a short one: `gait_planner.ros.node.DDS_PROFILE`), so the client knows within
a few seconds either way.
"""

from __future__ import annotations

import math
import sys
import time
import uuid
from typing import Any, Callable, Mapping, TextIO

import rclpy
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.action.client import ClientGoalHandle
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from unique_identifier_msgs.msg import UUID

from gait_planner.request import FIELDS, plan_request
from gait_planner.ros.action_server import ACTION
from gait_planner.ros.node import BUSY, PREPARATION_SERVICE, SERVICE
from gait_planner_msgs.action import PlanGait as PlanGaitAction
from gait_planner_msgs.srv import PlanGait, Preparation

CANCEL_WAIT = 10.0  # s to wait for the node to answer a cancel request
DISCOVERY_WAIT = 10.0  # s to wait for the node's service or action to appear
GOAL_RESPONSE_WAIT = 5.0  # s to wait for a goal's acceptance before sending the goal again
GOAL_ATTEMPTS = 3
GONE_GRACE = 2.0  # s a server that was seen must be missing from the graph to count as gone
SPIN = 0.1  # s, one turn of the client's spin
STATUS = {GoalStatus.STATUS_SUCCEEDED: "succeeded", GoalStatus.STATUS_ABORTED: "aborted",
          GoalStatus.STATUS_CANCELED: "canceled"}


class CallError(RuntimeError):
    """No answer can come to a call; the message says why."""


class NodeGone(CallError):
    """The node left the ROS graph (it stopped or died) before it answered."""


class Presence:
    """Whether a server that was seen is still in the ROS graph: `check` raises NodeGone
    once `ready()` (`service_is_ready`, `server_is_ready`) has been False for `grace` s on
    end. Made once the server was seen: discovery can take a while after a start, and a
    server not yet discovered is not a dead one; a short absence (a lost discovery message)
    is forgiven."""

    def __init__(self, ready: Callable[[], bool], name: str, grace: float = GONE_GRACE):
        self._ready, self._name, self._grace = ready, name, grace
        self._seen = time.monotonic()

    def check(self) -> None:
        now = time.monotonic()
        if self._ready():
            self._seen = now
        elif now - self._seen >= self._grace:
            raise NodeGone(
                f"the node serving {self._name} left the ROS graph {now - self._seen:.1f} s "
                "ago without answering (it stopped or died; see its log): no plan")


def request_msg(fields: Mapping[str, Any], kind=PlanGait.Request):
    """PlanGait.Request (or the action's Goal: `kind`) of the request's `fields` (missing or
    None: 0 or empty, the defaults), checked first as the node checks it (RequestError)."""
    plan_request(**fields)
    req = kind()
    for name in FIELDS:
        if fields.get(name) is not None:
            setattr(req, name, type(getattr(req, name))(fields[name]))
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
        "walk_steps": res.walk_steps, "walk_half_cycles": res.walk_half_cycles,
        "walk_feedback_share": res.walk_feedback_share, "walk_stopped": res.walk_stopped,
        "walk_touches": res.walk_touches, "walk_first_touch": res.walk_first_touch,
    }


def _spin_until(node: Node, done: Callable[[], bool], timeout: float, what: str,
                presence: Presence) -> None:
    """Spin `node` until `done()`; CallError after `timeout` s, NodeGone if the server
    leaves the graph."""
    deadline = time.monotonic() + timeout
    while not done():
        presence.check()
        if time.monotonic() > deadline:
            raise CallError(f"no {what} from {ACTION} within {timeout:g} s")
        rclpy.spin_once(node, timeout_sec=SPIN)


def _call_service(kind, name: str, request, timeout: float):
    """Call the node's service `name` (of type `kind`) once with `request` and return its
    response (CallError if no node serves it or none answers within `timeout` s)."""
    rclpy.init()
    node = rclpy.create_node("gait_planner_client")
    try:
        client = node.create_client(kind, name)
        if not client.wait_for_service(timeout_sec=min(timeout, DISCOVERY_WAIT)):
            raise CallError(f"no service {name}: is `gait-planner node` running "
                            "(same ROS_DOMAIN_ID)?")
        future = client.call_async(request)
        _spin_until(node, future.done, timeout, "answer",
                    Presence(client.service_is_ready, name))
        return future.result()
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def ask_preparation(*, timeout: float) -> dict:
    """What the node has prepared (`gait_planner_msgs/srv/Preparation`): done, ready,
    pending and message."""
    res = _call_service(Preparation, PREPARATION_SERVICE, Preparation.Request(), timeout)
    return {"done": res.done, "ready": list(res.ready), "pending": list(res.pending),
            "message": res.message}


def call_plan_gait(fields: Mapping[str, Any], *, timeout: float) -> dict:
    """Call the service once with the request's `fields` and return the response's scalar
    fields and its "status": succeeded, failed (the solver ran: `message` says why) or
    refused (busy, or a request the node cannot plan)."""
    answer = answer_dict(_call_service(PlanGait, SERVICE, request_msg(fields), timeout))
    status = ("succeeded" if answer["success"] else
              "failed" if answer["solver_status"] else "refused")
    return {"status": status, **answer}


def feedback_line(feedback: PlanGaitAction.Feedback) -> str:
    """One line per feedback message: elapsed s, phase, and (once the solver iterates)
    iteration, cost and constraint violation."""
    line = f"{feedback.elapsed:7.2f} s  {feedback.phase}"
    if not math.isnan(feedback.cost):  # NaN: a phase change, no iteration yet
        line += (f"  iteration {feedback.iteration}  cost {feedback.cost:.6g}  "
                 f"violation {feedback.constraint_violation:.2e}")
    return line


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
    `gait_planner.ros.worker.RESERVATION_TIMEOUT` s). Raises CallError if no goal is
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
                raise CallError(f"no goal response from {ACTION} within {wait:g} s, "
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


def call_plan_gait_action(fields: Mapping[str, Any], *, timeout: float,
                          out: TextIO = sys.stderr) -> dict:
    """Send one goal with the request's `fields` to the action, print each feedback to `out`
    as it arrives, and return the result's scalar fields plus "status" (succeeded, aborted,
    canceled; rejected: busy, with only success and message). Ctrl-C (KeyboardInterrupt)
    cancels the goal and waits for its result (canceled); a second Ctrl-C leaves at once."""
    goal_msg = request_msg(fields, PlanGaitAction.Goal)
    # Python's own SIGINT handler, so that Ctrl-C raises here and the cancel can still be sent
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("gait_planner_action_client")
    try:
        client = ActionClient(node, PlanGaitAction, ACTION)
        if not client.wait_for_server(timeout_sec=min(timeout, DISCOVERY_WAIT)):
            raise CallError(f"no action {ACTION}: is `gait-planner node` running "
                            "(same ROS_DOMAIN_ID)?")
        presence = Presence(client.server_is_ready, ACTION)

        def spin_once() -> None:
            presence.check()
            rclpy.spin_once(node, timeout_sec=SPIN)

        goal = send_goal(
            client, goal_msg, spin_once,
            feedback_callback=lambda msg: print(feedback_line(msg.feedback), file=out,
                                                flush=True),
            note=lambda text: print(text, file=out, flush=True))
        if not goal.accepted:
            return {"status": "rejected", "success": False, "message": BUSY}
        result = goal.get_result_async()
        try:
            _spin_until(node, result.done, timeout, "result", presence)
        except KeyboardInterrupt:
            print("canceling the goal ...", file=out, flush=True)
            canceled = goal.cancel_goal_async()
            _spin_until(node, canceled.done, CANCEL_WAIT, "cancel response", presence)
            print("cancel refused (the plan is being recorded or walked); waiting for the result"
                  if not canceled.result().goals_canceling else
                  "cancel accepted; waiting for the node to stop (a problem being built is "
                  "finished first; Ctrl-C again leaves at once)", file=out, flush=True)
            _spin_until(node, result.done, timeout, "result after the cancel", presence)
        answer = result.result()
        return {"status": STATUS.get(answer.status, str(answer.status)),
                **answer_dict(answer.result)}
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
