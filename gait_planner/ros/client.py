"""A minimal service client (ros2cli is not on PyPI): ``gait-planner call``."""

from __future__ import annotations

import argparse

import rclpy

from gait_planner.ros.node import SERVICE
from gait_planner_msgs.srv import PlanGait


def request_msg(args: argparse.Namespace) -> PlanGait.Request:
    """PlanGait.Request from command-line options (unset = the node's/scene's defaults)."""
    req = PlanGait.Request()
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
        res = future.result()
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
    finally:
        node.destroy_node()
        rclpy.shutdown()
