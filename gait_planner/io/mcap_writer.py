"""One MCAP recording per plan, ROS 2 profile, as rosbag2 would write it (docs/design.md sec. 7).

`write_plan_mcap(result, path)` writes

* ``ros2msg`` schemas in rosbag2's concatenated form (`gait_planner.io.ros_definitions`),
  ``cdr`` messages (the dicts of `gait_planner.io.messages`, encoded as `CdrEncoder`
  says), and on every channel the metadata ``offered_qos_profiles`` as rosbag2 (Jazzy and
  later) serialises it: a YAML sequence with one profile;
* the topics of `TOPICS`: /robot_description, /tf_static (transient_local, reliable, depth
  1, as robot_state_publisher offers them), /gait_planner/joint_trajectory (one message),
  and per time node /gait_planner/state, /gait_planner/contact_forces, /tf and
  /joint_states. Log time = publish time = header.stamp = start + (t_n - t_0); the
  one-off messages are logged at the start;
* the metadata record ``gait_planner.plan`` (`plan_metadata`) and the scene file as the
  attachment ``<scene>.yaml``.

The file appears atomically: it is written to a hidden temporary file in the target folder
and renamed over `path` (replacing an existing file) only when complete; on any error the
temporary file is removed and an existing file at `path` is left as it was. A process
killed while writing leaves only the temporary file, which
`gait_planner.atomic.remove_stale_temporaries` removes later.

Schemas, channels (with their metadata, which mcap_ros2's Writer cannot attach) and records
are written with mcap's `Writer`; chunks are zstd-compressed (the ``zstandard`` package, a
dependency of mcap).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from functools import lru_cache
from importlib import metadata as importlib_metadata
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer
from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from gait_planner.io import messages
from gait_planner.atomic import atomic_target
from gait_planner.io.ros_definitions import STANDARD_DEFINITIONS, custom_definitions, schema_text
from gait_planner.result import PlanResult

__all__ = ["METADATA_NAME", "TOPICS", "CdrEncoder", "QosProfile", "encoder_for", "plan_metadata",
           "qos_yaml", "register_topics", "write_plan_mcap"]

METADATA_NAME = "gait_planner.plan"
DEFAULT_PERIODICITY = (
    "mirror: nodes N-1 and N are the mirror images (about y = 0, shifted by step_length in x) "
    "of nodes 0 and 1 (paper eqs. 7-9); duration and cost_value cover t_0 .. t_(N-1)"
)

# rmw's RMW_DURATION_INFINITE as rosbag2 writes it for the default (infinite) durations
_INFINITE = (9223372036, 854775807)


@dataclass(frozen=True)
class QosProfile:
    """The QoS policies rosbag2 records for a topic's publisher."""

    depth: int = 10
    reliability: str = "reliable"  # or "best_effort"
    durability: str = "volatile"  # or "transient_local"
    history: str = "keep_last"


def qos_yaml(profile: QosProfile) -> str:
    """`offered_qos_profiles` text: what rosbag2's serialize_rclcpp_qos_vector (yaml-cpp's
    Dump of a one-element sequence, rosbag2 metadata version >= 9) writes for `profile`."""
    sec, nsec = _INFINITE
    duration = f"\n    sec: {sec}\n    nsec: {nsec}"
    return (f"- history: {profile.history}\n  depth: {profile.depth}\n"
            f"  reliability: {profile.reliability}\n  durability: {profile.durability}\n"
            f"  deadline:{duration}\n  lifespan:{duration}\n  liveliness: automatic\n"
            f"  liveliness_lease_duration:{duration}\n"
            f"  avoid_ros_namespace_conventions: false")


LATCHED = QosProfile(depth=1, durability="transient_local")
STREAM = QosProfile(depth=10)
TF_STREAM = QosProfile(depth=100)  # tf2_ros.TransformBroadcaster's default depth

# topic -> (ROS type, offered QoS), in the order the channels are registered
TOPICS: dict[str, tuple[str, QosProfile]] = {
    "/robot_description": ("std_msgs/msg/String", LATCHED),
    "/tf_static": ("tf2_msgs/msg/TFMessage", LATCHED),
    "/gait_planner/joint_trajectory": ("trajectory_msgs/msg/JointTrajectory", STREAM),
    "/gait_planner/state": ("gait_planner_msgs/msg/MultibodyState", STREAM),
    "/gait_planner/contact_forces": ("gait_planner_msgs/msg/ContactForces", STREAM),
    "/tf": ("tf2_msgs/msg/TFMessage", TF_STREAM),
    "/joint_states": ("sensor_msgs/msg/JointState", STREAM),
}


def _number(x: float) -> str:
    return repr(float(x))


def plan_metadata(result: PlanResult) -> dict[str, str]:
    """The string key-value pairs of the ``gait_planner.plan`` metadata record.

    Keys of docs/design.md section 7 (scene, cost, cost_value, step_length, duration,
    friction_coefficient, phase_scaling (comma-separated), solve_time_s, iterations, nodes),
    periodicity (result.settings["periodicity"] if given, else `DEFAULT_PERIODICITY`),
    success, message, solver_status, max_constraint_violation, max_dynamics_residual,
    max_friction_violation, robot_package_dirs (a scene drafted from a URDF: where its
    ``package://`` paths resolved when it was planned, absolute, os.pathsep-separated; the
    recording's scene names them relative to a scene file it no longer has), then every
    other entry of result.settings. Floats are written
    with repr (they read back exactly with float()). A settings key equal to one of the
    fixed keys (other than periodicity) raises ValueError.
    """
    stats = result.stats
    data = {
        "scene": result.scene.name,
        "cost": result.cost_name,
        "cost_value": _number(result.cost_value),
        "step_length": _number(result.step_length),
        "duration": _number(result.duration),
        "friction_coefficient": _number(result.friction_coefficient),
        "phase_scaling": ",".join(_number(s) for s in result.phase_scaling),
        "solve_time_s": _number(stats.solve_time),
        "iterations": str(int(stats.iterations)),
        "nodes": str(result.n_nodes),
        "periodicity": DEFAULT_PERIODICITY,
        "success": "true" if result.success else "false",
        "message": result.message,
        "solver_status": stats.status,
        "max_constraint_violation": _number(stats.max_constraint_violation),
        "max_dynamics_residual": _number(stats.max_dynamics_residual),
        "max_friction_violation": _number(stats.max_friction_violation),
    }
    robot = result.scene.robot
    found = [d for d in (robot.search_dirs() if robot else ()) if os.path.isabs(d)]
    if found:
        data["robot_package_dirs"] = os.pathsep.join(found)
    for key, value in result.settings.items():
        if key in data and key != "periodicity":
            raise ValueError(f"result.settings key {key!r} would overwrite the metadata key of "
                             f"the same name; rename it")
        data[str(key)] = str(value)
    return data


def _library() -> str:
    try:
        version = importlib_metadata.version("gait_planner")
    except importlib_metadata.PackageNotFoundError:
        version = "unknown"
    return (f"gait_planner {version}; mcap {importlib_metadata.version('mcap')}; "
            f"rosbags {importlib_metadata.version('rosbags')}")


class CdrEncoder:
    """CDR encoder of message dicts (the layouts of `gait_planner.io.messages`).

    A rosbags type store (`Typestore.serialize_cdr`, public API) holding exactly the types
    parsed from `schemas` (ROS type "pkg/msg/Type" -> schema text), the texts the recording
    stores: the bytes follow the schema a reader gets. Padding is zeroed, so a plan's
    recording is the same bytes every time. (rclpy's `serialize_message` was not used:
    tf2_msgs has no PyPI wheel, Fast CDR leaves padding bytes uninitialised (heap bytes in
    the file), and filling rclpy messages from the dicts took three times as long as this.)
    Building one costs about 0.1 s (parsing, code generation), so `encoder_for` builds it
    once per set of schemas; afterwards it is only read, so threads may share it.
    """

    _NUMPY = {"byte": "uint8", "char": "uint8"}  # ROS 2 primitives not named as numpy's

    def __init__(self, schemas: Mapping[str, str]) -> None:
        self._store = get_typestore(Stores.EMPTY)
        for ros_type, text in schemas.items():
            self._store.register(get_types_from_msg(text, ros_type))
        for ros_type in self._store.fielddefs:
            self._store.get_msgdef(ros_type)  # generates the (de)serialisers now

    def encode(self, ros_type: str, data: Mapping[str, Any]) -> bytes:
        """The CDR bytes (little endian, with the encapsulation header) of `data`."""
        return bytes(self._store.serialize_cdr(self._message(ros_type, data), ros_type))

    def _message(self, ros_type: str, data: Mapping[str, Any]) -> object:
        fields = self._store.fielddefs[ros_type][1]
        names = [name for name, _ in fields]
        if set(data) != set(names):
            raise ValueError(f"{ros_type} has the fields {names}; the message dict has "
                             f"{sorted(data)}")
        values = {}
        for name, (kind, desc) in fields:
            value = data[name]
            if kind == Nodetype.NAME:
                value = self._message(desc, value)
            elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
                (element_kind, element), _ = desc
                if element_kind == Nodetype.NAME:
                    value = [self._message(element, item) for item in value]
                elif element[0] != "string":
                    value = np.asarray(value, dtype=self._NUMPY.get(element[0], element[0]))
            values[name] = value
        return self._store.types[ros_type](**values)


@lru_cache(maxsize=4)
def encoder_for(schemas: tuple[tuple[str, str], ...]) -> CdrEncoder:
    """The `CdrEncoder` of these (ROS type, schema text) pairs, built on first use."""
    return CdrEncoder(dict(schemas))


def _check_path(path: Path, allowed_dirs: Sequence[str | os.PathLike] | None) -> Path:
    """The absolute target path, or ValueError if its folder is not inside an allowed one."""
    target = Path(path).expanduser()
    folder = target.parent.resolve()
    if not target.name or target.name in (".", ".."):
        raise ValueError(f"MCAP path {str(path)!r} names no file")
    if allowed_dirs is not None:
        allowed = [Path(d).expanduser().resolve() for d in allowed_dirs]
        if not any(folder == d or d in folder.parents for d in allowed):
            raise ValueError(
                f"refusing to write {str(path)!r}: its folder {str(folder)!r} is outside the "
                f"allowed output folders {[str(d) for d in allowed]}")
    resolved = folder / target.name
    if resolved.is_dir():
        raise ValueError(f"MCAP path {str(path)!r} is a directory")
    return resolved


def _records(result: PlanResult, start_ns: int) -> Iterable[tuple[int, int, str, Any]]:
    """(log time, channel order, topic, message dict) of every message."""
    tree = messages.frame_tree(result.scene)
    order = {topic: i for i, topic in enumerate(TOPICS)}
    yield start_ns, order["/robot_description"], "/robot_description", \
        messages.robot_description(result)
    yield start_ns, order["/tf_static"], "/tf_static", messages.tf_static(result, start_ns, tree)
    yield start_ns, order["/gait_planner/joint_trajectory"], "/gait_planner/joint_trajectory", \
        messages.joint_trajectory(result, start_ns)
    stamps = messages.node_stamps_ns(result, start_ns)
    per_node = {
        "/gait_planner/state": messages.multibody_states(result, start_ns),
        "/gait_planner/contact_forces": messages.contact_forces(result, start_ns),
        "/tf": messages.tf_messages(result, start_ns, tree),
        "/joint_states": messages.joint_states(result, start_ns),
    }
    for topic, items in per_node.items():
        for stamp, item in zip(stamps, items):
            yield stamp, order[topic], topic, item


def recording_schemas() -> dict[str, str]:
    """ROS type -> schema text of every type a recording holds."""
    definitions = {**STANDARD_DEFINITIONS, **custom_definitions()}
    return {ros_type: schema_text(ros_type, definitions) for ros_type, _ in TOPICS.values()}


def recording_encoder() -> CdrEncoder:
    """The encoder of the recordings' messages (built on the first call: about 0.1 s)."""
    return encoder_for(tuple(recording_schemas().items()))


def register_topics(writer: Writer, topics: Mapping[str, tuple[str, QosProfile]],
                    texts: Mapping[str, str]) -> dict[str, int]:
    """Register each topic (name -> (ROS type, offered QoS)) on `writer` as a CDR channel,
    one ros2msg schema per type from `texts` (`recording_schemas`); topic -> channel id."""
    schemas: dict[str, int] = {}  # ROS type -> schema id
    channels: dict[str, int] = {}
    for topic, (ros_type, qos) in topics.items():
        if ros_type not in schemas:
            schemas[ros_type] = writer.register_schema(ros_type, SchemaEncoding.ROS2,
                                                       texts[ros_type].encode("utf-8"))
        channels[topic] = writer.register_channel(
            topic, MessageEncoding.CDR, schemas[ros_type],
            metadata={"offered_qos_profiles": qos_yaml(qos)})
    return channels


def _write(result: PlanResult, stream, start_ns: int) -> None:
    records = sorted(_records(result, start_ns), key=lambda r: (r[0], r[1]))
    writer = Writer(stream, compression=CompressionType.ZSTD)
    writer.start(profile="ros2", library=_library())
    texts = recording_schemas()
    encoder = encoder_for(tuple(texts.items()))
    channels = register_topics(writer, TOPICS, texts)
    sequence = dict.fromkeys(TOPICS, 0)
    for log_time, _, topic, message in records:
        sequence[topic] += 1
        writer.add_message(channels[topic], log_time=log_time, publish_time=log_time,
                           sequence=sequence[topic],
                           data=encoder.encode(TOPICS[topic][0], message))
    writer.add_metadata(METADATA_NAME, plan_metadata(result))
    writer.add_attachment(create_time=start_ns, log_time=start_ns,
                          name=f"{result.scene.name}.yaml", media_type="application/yaml",
                          data=result.scene.source.encode("utf-8"))
    writer.finish()


def write_plan_mcap(result: PlanResult, path: str | os.PathLike, start_ns: int | None = None,
                    *, allowed_dirs: Sequence[str | os.PathLike] | None = None) -> Path:
    """Write the MCAP recording of `result` to `path` atomically; return the absolute path.

    start_ns: plan start (ns since the epoch) = stamp of node 0; default: now.
    allowed_dirs: if given, `path`'s folder must be one of them or inside one (symbolic
        links resolved), else ValueError; default: any folder.
    Raises ValueError for a result that cannot be recorded (NaN or infinite values,
    inconsistent shapes, see `gait_planner.io.messages.check_result`), OSError if the file
    cannot be written; in every failing case no file and no temporary file is left.
    The folder must exist.
    """
    target = _check_path(Path(path), allowed_dirs)
    messages.check_result(result, finite=True)
    start_ns = time.time_ns() if start_ns is None else int(start_ns)
    if start_ns < 0:
        raise ValueError(f"start_ns must be >= 0, got {start_ns}")
    if not result.scene.source:
        raise ValueError(f"scene {result.scene.name!r} has no source text to attach")
    with atomic_target(target) as tmp, open(tmp, "wb") as stream:
        _write(result, stream, start_ns)
        stream.flush()
        os.fsync(stream.fileno())
    return target
