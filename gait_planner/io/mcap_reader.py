"""Read a plan's MCAP recording back into numpy arrays, from the file alone.

`read_plan_mcap(path)` decodes the recording with mcap + mcap_ros2 (the schemas stored in
the file) and returns a `RecordedPlan`. It is what independent checks of recorded plans
use, so it deliberately shares no code with the writer (`gait_planner.io.mcap_writer`,
`messages`, `ros_definitions`, `urdf`): the topic names below restate docs/design.md section 7.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

__all__ = ["ChannelInfo", "RecordedPlan", "Transform", "read_plan_mcap"]

STATE = "/gait_planner/state"
CONTACTS = "/gait_planner/contact_forces"
TRAJECTORY = "/gait_planner/joint_trajectory"
DESCRIPTION = "/robot_description"
TF, TF_STATIC = "/tf", "/tf_static"
JOINT_STATES = "/joint_states"
PLAN_METADATA = "gait_planner.plan"
_REQUIRED = (STATE, CONTACTS, TRAJECTORY, DESCRIPTION, TF, TF_STATIC, JOINT_STATES)


@dataclass(frozen=True)
class ChannelInfo:
    """What the file says about one topic."""

    topic: str
    schema_name: str
    schema_encoding: str
    message_encoding: str
    metadata: dict[str, str]
    message_count: int


@dataclass(frozen=True)
class Transform:
    """One geometry_msgs/TransformStamped: child pose in parent; quaternion (x, y, z, w)."""

    parent: str
    child: str
    stamp_ns: int
    translation: np.ndarray
    rotation: np.ndarray

    def matrix(self) -> np.ndarray:
        """4x4 homogeneous transform parent <- child."""
        x, y, z, w = self.rotation / np.linalg.norm(self.rotation)
        R = np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ])
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, self.translation
        return T


@dataclass(frozen=True)
class RecordedPlan:
    """A plan as recorded. N + 1 time nodes; k = 12 nb; na joint angles.

    State (/gait_planner/state): nodes, times (s from the start), stamps_ns (header),
    phases, active_contacts, body_names, q (N+1, k), generalized_force (N+1, k),
    kinetic_energy, potential_energy (N+1,); held_joint_names and held_joint_impulses
    (N+1, m) N m s (a robot's locked joints; empty in recordings made before them).
    Contacts (/gait_planner/contact_forces), per node: contact_names, contact_points and
    contact_force_vectors ((m_n, 3) arrays, m_n active contacts); `contact_force(name)`
    gives the dense (N+1, 3) series, zero where inactive. Per foot in contact:
    wrench_bodies, wrench_points ((b_n, 3)), wrenches ((b_n, 6): force N, moment N m about
    the wrench point, world) and centers_of_pressure ((b_n, 3)).
    Trajectory (/gait_planner/joint_trajectory, one message): joint_names, trajectory_stamp_ns,
    time_from_start (N+1,) s, positions, velocities, accelerations, effort (N+1, na).
    Joint states: joint_state_position / _velocity / _effort (N+1, na).
    tf: per /tf message a tuple of `Transform`; tf_static: the /tf_static transforms.
    log_times_ns / header_stamps_ns: topic -> (messages,) int64, for every topic whose
    messages carry a header (for /tf: the stamp of each message's first transform).
    metadata: the ``gait_planner.plan`` record; metadata_records: every record by name;
    attachments: name -> text; scene_text: the ``<scene>.yaml`` attachment; urdf: the
    /robot_description text; channels: topic -> `ChannelInfo`; profile: the header's.
    """

    path: str
    profile: str
    channels: dict[str, ChannelInfo]
    metadata: dict[str, str]
    metadata_records: dict[str, dict[str, str]]
    attachments: dict[str, str]
    scene_text: str
    urdf: str
    body_names: tuple[str, ...]
    nodes: np.ndarray
    times: np.ndarray
    stamps_ns: np.ndarray
    phases: tuple[str, ...]
    active_contacts: tuple[tuple[str, ...], ...]
    q: np.ndarray
    generalized_force: np.ndarray
    kinetic_energy: np.ndarray
    potential_energy: np.ndarray
    contact_names: tuple[tuple[str, ...], ...]
    contact_points: tuple[np.ndarray, ...]
    contact_force_vectors: tuple[np.ndarray, ...]
    wrench_bodies: tuple[tuple[str, ...], ...]
    wrench_points: tuple[np.ndarray, ...]
    wrenches: tuple[np.ndarray, ...]
    centers_of_pressure: tuple[np.ndarray, ...]
    joint_names: tuple[str, ...]
    trajectory_stamp_ns: int
    time_from_start: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray  # (N+1, na); (N+1, 0) in recordings made before they were published
    held_joint_names: tuple[str, ...]
    held_joint_impulses: np.ndarray  # (N+1, m) N m s
    effort: np.ndarray
    joint_state_position: np.ndarray
    joint_state_velocity: np.ndarray
    joint_state_effort: np.ndarray
    tf: tuple[tuple[Transform, ...], ...]
    tf_static: tuple[Transform, ...]
    log_times_ns: dict[str, np.ndarray] = field(default_factory=dict)
    header_stamps_ns: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return int(self.times.shape[0])

    def contact_force(self, name: str) -> np.ndarray:
        """(N+1, 3) force of contact `name` at every node, zero where it is not listed."""
        out = np.zeros((self.n_nodes, 3))
        for n, (names, forces) in enumerate(zip(self.contact_names, self.contact_force_vectors)):
            if name in names:
                out[n] = forces[names.index(name)]
        return out


def _points(points: Any) -> np.ndarray:
    """(m, 3) from geometry_msgs/Point-like messages."""
    return np.array([[p.x, p.y, p.z] for p in points]).reshape(-1, 3)


def _ns(time_msg: Any) -> int:
    return int(time_msg.sec) * 1_000_000_000 + int(time_msg.nanosec)


def _array(values: Any) -> np.ndarray:
    return np.asarray(list(values), dtype=float)


def _transform(t: Any) -> Transform:
    tr, rot = t.transform.translation, t.transform.rotation
    return Transform(t.header.frame_id, t.child_frame_id, _ns(t.header.stamp),
                     np.array([tr.x, tr.y, tr.z]), np.array([rot.x, rot.y, rot.z, rot.w]))


def _stack(rows: list, what: str, path: Path) -> np.ndarray:
    lengths = {len(r) for r in rows}
    if len(lengths) > 1:
        raise ValueError(f"{path}: {what} changes length between messages: {sorted(lengths)}")
    return np.array([_array(r) for r in rows]) if rows else np.zeros((0, 0))


def read_plan_mcap(path: str | Path) -> RecordedPlan:
    """Decode the MCAP recording of a plan at `path` (module docstring). Raises ValueError
    if a required topic, the plan metadata or the scene attachment is missing."""
    path = Path(path)
    decoded: dict[str, list[tuple[int, Any]]] = {topic: [] for topic in _REQUIRED}
    log_times: dict[str, list[int]] = {}
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        summary = reader.get_summary()
        if summary is None:
            raise ValueError(f"{path}: the MCAP file has no summary section")
        counts = summary.statistics.channel_message_counts if summary.statistics else {}
        channels = {
            ch.topic: ChannelInfo(ch.topic, summary.schemas[ch.schema_id].name,
                                  summary.schemas[ch.schema_id].encoding, ch.message_encoding,
                                  dict(ch.metadata), int(counts.get(ch.id, 0)))
            for ch in summary.channels.values()
        }
        for _, channel, message, msg in reader.iter_decoded_messages(log_time_order=True):
            decoded.setdefault(channel.topic, []).append((message.log_time, msg))
            log_times.setdefault(channel.topic, []).append(message.log_time)
        records = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        attachments = {a.name: bytes(a.data).decode("utf-8") for a in reader.iter_attachments()}
    missing = [t for t in _REQUIRED if not decoded[t]]
    if missing:
        raise ValueError(f"{path}: no messages on {missing}")
    if PLAN_METADATA not in records:
        raise ValueError(f"{path}: no metadata record {PLAN_METADATA!r}")
    meta = records[PLAN_METADATA]
    scene_file = f"{meta.get('scene', '')}.yaml"
    if scene_file not in attachments:
        raise ValueError(f"{path}: no scene attachment {scene_file!r} "
                         f"(attachments: {sorted(attachments)})")

    states = [m for _, m in decoded[STATE]]
    contacts = [m for _, m in decoded[CONTACTS]]
    joints = [m for _, m in decoded[JOINT_STATES]]
    trajectory = decoded[TRAJECTORY][-1][1]
    points = list(trajectory.points)
    stamps = {
        STATE: [_ns(m.header.stamp) for m in states],
        CONTACTS: [_ns(m.header.stamp) for m in contacts],
        JOINT_STATES: [_ns(m.header.stamp) for m in joints],
        TRAJECTORY: [_ns(m.header.stamp) for _, m in decoded[TRAJECTORY]],
        TF: [_ns(m.transforms[0].header.stamp) if m.transforms else -1
             for _, m in decoded[TF]],
        TF_STATIC: [_ns(m.transforms[0].header.stamp) if m.transforms else -1
                    for _, m in decoded[TF_STATIC]],
    }
    return RecordedPlan(
        path=str(path),
        profile=header.profile,
        channels=channels,
        metadata=meta,
        metadata_records=records,
        attachments=attachments,
        scene_text=attachments[scene_file],
        urdf=decoded[DESCRIPTION][-1][1].data,
        body_names=tuple(states[0].body_names),
        nodes=np.array([m.node for m in states], dtype=np.int64),
        times=np.array([m.time for m in states], dtype=float),
        stamps_ns=np.array(stamps[STATE], dtype=np.int64),
        phases=tuple(m.phase for m in states),
        active_contacts=tuple(tuple(m.active_contacts) for m in states),
        q=_stack([m.q for m in states], "q", path),
        generalized_force=_stack([m.generalized_force for m in states], "generalized_force",
                                 path),
        kinetic_energy=np.array([m.kinetic_energy for m in states], dtype=float),
        potential_energy=np.array([m.potential_energy for m in states], dtype=float),
        contact_names=tuple(tuple(m.contact_names) for m in contacts),
        contact_points=tuple(_points(m.points) for m in contacts),
        contact_force_vectors=tuple(np.array([[f.x, f.y, f.z] for f in m.forces]).reshape(-1, 3)
                                    for m in contacts),
        # recordings made before the per-foot wrenches were published have none
        wrench_bodies=tuple(tuple(getattr(m, "wrench_bodies", ())) for m in contacts),
        wrench_points=tuple(_points(getattr(m, "wrench_points", ())) for m in contacts),
        wrenches=tuple(np.array([[w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y,
                                  w.torque.z] for w in getattr(m, "wrenches", ())]).reshape(-1, 6)
                       for m in contacts),
        centers_of_pressure=tuple(_points(getattr(m, "centers_of_pressure", ()))
                                  for m in contacts),
        joint_names=tuple(trajectory.joint_names),
        trajectory_stamp_ns=_ns(trajectory.header.stamp),
        time_from_start=np.array([_ns(p.time_from_start) * 1e-9 for p in points]),
        positions=_stack([p.positions for p in points], "positions", path),
        velocities=_stack([p.velocities for p in points], "velocities", path),
        accelerations=np.array([list(p.accelerations) for p in points], dtype=float),
        held_joint_names=tuple(getattr(states[0], "held_joint_names", ())),
        held_joint_impulses=np.array([list(getattr(m, "held_joint_impulses", ()))
                                      for m in states], dtype=float).reshape(len(states), -1),
        effort=_stack([p.effort for p in points], "effort", path),
        joint_state_position=_stack([m.position for m in joints], "position", path),
        joint_state_velocity=_stack([m.velocity for m in joints], "velocity", path),
        joint_state_effort=_stack([m.effort for m in joints], "effort", path),
        tf=tuple(tuple(_transform(t) for t in m.transforms) for _, m in decoded[TF]),
        tf_static=tuple(_transform(t) for _, m in decoded[TF_STATIC] for t in m.transforms),
        log_times_ns={t: np.array(v, dtype=np.int64) for t, v in log_times.items()},
        header_stamps_ns={t: np.array(v, dtype=np.int64) for t, v in stamps.items()},
    )
