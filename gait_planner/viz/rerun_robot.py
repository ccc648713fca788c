"""A robot drafted from its URDF, drawn in rerun as itself: its own meshes, moved by /tf.

For a scene with a ``robot:`` section (`gait_planner.model.scene.RobotSource`) the rerun
view draws the URDF instead of the draft's primitives:

* `log_robot_model`: the URDF through rerun's built-in URDF loader (``log_file_from_path``,
  static, under ``world/robot``): its visual meshes, ``package://`` paths resolved in
  `RobotSource.search_dirs` (the loader reads ``ROS_PACKAGE_PATH``, set for the call), its
  fixed joints as named transform frames; and the frame ``world`` of /tf tied to the view's
  ``world`` entity.
* `log_robot_motion`: per node, the transforms of /tf (`gait_planner.io.messages.tf_messages`:
  ``world -> <base link>`` and every planned joint) as Transform3D between named frames
  (rerun >= 0.28), so the view and a replay of the MCAP move the same frames.
"""

from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import rerun as rr

from gait_planner.io.messages import WORLD_FRAME, tf_messages
from gait_planner.result import PlanResult

__all__ = ["ROBOT_ENTITY", "log_robot_model", "log_robot_motion", "log_transform", "log_urdf"]

ROBOT_ENTITY = "world/robot"


@contextmanager
def _package_path(dirs):
    saved = os.environ.get("ROS_PACKAGE_PATH")
    os.environ["ROS_PACKAGE_PATH"] = os.pathsep.join(list(dirs) + ([saved] if saved else []))
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop("ROS_PACKAGE_PATH", None)
        else:
            os.environ["ROS_PACKAGE_PATH"] = saved


def log_urdf(rec: rr.RecordingStream, urdf: str, urdf_path: str, dirs, name: str) -> None:
    """A URDF (its text, or its file where `urdf_path` is set) through rerun's URDF loader,
    static under `ROBOT_ENTITY`, ``package://`` paths looked for in `dirs`; and the frame
    ``world`` of /tf tied to the view's ``world`` entity."""
    with _package_path(dirs):
        if urdf_path:
            rec.log_file_from_path(Path(urdf_path), entity_path_prefix=ROBOT_ENTITY, static=True)
        else:
            rec.log_file_from_contents(f"{name}.urdf", urdf.encode(),
                                       entity_path_prefix=ROBOT_ENTITY, static=True)
    rec.log(f"{ROBOT_ENTITY}/frames/{WORLD_FRAME}",
            rr.Transform3D(parent_frame="tf#/world", child_frame=WORLD_FRAME), static=True)


def log_transform(rec: rr.RecordingStream, parent: str, child: str, translation, xyzw,
                  static: bool = False) -> None:
    """One /tf transform parent -> child as a Transform3D between named frames."""
    rec.log(f"{ROBOT_ENTITY}/frames/{child}", rr.Transform3D(
        translation=list(translation), quaternion=rr.Quaternion(xyzw=list(xyzw)),
        parent_frame=parent, child_frame=child), static=static)


def log_robot_model(rec: rr.RecordingStream, result: PlanResult) -> None:
    """The robot's URDF, static (module docstring)."""
    robot = result.scene.robot
    log_urdf(rec, robot.urdf, robot.urdf_path, robot.search_dirs(), result.scene.name)


def log_robot_motion(rec: rr.RecordingStream, result: PlanResult) -> None:
    """The /tf transforms of every node on the timelines ``time`` and ``node``."""
    t = np.asarray(result.times, dtype=float) - float(result.times[0])
    for n, message in enumerate(tf_messages(result, 0)):
        rec.set_time("time", duration=float(t[n]))
        rec.set_time("node", sequence=n)
        for transform in message["transforms"]:
            move, turn = transform["transform"]["translation"], transform["transform"]["rotation"]
            log_transform(rec, transform["header"]["frame_id"], transform["child_frame_id"],
                          (move["x"], move["y"], move["z"]),
                          (turn["x"], turn["y"], turn["z"], turn["w"]))
    rec.reset_time()
