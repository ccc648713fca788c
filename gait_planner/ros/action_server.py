"""The action ``/gait_planner/plan_gait`` (gait_planner_msgs/action/PlanGait): the service's
request and answer, with feedback while the plan is made and cancel.

* One plan at a time: a goal that arrives while a plan runs (from the action or the service)
  is rejected at once. An accepted goal holds the node from its acceptance; if rclpy drops
  it because its acceptance could not be sent (see `gait_planner.ros.worker`), the hold
  lapses after `RESERVATION_TIMEOUT` s. A ROS 2 goal rejection carries no reason; this node
  rejects goals for no other reason than "busy" (a bad request is accepted and aborted with
  its message) and logs it, and `gait-planner call --action` prints it.
* Feedback: the phase at every phase change (cost NaN) and iteration, cost and constraint
  violation every ``feedback_every`` IPOPT iterations, with the seconds since the goal was
  accepted; while walking, the phase with how far the walk got at each half cycle's end
  ("walking (2 of 10 half cycles done)", `PlanWorker.detail`). While nothing new comes (a
  build, the guess, the recording, a slow iteration) the phase is sent again every
  `FEEDBACK_HEARTBEAT` s (cost NaN, the iteration count so far). So a long build shows that
  the node is alive, and a client that lost the first message still learns the phase (the
  server's feedback writer may not yet have matched a new client's reader when the goal is
  accepted: a "building" lost that way failed CI once).
* Cancel: accepted while the problem is built or solved, refused while the found plan is
  being recorded (a second or two) or walked (phase "walking", parameter walk_steps). An
  accepted cancel stops IPOPT within one iteration, and the goal ends canceled with nothing
  recorded or published.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Callable

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.action.server import ServerGoalHandle
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node

from gait_planner.result import PlanStatus
from gait_planner.ros.worker import Closed, Lapsed, PlanWorker
from gait_planner_msgs.action import PlanGait as PlanGaitAction

ACTION = "/gait_planner/plan_gait"
CANCEL_MARK_WAIT = 0.5  # s, the longest a stopped goal waits for rclpy's "canceling" mark
FEEDBACK_HEARTBEAT = 0.5  # s without feedback after which the last one is sent again

# plan(request, answer): plans a request, fills the answer (Response or Result fields) and
# says how the plan ended (None: refused)
Plan = Callable[[object, object], "PlanStatus | None"]


class PlanGaitActionServer:
    """Wires the action's goal, cancel and execute callbacks to a `PlanWorker`."""

    def __init__(self, node: Node, worker: PlanWorker, plan: Plan, callback_group):
        self._node, self._worker, self._plan = node, worker, plan
        self._tickets: dict[int, int] = {}  # id of an accepted goal -> its reservation
        self._server = ActionServer(
            node, PlanGaitAction, ACTION, execute_callback=self._execute,
            goal_callback=self._on_goal, cancel_callback=self._on_cancel,
            callback_group=callback_group)

    def destroy(self) -> None:
        """Destroy the action server (before its node)."""
        self._server.destroy()

    def _on_goal(self, goal: PlanGaitAction.Goal) -> GoalResponse:
        ticket = self._worker.try_reserve()
        if ticket is not None:
            self._tickets[id(goal)] = ticket  # goal_handle.request is `goal`
            return GoalResponse.ACCEPT
        self._node.get_logger().warning(
            "plan goal rejected: busy (one plan at a time; the running plan goes on)")
        return GoalResponse.REJECT

    def _on_cancel(self, goal_handle: ServerGoalHandle) -> CancelResponse:
        if self._worker.request_stop(self._tickets.get(id(goal_handle.request), -1)):
            self._node.get_logger().info(
                f"plan goal canceled at iteration {self._worker.stopped_at} of "
                f"{self._worker.phase or 'its start'}: stopping the solver")
            return CancelResponse.ACCEPT
        self._node.get_logger().info(
            "cancel refused: the plan is being recorded or walked, or is over")
        return CancelResponse.REJECT

    def _await_cancel_mark(self, goal_handle: ServerGoalHandle) -> None:
        """Wait (up to `CANCEL_MARK_WAIT` s; not at shutdown) until rclpy has marked the goal
        canceling. rclpy marks it after `_on_cancel` returns, and `_on_cancel` has already
        stopped the plan: a plan that stops at once could end before the mark, and the goal
        was then aborted (message "stopped on request") instead of canceled, and the cancel
        answered as refused (seen in test/ros/test_fuzz.py)."""
        deadline = time.monotonic() + CANCEL_MARK_WAIT
        while (not goal_handle.is_cancel_requested and not self._worker.closing()
               and time.monotonic() < deadline):
            time.sleep(0.002)

    def _execute(self, goal_handle: ServerGoalHandle) -> PlanGaitAction.Result:
        started = time.monotonic()
        every = max(1, int(self._node.get_parameter("feedback_every").value))
        last = {"message": None, "at": started}  # the last feedback sent, and when
        order = threading.Lock()  # a heartbeat never repeats a phase after its successor

        def publish(message: PlanGaitAction.Feedback) -> None:  # holding `order`
            now = time.monotonic()
            message.elapsed = now - started
            last["message"], last["at"] = message, now
            try:
                goal_handle.publish_feedback(message)
            except _rclpy.RCLError:  # shutting down (SIGINT, SIGTERM): the solve stops next
                pass

        def feedback(phase: str, iteration: int, cost: float, violation: float) -> None:
            if iteration % every and not math.isnan(cost):  # phase changes always go
                return
            with order:
                publish(PlanGaitAction.Feedback(phase=phase, iteration=iteration, cost=cost,
                                                constraint_violation=violation))

        def heartbeat() -> None:  # the waiting executor thread; `feedback` is the plan's
            with order:
                message = last["message"]
                if message is not None and time.monotonic() - last["at"] >= FEEDBACK_HEARTBEAT:
                    publish(PlanGaitAction.Feedback(  # a phase message: cost NaN
                        phase=message.phase, iteration=message.iteration, cost=math.nan,
                        constraint_violation=math.nan))

        result, status = PlanGaitAction.Result(), None
        try:
            status = self._worker.run(self._tickets[id(goal_handle.request)],
                                      lambda: self._plan(goal_handle.request, result), feedback,
                                      tick=heartbeat)
        except (Closed, Lapsed) as err:
            result.success, result.message = False, str(err)
        self._tickets.pop(id(goal_handle.request), None)
        stopped = status is PlanStatus.STOPPED
        if stopped:
            self._await_cancel_mark(goal_handle)
        try:
            if goal_handle.is_cancel_requested and stopped:
                goal_handle.canceled()
            elif result.success:
                goal_handle.succeed()
            else:
                goal_handle.abort()
        except _rclpy.RCLError:  # the context is shut down (SIGINT, SIGTERM): nobody to tell
            pass
        return result
