"""The walk's MCAP recording (ROS 2 profile, the plan recordings' schemas and encoder).

`write_walk_mcap(result, path, every)` writes, from `walk(..., series=True)`, every
`every`-th simulation step (log time = header stamp = simulated time since start 0):

* /walk/joint_states (sensor_msgs/JointState): simulated angles (rad), rates (rad/s) and
  the applied torque (N m, feed-forward + feedback, conjugate to the angles);
* /walk/feedforward and /walk/feedback (sensor_msgs/JointState, effort only): the split;
* /walk/contact_forces (gait_planner_msgs/ContactForces): per planned contact point in
  contact, the summed force (N, world) of its spheres on the foot and the point's position;
* the metadata record ``gait_planner.walk``: the summary's scalars, as text.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from mcap.writer import CompressionType, Writer

from gait_planner.atomic import atomic_target
from gait_planner.io.mcap_writer import (STREAM, encoder_for, recording_schemas,
                                         register_topics)
from gait_planner.io.messages import header, vector3

__all__ = ["TOPICS", "output_path", "write_walk_mcap"]

TOPICS = {"/walk/joint_states": ("sensor_msgs/msg/JointState", STREAM),
          "/walk/feedforward": ("sensor_msgs/msg/JointState", STREAM),
          "/walk/feedback": ("sensor_msgs/msg/JointState", STREAM),
          "/walk/contact_forces": ("gait_planner_msgs/msg/ContactForces", STREAM)}


def _joints(ns: int, names, position=(), velocity=(), effort=()) -> dict[str, Any]:
    return {"header": header(ns, "world"), "name": list(names),
            "position": list(map(float, position)), "velocity": list(map(float, velocity)),
            "effort": list(map(float, effort))}


def output_path(path: str | os.PathLike) -> Path:
    """`path` made absolute, for a walk's recording; ValueError naming it if its folder does
    not exist."""
    target = Path(path).expanduser().resolve()
    if not target.parent.is_dir():
        raise ValueError(f"cannot write {path}: no folder {target.parent}")
    return target


def write_walk_mcap(result: dict[str, Any], path: str | os.PathLike, every: int = 10) -> Path:
    """Write the walk `result` (with its "series") to `path` atomically; the absolute path."""
    series = result["series"]
    target = output_path(path)
    texts = recording_schemas()
    encoder = encoder_for(tuple(texts.items()))
    names, contacts = series["joint_names"], series["contact_names"]
    with atomic_target(target) as tmp, open(tmp, "wb") as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        writer.start(profile="ros2", library="gait_planner walk")
        channels = register_topics(writer, TOPICS, texts)
        for seq, k in enumerate(range(0, len(series["time"]), every), start=1):
            ns = int(round(series["time"][k] * 1e9))
            ff, fb = series["feedforward"][k], series["feedback"][k]
            active = [i for i in range(len(contacts)) if series["ground_force"][k][i][2] > 0]
            messages = {
                "/walk/joint_states": _joints(ns, names, series["position"][k],
                                              series["velocity"][k], ff + fb),
                "/walk/feedforward": _joints(ns, names, effort=ff),
                "/walk/feedback": _joints(ns, names, effort=fb),
                "/walk/contact_forces": {
                    "header": header(ns, "world"), "node": k, "time": float(series["time"][k]),
                    "contact_names": [contacts[i] for i in active],
                    "points": [vector3(series["contact_position"][k][i]) for i in active],
                    "forces": [vector3(series["ground_force"][k][i]) for i in active],
                    "wrench_bodies": [], "wrench_points": [], "wrenches": [],
                    "centers_of_pressure": []},
            }
            for topic, message in messages.items():
                writer.add_message(channels[topic], log_time=ns, publish_time=ns, sequence=seq,
                                   data=encoder.encode(TOPICS[topic][0], message))
        writer.add_metadata("gait_planner.walk", {
            k: v if isinstance(v, str) else json.dumps(v)
            for k, v in result.items() if k != "series"})
        writer.finish()
    return target

