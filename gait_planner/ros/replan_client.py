"""The node in a re-planning loop, as a walking controller uses it (issue #63): a
`walk.followed.Planning` whose plans come from the node's action.

`NodePlanning(node, spin_until, scene)` publishes the walker's measured state as a robot
does (`/joint_states` and the world -> root transform on `/tf`, stamped with the simulated
time) and sends a goal with `start: "robot"` (the root's twist in the goal) at every
re-plan; the start from standing is `start: "standing"`, the stop a `start: "state"` goal
from the followed plan's own node (its joint angles, the root's pose, and the rates after
it by forward differences of the plan's nodes), the preparations such goals from the
gait's first node (the walk's stops start from the prepared one: prepared from the gait's
exact first state instead, walker2d's stops through the node took 86-130 iterations and
missed their strikes, 2026-12-07; prepared as they are sent, 7). Each answer is followed
as the node recorded it (its MCAP: the trajectory the node published on
`/gait_planner/joint_trajectory`, with the root's states); the trajectories heard on that
topic are kept in `heard` for comparison. A goal rejected (busy), aborted or not answered
within `RESULT_WAIT` s is an `Answer` that failed, saying why.
"""

from __future__ import annotations

import itertools
from typing import Callable

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.io.messages import WORLD_FRAME, frame_tree, quaternion_msg
from gait_planner.model.scene import Scene
from gait_planner.ocp.transition import StartState
from gait_planner.walk.followed import Answer, Followed, Measured
from gait_planner.walk.reference import planned_joints, root_rates_after

__all__ = ["NodePlanning", "RESULT_WAIT"]

RESULT_WAIT = 300.0  # s, the longest a goal's result is waited for
PUBLISH_SPIN = 0.1  # s spun after publishing a measured state, so the node has it


def _set_xyz(msg, values) -> None:
    """Set a Vector3 or Point message's x, y, z from three numbers."""
    msg.x, msg.y, msg.z = (float(v) for v in values)


class NodePlanning:
    """A `walk.followed.Planning` through the node's action (module docstring); node: the
    controller's rclpy node, spin_until(done, timeout): spins its executor."""

    def __init__(self, node, spin_until: Callable[[Callable[[], bool], float], bool],
                 scene: Scene):
        from rclpy.action import ActionClient
        from sensor_msgs.msg import JointState
        from tf2_msgs.msg import TFMessage
        from trajectory_msgs.msg import JointTrajectory

        from gait_planner.ros.action_server import ACTION
        from gait_planner.ros.node import TOPIC_JOINT_STATES, TOPIC_TF, TOPIC_TRAJECTORY
        from gait_planner_msgs.action import PlanGait

        self.node, self.spin_until, self.scene = node, spin_until, scene
        self._goal = PlanGait.Goal
        self.action = ActionClient(node, PlanGait, ACTION)
        self.joints = node.create_publisher(JointState, TOPIC_JOINT_STATES, 10)
        self.tf = node.create_publisher(TFMessage, TOPIC_TF, 100)
        self.heard: list = []
        node.create_subscription(JointTrajectory, TOPIC_TRAJECTORY, self.heard.append, 10)
        self.root = frame_tree(scene).root
        self._names = itertools.count()

    def __call__(self, kind: str, start: StartState | None, measured: Measured | None,
                 limit: float | None, **fields) -> Answer:
        goal = self._goal(steps=int(fields.get("steps", 1)),
                          transition_half_cycles=int(fields.get("halves", 0)),
                          stop=bool(fields.get("stop", False)),
                          max_solve_time=float(limit or 0.0),
                          output_name=f"{kind.replace(' ', '_')}_{next(self._names)}")
        if kind == "re-plan":
            self._publish(measured)
            goal.start = "robot"
            _set_xyz(goal.root_twist.linear, measured.root_linear)
            _set_xyz(goal.root_twist.angular, measured.root_angular)
        elif kind == "stop":
            self._state_goal(goal, *fields["source"])
        elif start is not None and start.standing:
            goal.start = "standing"
        elif kind in ("prepare re-plan", "prepare stop"):  # from the gait's first node
            gait = self._send(self._goal(steps=1, output_name="gait"))
            if not gait.success:
                return gait
            self._state_goal(goal, gait.followed, 0)
        return self._send(goal)

    def _publish(self, m: Measured) -> None:
        """The measured state on /joint_states and /tf, stamped with its simulated time."""
        from builtin_interfaces.msg import Time
        from geometry_msgs.msg import TransformStamped
        from sensor_msgs.msg import JointState
        from tf2_msgs.msg import TFMessage

        sec, nanosec = divmod(int(round(m.time * 1e9)), 10**9)
        stamp = Time(sec=sec, nanosec=nanosec)
        state = JointState(name=list(m.names), position=[float(v) for v in m.positions],
                           velocity=[float(v) for v in m.velocities])
        state.header.stamp = stamp
        transform = TransformStamped(child_frame_id=self.root)
        transform.header.frame_id, transform.header.stamp = WORLD_FRAME, stamp
        _set_xyz(transform.transform.translation, m.root_position)
        r = transform.transform.rotation
        r.x, r.y, r.z, r.w = (float(v) for v in m.root_xyzw)
        self.joints.publish(state)
        self.tf.publish(TFMessage(transforms=[transform]))
        self.spin_until(lambda: False, PUBLISH_SPIN)

    def _state_goal(self, goal, followed: Followed, n: int) -> None:
        """goal's start "state": node n of the followed plan: its recording's joint angles
        there, the root body's pose, and the rates after the node (forward differences to
        node n + 1, `walk.reference.root_rates_after`: at a strike the central differences
        would straddle the impact, and a stop from them took 117-136 iterations,
        2026-12-07). The root body's pose is the root frame's of a shipped scene; a drafted
        robot's base link pose is not derived from it here."""
        rec = planned_joints(followed.recording)
        i = self.scene.body_index(self.scene.root.body)
        q, h = followed.q, float(followed.times[n + 1] - followed.times[n])
        velocity, angular = root_rates_after(self.scene, q, followed.times, n)
        goal.start = "state"
        goal.state.name = list(rec.joint_names)
        goal.state.position = [float(v) for v in rec.positions[n]]
        goal.state.velocity = [float(v) for v in (rec.positions[n + 1] - rec.positions[n]) / h]
        _set_xyz(goal.root_pose.position, q[n, 12 * i:12 * i + 3])
        quaternion = quaternion_msg(q[n, 12 * i + 3:12 * i + 12].reshape(3, 3).T)
        o = goal.root_pose.orientation
        o.x, o.y, o.z, o.w = (quaternion[k] for k in "xyzw")
        _set_xyz(goal.root_twist.linear, velocity)
        _set_xyz(goal.root_twist.angular, angular)

    def _send(self, goal) -> Answer:
        from action_msgs.msg import GoalStatus

        from gait_planner.ros.client import send_goal

        if not self.spin_until(self.action.server_is_ready, 20.0):
            return Answer(False, "the node's action is not available", None, None)
        handle = send_goal(self.action, goal, lambda: self.spin_until(lambda: False, 0.01))
        if not handle.accepted:
            return Answer(False, "the goal was rejected (the node is busy)", None, None)
        future = handle.get_result_async()
        if not self.spin_until(future.done, RESULT_WAIT):
            return Answer(False, f"no result within {RESULT_WAIT:g} s", None, None)
        status, result = future.result().status, future.result().result
        if status != GoalStatus.STATUS_SUCCEEDED or not result.success:
            return Answer(False, result.message or f"goal status {status}",
                          int(result.iterations) or None, None)
        rec = read_plan_mcap(result.mcap_path)
        return Answer(True, "converged", int(result.iterations), Followed.of_recording(rec))
