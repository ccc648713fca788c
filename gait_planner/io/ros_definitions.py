"""ROS 2 message definition texts for MCAP schemas, in rosbag2's concatenated form.

rosbag2 (rosbag2_storage_mcap, message_definition_cache.cpp) stores a schema as the root
type's .msg text followed, for every type it depends on (depth first, each type once,
dependencies of one type in sorted order), by ``"\\n" + "=" * 80 + "\\nMSG: pkg/Type\\n"`` and
that type's text. `schema_text` builds exactly that from:

* the standard types below (their field lines, comments left out; tf2_msgs has no wheel,
  so none of them is read from an installed package);
* our own types, read from the gait_planner_msgs sources (`msg_defs/msg/*.msg` next to this
  package in a source checkout, else the installed share found through ament_index),
  verbatim, comments included, as rosbag2 would.
"""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path
from typing import Mapping

__all__ = ["STANDARD_DEFINITIONS", "SEPARATOR", "custom_definitions", "msg_defs_dir",
           "schema_text", "short_name"]

SEPARATOR = "=" * 80
CUSTOM_PACKAGE = "gait_planner_msgs"

STANDARD_DEFINITIONS: dict[str, str] = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec\n",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "std_msgs/String": "string data\n",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/Transform": "Vector3 translation\nQuaternion rotation\n",
    "geometry_msgs/Wrench": "Vector3 force\nVector3 torque\n",
    "geometry_msgs/TransformStamped": (
        "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"
    ),
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
    "sensor_msgs/JointState": (
        "std_msgs/Header header\n\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
        "float64[] effort\n"
    ),
    "trajectory_msgs/JointTrajectory": (
        "std_msgs/Header header\nstring[] joint_names\nJointTrajectoryPoint[] points\n"
    ),
    "trajectory_msgs/JointTrajectoryPoint": (
        "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\n"
        "float64[] effort\nbuiltin_interfaces/Duration time_from_start\n"
    ),
}

_PRIMITIVES = frozenset({"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16",
                         "uint16", "int32", "uint32", "int64", "uint64", "string", "wstring"})
_FIELD_TYPE = re.compile(r"^\s*([A-Za-z][A-Za-z0-9_/]*)(?:<=\d+)?(?:\[[^\]]*\])?\s+\S")


def short_name(type_name: str) -> str:
    """"pkg/msg/Type" or "pkg/Type" -> "pkg/Type"."""
    parts = type_name.split("/")
    if len(parts) == 3 and parts[1] == "msg":
        return f"{parts[0]}/{parts[2]}"
    if len(parts) == 2:
        return type_name
    raise ValueError(f"not a message type name: {type_name!r} (expected pkg/msg/Type)")


def dependencies(text: str, package: str) -> list[str]:
    """Sorted "pkg/Type" names of the non-primitive field types in a .msg text."""
    found = set()
    for line in text.splitlines():
        match = _FIELD_TYPE.match(line.split("#", 1)[0])
        if not match or match.group(1) in _PRIMITIVES:
            continue
        name = match.group(1)
        found.add(name if "/" in name else f"{package}/{name}")
    return sorted(found)


def msg_defs_dir() -> Path | None:
    """The folder holding gait_planner_msgs' .msg files: the source checkout's
    msg_defs/msg first, else <share>/gait_planner_msgs/msg via ament_index, else None."""
    source = Path(__file__).resolve().parents[2] / "msg_defs" / "msg"
    if source.is_dir():
        return source
    try:
        from ament_index_python.packages import get_package_share_directory

        share = Path(get_package_share_directory(CUSTOM_PACKAGE)) / "msg"
        return share if share.is_dir() else None
    except Exception:  # not importable, no AMENT_PREFIX_PATH, or package not installed
        return None


@lru_cache(maxsize=4)
def _custom(directory: str) -> dict[str, str]:
    return {f"{CUSTOM_PACKAGE}/{p.stem}": p.read_text(encoding="utf-8")
            for p in sorted(Path(directory).glob("*.msg"))}


def custom_definitions(directory: Path | None = None) -> dict[str, str]:
    """"gait_planner_msgs/Type" -> .msg text of our own message types."""
    directory = directory or msg_defs_dir()
    if directory is None:
        raise FileNotFoundError(
            f"no {CUSTOM_PACKAGE} message definitions: neither msg_defs/msg next to the "
            f"gait_planner package nor an installed share/{CUSTOM_PACKAGE} (AMENT_PREFIX_PATH)")
    return dict(_custom(str(directory)))


def schema_text(type_name: str, definitions: Mapping[str, str] | None = None) -> str:
    """The rosbag2 concatenated definition of `type_name` ("pkg/msg/Type" or "pkg/Type"),
    from `definitions` ("pkg/Type" -> text; default: standard + our own types)."""
    if definitions is None:
        definitions = {**STANDARD_DEFINITIONS, **custom_definitions()}
    seen: set[str] = set()

    def text_of(name: str) -> str:
        if name not in definitions:
            raise KeyError(f"no message definition for {name!r} (needed by {type_name!r})")
        return definitions[name]

    def append(name: str, depth: int) -> str:
        if depth > 50:
            raise RecursionError(f"message definition of {type_name!r} nests too deeply")
        text = text_of(name)
        for dep in dependencies(text, name.split("/")[0]):
            if dep not in seen:
                seen.add(dep)
                text += f"\n{SEPARATOR}\nMSG: {dep}\n" + append(dep, depth + 1)
        return text

    return append(short_name(type_name), 0)
