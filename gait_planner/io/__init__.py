"""The formats: a `PlanResult` as ROS messages, an MCAP recording and a URDF (pictures of
it, figures and rerun, are `gait_planner.viz`).

* `gait_planner.io.messages`: message layouts as plain dicts (+ `fill_message` for rclpy);
* `gait_planner.io.urdf`: `scene_to_urdf` and the frame scheme /tf follows;
* `gait_planner.io.mcap_writer`: `write_plan_mcap` (ROS 2 profile, atomic);
* `gait_planner.io.mcap_reader`: `read_plan_mcap` -> `RecordedPlan` (independent of the writer);
* `gait_planner.io.robot_tree`, `ros_definitions`: the robot's frames, the messages' definitions.

The names below are imported lazily, so ``import gait_planner.io.messages`` (the ROS node)
does not load mcap.
"""

from __future__ import annotations

from gait_planner.lazy import lazy_exports

_EXPORTS = {
    "fill_message": "messages",
    "plan_response_fields": "messages",
    "scene_to_urdf": "urdf",
    "write_plan_mcap": "mcap_writer",
    "read_plan_mcap": "mcap_reader",
    "RecordedPlan": "mcap_reader",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
