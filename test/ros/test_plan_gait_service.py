"""Transport test of the PlanGait service: two nodes in one process, real rclpy and DDS.

The server answers a fixed response without planning anything: this checks that requests
and responses (with a JointTrajectory inside) cross the middleware intact under the
contract's service name, not the planner.
"""

from __future__ import annotations

import pytest
from builtin_interfaces.msg import Duration
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from gait_planner_msgs.srv import PlanGait

pytestmark = pytest.mark.timeout(90)

SERVICE = "/gait_planner/plan_gait"
WAIT = 15.0  # s


def fixed_response() -> PlanGait.Response:
    trajectory = JointTrajectory(
        joint_names=["hip_r_x", "knee_r"],
        points=[
            JointTrajectoryPoint(
                positions=[0.1 * n, -0.2 * n],
                velocities=[1.0, -2.0],
                effort=[10.0 * n, -55.5],
                time_from_start=Duration(sec=0, nanosec=50_000_000 * n),
            )
            for n in range(3)
        ],
    )
    return PlanGait.Response(
        success=True,
        message="fixed answer of the transport test",
        solver_status="Solve_Succeeded",
        cost=41.2256,
        duration=0.5988,
        phase_scaling=[1.5, 1.5, 1.4889, 1.4724],
        solve_time=0.25,
        iterations=42,
        max_constraint_violation=1e-12,
        max_dynamics_residual=2e-10,
        max_friction_violation=0.0,
        trajectory=trajectory,
        mcap_path="/tmp/runs/test.mcap",
    )


def test_plan_gait_request_and_response_cross_between_nodes(make_node, executor, spin_until):
    received: list[PlanGait.Request] = []

    def serve(request: PlanGait.Request, response: PlanGait.Response) -> PlanGait.Response:
        received.append(request)
        answer = fixed_response()
        answer.step_length = request.step_length  # echo one field to tie answer to request
        return answer

    server = make_node("gait_planner")
    server.create_service(PlanGait, SERVICE, serve)
    client_node = make_node("gait_planner_test_client")
    client = client_node.create_client(PlanGait, SERVICE)
    executor.add_node(server)
    executor.add_node(client_node)

    assert spin_until(client.service_is_ready, WAIT), f"{SERVICE} not discovered in {WAIT} s"
    request = PlanGait.Request(
        scene="walker2d",
        step_length=0.55,
        cost="torque_squared",
        friction_coefficient=0.6,
        intervals_per_phase=6,
        max_solve_time=30.0,
        output_name="transport",
        cold_start=True,
    )
    future = client.call_async(request)
    executor.spin_until_future_complete(future, timeout_sec=WAIT)

    assert future.done(), f"no response from {SERVICE} within {WAIT} s"
    assert received == [request]
    expected = fixed_response()
    expected.step_length = 0.55
    assert future.result() == expected
