"""Replay anywhere: one recording per scene, read by four programs that share no code with
the writer: mcap_ros2's decoder, rclpy (the real message classes), rosbags (its own ROS 2
Kilted definitions plus ours from msg_defs/msg) and rerun (`rerun mcap convert`)."""

from __future__ import annotations

import importlib
import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.interfaces import QosDurability, QosReliability
from rosbags.rosbag2.storage_mcap import McapReader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from gait_planner.io import messages
from gait_planner.io.mcap_writer import LATCHED, TOPICS
from gait_planner.io.urdf import kinematic_tree

from io_msgdef import MSG_DEFS

SCENES = ("walker3d", "walker2d", "compass")
START_NS = 1_700_000_000_123_456_789
NS = 1_000_000_000
RERUN = Path(sys.executable).with_name("rerun")


def expected_messages(result, start_ns: int) -> dict[str, list[dict[str, Any]]]:
    """topic -> the message dicts the recording must hold (docs/design.md section 7)."""
    tree = kinematic_tree(result.scene)
    return {
        "/robot_description": [messages.robot_description(result)],
        "/tf_static": [messages.tf_static(result, start_ns, tree)],
        "/gait_planner/joint_trajectory": [messages.joint_trajectory(result, start_ns)],
        "/gait_planner/state": messages.multibody_states(result, start_ns),
        "/gait_planner/contact_forces": messages.contact_forces(result, start_ns),
        "/tf": messages.tf_messages(result, start_ns, tree),
        "/joint_states": messages.joint_states(result, start_ns),
    }


@pytest.fixture(scope="module", params=SCENES)
def plan(request, make_result, tmp_path_factory) -> SimpleNamespace:
    from gait_planner.io.mcap_writer import write_plan_mcap

    result = make_result(request.param, intervals=10 if request.param == "walker3d" else 6)
    path = write_plan_mcap(result, tmp_path_factory.mktemp(request.param) / "plan.mcap",
                           START_NS)
    return SimpleNamespace(result=result, path=path,
                           expected=expected_messages(result, START_NS))


def _raw(path: Path) -> list[tuple[str, str, int, bytes]]:
    """(topic, ROS type, log time, CDR bytes) of every message, in log-time order."""
    with path.open("rb") as stream:
        reader = make_reader(stream, validate_crcs=True)
        return [(c.topic, s.name, m.log_time, m.data) for s, c, m in reader.iter_messages()]


def _plain(value: Any) -> Any:
    if isinstance(value, SimpleNamespace):  # mcap_ros2's messages: slotted namespaces
        names = getattr(type(value), "__slots__", None) or list(vars(value))
        return {k: _plain(getattr(value, k)) for k in names}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def test_counts_and_order(plan):
    counts = {topic: 0 for topic in TOPICS}
    for topic, ros_type, _, _ in _raw(plan.path):
        assert ros_type == TOPICS[topic][0]
        counts[topic] += 1
    assert counts == {topic: len(msgs) for topic, msgs in plan.expected.items()}


def test_mcap_ros2_decodes_every_message_as_built(plan):
    """mcap_ros2's public decoder, from the schemas in the file, gives back exactly the
    dicts of `gait_planner.io.messages`: every field, every float bit."""
    seen = {topic: 0 for topic in TOPICS}
    with plan.path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages():
            topic = channel.topic
            assert _plain(decoded) == plan.expected[topic][seen[topic]], topic
            assert message.publish_time == message.log_time
            header = getattr(decoded, "header", None)
            if header is not None and topic != "/gait_planner/joint_trajectory":
                assert header.stamp.sec * NS + header.stamp.nanosec == message.log_time
            seen[topic] += 1
    assert seen == {topic: len(msgs) for topic, msgs in plan.expected.items()}


@pytest.mark.skipif(importlib.util.find_spec("rclpy") is None, reason="rclpy is not installed")
def test_rclpy_reads_what_the_node_publishes(plan):
    """Each recorded message of a type with an installed class (all but tf2_msgs, which has
    no wheel) deserialises with rclpy into the message the node publishes (`fill_message`)."""
    from rclpy.serialization import deserialize_message

    seen = {topic: 0 for topic in TOPICS}
    types = set()
    for topic, ros_type, _, data in _raw(plan.path):
        package, _, name = ros_type.split("/")
        index, seen[topic] = seen[topic], seen[topic] + 1
        if importlib.util.find_spec(package) is None:
            continue
        cls = getattr(importlib.import_module(f"{package}.msg"), name)
        built = messages.fill_message(cls(), plan.expected[topic][index])
        assert deserialize_message(data, cls) == built, (topic, index)
        types.add(ros_type)
    assert {"std_msgs/msg/String", "trajectory_msgs/msg/JointTrajectory",
            "sensor_msgs/msg/JointState"} <= types


# ---------------------------------------------------------------------------- rosbags


def _kilted_store():
    """rosbags' ROS 2 Kilted types plus gait_planner_msgs from its .msg sources."""
    store = get_typestore(Stores.ROS2_KILTED)
    for path in sorted((MSG_DEFS / "msg").glob("*.msg")):
        store.register(get_types_from_msg(path.read_text(), f"gait_planner_msgs/msg/{path.stem}"))
    return store


def _rosbags_messages(path: Path, store) -> tuple[list, list[tuple[str, int, Any, bytes]]]:
    reader = McapReader(path)
    reader.open()
    try:
        connections = list(reader.connections)
        found = [(c.topic, t, store.deserialize_cdr(data, c.msgtype), bytes(data))
                 for c, t, data in reader.messages(connections)]
    finally:
        reader.close()
    return connections, found


def test_rosbags_reads_topics_qos_counts_and_values(plan):
    store = _kilted_store()
    connections, found = _rosbags_messages(plan.path, store)
    assert {c.topic: c.msgtype for c in connections} == {t: v[0] for t, v in TOPICS.items()}
    for c in connections:
        (qos,) = c.ext.offered_qos_profiles
        assert qos.reliability is QosReliability.RELIABLE
        assert qos.durability is (QosDurability.TRANSIENT_LOCAL if TOPICS[c.topic][1] is LATCHED
                                  else QosDurability.VOLATILE)
    by_topic: dict[str, list] = {topic: [] for topic in TOPICS}
    for topic, stamp, msg, data in found:
        # rosbags' own definitions re-encode the very bytes: same layout, field for field
        assert bytes(store.serialize_cdr(msg, msg.__msgtype__)) == data
        by_topic[topic].append((stamp, msg))
    assert {t: len(v) for t, v in by_topic.items()} == {
        t: len(v) for t, v in plan.expected.items()}

    result = plan.result
    stamps = messages.node_stamps_ns(result, START_NS)
    for n, (stamp, state) in enumerate(by_topic["/gait_planner/state"]):
        assert stamp == stamps[n] == state.header.stamp.sec * NS + state.header.stamp.nanosec
        assert state.node == n and state.phase == result.phases[n]
        assert np.array_equal(state.q, result.q[n])
        assert state.kinetic_energy == result.kinetic_energy[n]
    for n, (_, forces) in enumerate(by_topic["/gait_planner/contact_forces"]):
        assert forces.contact_names == list(result.active_contacts[n])
        for name, force in zip(forces.contact_names, forces.forces):
            assert [force.x, force.y, force.z] == list(result.contact_forces[name][n])
    ((_, trajectory),) = by_topic["/gait_planner/joint_trajectory"]
    assert trajectory.joint_names == list(result.joint_angle_names)
    assert np.array_equal([p.positions for p in trajectory.points], result.joint_angles)
    for n, (_, joints) in enumerate(by_topic["/joint_states"]):
        assert np.array_equal(joints.position, result.joint_angles[n])
    ((_, description),) = by_topic["/robot_description"]
    assert description.data == messages.robot_description(result)["data"]
    tree = kinematic_tree(result.scene)
    for _, tf in by_topic["/tf"]:
        assert [t.child_frame_id for t in tf.transforms] == (
            [tree.root] + [j.child for j in tree.moving_joints])


def test_rosbags_reads_with_the_embedded_schemas_alone(plan):
    """The README's way: no .msg files, the types come from the schemas in the file."""
    reader = McapReader(plan.path)
    reader.open()
    try:
        store = get_typestore(Stores.EMPTY)
        for c in reader.connections:
            store.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        count = sum(1 for c, _, data in reader.messages(reader.connections)
                    if store.deserialize_cdr(data, c.msgtype).__msgtype__ == c.msgtype)
    finally:
        reader.close()
    assert count == sum(len(v) for v in plan.expected.values())


# ---------------------------------------------------------------------------- rerun


def _rerun_cli() -> str | None:
    return str(RERUN) if RERUN.is_file() else shutil.which("rerun")


@pytest.mark.skipif(_rerun_cli() is None, reason="the rerun CLI (rerun-sdk) is not installed")
def test_rerun_converts_to_an_rrd_that_loads(plan, tmp_path):
    from rerun.chunk import RrdReader

    rrd = tmp_path / "plan.rrd"
    done = subprocess.run([_rerun_cli(), "mcap", "convert", str(plan.path), "-o", str(rrd)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    done = subprocess.run([_rerun_cli(), "rrd", "verify", str(rrd)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr

    rows = {topic: 0 for topic in TOPICS}
    states = {}
    for chunk in RrdReader(rrd).store().stream():
        topic = str(chunk.entity_path)
        if chunk.is_static or topic not in rows:
            continue
        rows[topic] += chunk.num_rows
        if topic == "/gait_planner/state":
            batch = chunk.to_record_batch()
            column = batch.column("gait_planner_msgs.msg.MultibodyState:message").to_pylist()
            stamps = batch.column("ros2_timestamp").cast("int64").to_pylist()  # ns
            for (state,), stamp in zip(column, stamps):
                states[state["node"]] = (state, stamp)
    expected = plan.expected
    # one row per message; rerun gives /tf and /tf_static one row per transform
    assert rows == {topic: sum(len(m["transforms"]) for m in msgs) if topic.startswith("/tf")
                    else len(msgs) for topic, msgs in expected.items()}
    result = plan.result
    stamps = messages.node_stamps_ns(result, START_NS)
    assert sorted(states) == list(range(result.n_nodes))
    for n, (state, stamp) in states.items():
        assert state["q"] == list(result.q[n]) and stamp == stamps[n]
        assert state["active_contacts"] == list(result.active_contacts[n])
