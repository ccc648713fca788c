"""The ROS 2 node ``gait_planner``: service ``/gait_planner/plan_gait`` -> plan -> topics.

Thin adapter: a request is converted to a `PlanRequest`, planned and recorded by
`gait_planner.pipeline`, and the plain result is converted to messages by
`gait_planner.io.messages` (the one module that owns message layouts). Bad requests and
failed plans are answered with success = False and a message; the node keeps serving.

Parameters: ``default_scene`` (string, "walker3d"), ``output_dir`` (string, folder of the
recordings, "runs"), ``max_solve_time`` (double, s, 60.0: used when a request gives <= 0),
``compile_derivatives`` (bool, true: compiled derivative elements, which `make setup`
compiles for the shipped scenes with ``gait-planner prepare``).
Topics (reliable; volatile so a restarting controller never re-runs an old plan):
``/gait_planner/joint_trajectory`` (one message per plan), ``/gait_planner/state`` and
``/gait_planner/contact_forces`` (one message per node).
"""

from __future__ import annotations

import threading

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from gait_planner.io import messages
from gait_planner.ocp.solve import Planner
from gait_planner.pipeline import PlanRequest, RequestError, plan_and_record
from gait_planner_msgs.msg import ContactForces, MultibodyState
from gait_planner_msgs.srv import PlanGait
from trajectory_msgs.msg import JointTrajectory

SERVICE = "/gait_planner/plan_gait"
TOPIC_TRAJECTORY = "/gait_planner/joint_trajectory"
TOPIC_STATE = "/gait_planner/state"
TOPIC_FORCES = "/gait_planner/contact_forces"


def _given(value: float) -> float | None:
    """None for "not given" (<= 0); NaN and infinities pass on to be refused."""
    return None if value <= 0 else value


def request_from_msg(req, default_scene: str, default_time: float,
                     compiled: bool = False) -> PlanRequest:
    """PlanGait.Request -> PlanRequest (<= 0 or empty fields: the scene's values)."""
    return PlanRequest(
        scene=req.scene or default_scene,
        step_length=_given(req.step_length),
        cost=req.cost or None,
        friction_coefficient=_given(req.friction_coefficient),
        intervals_per_phase=req.intervals_per_phase if req.intervals_per_phase > 0 else None,
        max_solve_time=_given(req.max_solve_time) or default_time,
        output_name=req.output_name,
        cold_start=req.cold_start,
        compiled=compiled,
        steps=req.steps if req.steps > 0 else 1,
        posture=req.posture,
    )


class GaitPlannerNode(Node):
    """Serves plan requests one at a time (later requests wait for the running one)."""

    def __init__(self, *, planner: Planner | None = None, **kwargs):
        super().__init__("gait_planner", **kwargs)
        self.declare_parameter("default_scene", "walker3d")
        self.declare_parameter("output_dir", "runs")
        self.declare_parameter("max_solve_time", 60.0)
        # compile the derivative elements to C (a one-time cost per scene and machine)
        self.declare_parameter("compile_derivatives", True)
        self._planner = planner or Planner(progress=self._progress)
        self._lock = threading.Lock()
        group = ReentrantCallbackGroup()
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self._pub_trajectory = self.create_publisher(JointTrajectory, TOPIC_TRAJECTORY, 10)
        self._pub_state = self.create_publisher(MultibodyState, TOPIC_STATE, qos)
        self._pub_forces = self.create_publisher(ContactForces, TOPIC_FORCES, qos)
        self.create_service(PlanGait, SERVICE, self._on_plan, callback_group=group)

    def _progress(self, iteration: int, cost: float, violation: float, seconds: float) -> None:
        if iteration % 25 == 0:
            self.get_logger().info(
                f"iteration {iteration}: cost {cost:.6g}, constraint violation "
                f"{violation:.2e}, {seconds:.1f} s")

    def _param(self, name: str):
        return self.get_parameter(name).value

    def _on_plan(self, request: PlanGait.Request, response: PlanGait.Response):
        with self._lock:
            try:
                plan_request = request_from_msg(
                    request, self._param("default_scene"), self._param("max_solve_time"),
                    self._param("compile_derivatives"))
                outcome = plan_and_record(self._planner, plan_request, self._param("output_dir"))
            except (RequestError, OSError) as err:
                response.success, response.message = False, str(err)
                self.get_logger().warning(f"plan request refused: {err}")
                return response
            except Exception as err:  # noqa: BLE001  (a bug must not stop the service)
                response.success = False
                response.message = f"internal error ({type(err).__name__}): {err}"
                self.get_logger().error(f"plan request failed: {response.message}")
                return response
            result = outcome.result
            stamp = self.get_clock().now().nanoseconds
            messages.fill_message(response, messages.plan_response_fields(
                result, str(outcome.mcap_path or ""), stamp) if result.success else {
                    "success": False, "message": result.message,
                    "solver_status": result.stats.status})
            if result.success:
                self._publish(result, stamp)
                self.get_logger().info(
                    f"planned {result.scene.name}: cost {result.cost_value:.6g}, duration "
                    f"{result.duration:.4f} s, recorded {outcome.mcap_path}")
            else:
                self.get_logger().warning(f"plan failed: {result.message}")
            return response

    def _publish(self, result, start_ns: int) -> None:
        self._pub_trajectory.publish(messages.fill_message(
            JointTrajectory(), messages.joint_trajectory(result, start_ns)))
        for state in messages.multibody_states(result, start_ns):
            self._pub_state.publish(messages.fill_message(MultibodyState(), state))
        for forces in messages.contact_forces(result, start_ns):
            self._pub_forces.publish(messages.fill_message(ContactForces(), forces))


def main(args=None) -> int:
    """Run the node until interrupted (``gait-planner node``)."""
    rclpy.init(args=args)
    node = GaitPlannerNode()
    executor = MultiThreadedExecutor()
    executor.add_node(node)
    node.get_logger().info(f"serving {SERVICE}")
    try:
        executor.spin()
    except KeyboardInterrupt:
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0
