"""The MCAP recording: ROS 2 profile, round trip through the reader, atomic writes."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader

from gait_planner.io import mcap_writer, messages
from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.io.mcap_writer import TOPICS, write_plan_mcap
from gait_planner.io.ros_definitions import schema_text
from gait_planner.model.angles import angle_names

RERUN = Path(sys.executable).with_name("rerun")
KEYS = ("scene", "cost", "cost_value", "step_length", "duration", "friction_coefficient",
        "phase_scaling", "solve_time_s", "iterations", "nodes", "periodicity")
PER_NODE = ("/gait_planner/state", "/gait_planner/contact_forces", "/tf", "/joint_states")
LATCHED = ("/robot_description", "/tf_static")


@pytest.fixture(scope="module")
def recording(result, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("mcap") / "plan.mcap"
    assert write_plan_mcap(result, path, 1_700_000_000_123_456_789) == path.resolve()
    return path


@pytest.fixture(scope="module")
def recorded(recording):
    return read_plan_mcap(recording)


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_round_trip(result, recorded, start_ns):
    assert recorded.n_nodes == result.n_nodes
    assert np.array_equal(recorded.q, result.q)
    assert np.array_equal(recorded.generalized_force, result.generalized_force)
    assert np.array_equal(recorded.kinetic_energy, result.kinetic_energy)
    assert np.array_equal(recorded.potential_energy, result.potential_energy)
    assert np.array_equal(recorded.times, result.times - result.times[0])
    assert recorded.phases == result.phases
    assert recorded.active_contacts == result.active_contacts
    assert recorded.body_names == result.body_names
    assert recorded.contact_names == result.active_contacts
    for name, forces in result.contact_forces.items():
        assert np.array_equal(recorded.contact_force(name), forces)
    for n in range(result.n_nodes):
        wrenches = messages.foot_wrenches(result, n)
        assert recorded.wrench_bodies[n] == tuple(w[0] for w in wrenches)
        assert np.array_equal(recorded.wrench_points[n], np.array([w[1] for w in wrenches]))
        assert np.array_equal(recorded.wrenches[n],
                              np.array([np.r_[w[2], w[3]] for w in wrenches]))
        assert np.array_equal(recorded.centers_of_pressure[n], np.array([w[4] for w in wrenches]))
    assert recorded.joint_names == result.joint_angle_names == angle_names(result.scene)
    assert np.array_equal(recorded.positions, result.joint_angles)
    assert np.array_equal(recorded.velocities, result.joint_velocities)
    assert np.array_equal(recorded.accelerations, result.joint_accelerations)
    assert np.array_equal(recorded.effort, messages.node_efforts(result))
    assert np.array_equal(recorded.joint_state_position, result.joint_angles)
    assert np.allclose(recorded.time_from_start, recorded.times, atol=1e-9)
    assert recorded.trajectory_stamp_ns == start_ns
    assert recorded.scene_text == result.scene.source
    assert recorded.urdf.startswith("<?xml") and "<robot" in recorded.urdf


def test_metadata_keys_and_values(result, recorded):
    meta = recorded.metadata
    assert set(KEYS) <= set(meta)
    assert all(isinstance(v, str) for v in meta.values())
    assert meta["scene"] == "walker3d" and meta["cost"] == "kinetic_energy"
    assert float(meta["cost_value"]) == result.cost_value
    assert float(meta["duration"]) == result.duration
    assert [float(s) for s in meta["phase_scaling"].split(",")] == list(result.phase_scaling)
    assert int(meta["iterations"]) == 42 and int(meta["nodes"]) == result.n_nodes
    assert meta["torque_weight"] == "1e-06"  # result.settings entries
    assert list(recorded.attachments) == ["walker3d.yaml"]


def test_ros2_profile_schemas_and_qos(recording, recorded):
    assert recorded.profile == "ros2"
    assert set(recorded.channels) == set(TOPICS)
    for topic, channel in recorded.channels.items():
        assert channel.schema_encoding == "ros2msg" and channel.message_encoding == "cdr"
        assert channel.schema_name == TOPICS[topic][0]
        profiles = yaml.safe_load(channel.metadata["offered_qos_profiles"])
        assert isinstance(profiles, list) and len(profiles) == 1
        qos = profiles[0]
        assert qos["reliability"] == "reliable"
        assert qos["durability"] == ("transient_local" if topic in LATCHED else "volatile")
        assert {"history", "depth", "deadline", "lifespan", "liveliness",
                "liveliness_lease_duration", "avoid_ros_namespace_conventions"} <= set(qos)
    with recording.open("rb") as stream:
        schemas = make_reader(stream).get_summary().schemas.values()
    for schema in schemas:
        text = schema.data.decode()
        sections = text.split("\n" + "=" * 80 + "\nMSG: ")
        names = [s.split("\n", 1)[0] for s in sections[1:]]
        assert len(names) == len(set(names)), schema.name  # each nested type once
        if "Header" in text:
            assert "std_msgs/Header" in names and "builtin_interfaces/Time" in names
    by_name = {s.name: s.data.decode() for s in schemas}
    tf_names = [s.split("\n", 1)[0] for s in
                by_name["tf2_msgs/msg/TFMessage"].split("MSG: ")[1:]]
    assert tf_names == ["geometry_msgs/TransformStamped", "geometry_msgs/Transform",
                        "geometry_msgs/Quaternion", "geometry_msgs/Vector3", "std_msgs/Header",
                        "builtin_interfaces/Time"]  # rosbag2's depth-first, sorted order


def test_log_times_equal_header_stamps(result, recorded, start_ns):
    for topic in PER_NODE:
        assert len(recorded.log_times_ns[topic]) == result.n_nodes
        assert np.array_equal(recorded.log_times_ns[topic], recorded.header_stamps_ns[topic])
    assert np.array_equal(recorded.stamps_ns,
                          start_ns + np.round((result.times - result.times[0]) * 1e9))
    for topic in ("/gait_planner/joint_trajectory", "/tf_static"):
        assert list(recorded.log_times_ns[topic]) == [start_ns]
        assert list(recorded.header_stamps_ns[topic]) == [start_ns]
    assert list(recorded.log_times_ns["/robot_description"]) == [start_ns]


def test_recorded_tf_reproduces_body_poses(result, recorded):
    static = {t.child: (t.parent, t.matrix()) for t in recorded.tf_static}
    for n, transforms in enumerate(recorded.tf):
        tree = {**{t.child: (t.parent, t.matrix()) for t in transforms}, **static}
        for i, body in enumerate(result.scene.bodies):
            frame, T = body.name, np.eye(4)
            while frame != "world":
                parent, step = tree[frame]
                T, frame = step @ T, parent
            D = result.q[n, 12 * i + 3:12 * i + 12].reshape(3, 3).T
            assert np.abs(T[:3, :3] - D).max() < 1e-9


def test_write_is_atomic_and_refuses_bad_results(result, make_result, tmp_path, monkeypatch):
    q = result.q.copy()
    q[5, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        write_plan_mcap(make_result(q=q), tmp_path / "nan.mcap")
    assert _leftovers(tmp_path) == []

    # a failure after the messages were written (the metadata comes last) leaves nothing,
    # and an existing file is replaced only by a complete new one
    def fail(_result):
        raise RuntimeError("disk full, say")

    target = tmp_path / "keep.mcap"
    target.write_bytes(b"old")
    monkeypatch.setattr(mcap_writer, "plan_metadata", fail)
    for path in (tmp_path / "broken.mcap", target):
        with pytest.raises(RuntimeError, match="disk full"):
            write_plan_mcap(result, path)
    assert target.read_bytes() == b"old" and _leftovers(tmp_path) == ["keep.mcap"]


def test_unwritable_path_leaves_nothing(result, tmp_path):
    with pytest.raises(FileNotFoundError):
        write_plan_mcap(result, tmp_path / "missing" / "plan.mcap")
    (tmp_path / "a_file").write_text("")
    with pytest.raises(NotADirectoryError):
        write_plan_mcap(result, tmp_path / "a_file" / "plan.mcap")
    (tmp_path / "a_folder.mcap").mkdir()
    with pytest.raises(ValueError, match="is a directory"):
        write_plan_mcap(result, tmp_path / "a_folder.mcap")
    assert _leftovers(tmp_path) == ["a_file", "a_folder.mcap"]
    assert _leftovers(tmp_path / "a_folder.mcap") == []


@pytest.mark.skipif(os.geteuid() == 0, reason="running as root: a read-only folder is writable")
def test_read_only_folder_leaves_nothing(result, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    with pytest.raises(PermissionError):
        write_plan_mcap(result, locked / "plan.mcap")
    assert _leftovers(locked) == []


def test_allowed_dirs(result, tmp_path):
    inside = tmp_path / "runs"
    (inside / "sub").mkdir(parents=True)
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    write_plan_mcap(result, inside / "sub" / "a.mcap", allowed_dirs=[inside])
    with pytest.raises(ValueError, match="outside the allowed output folders"):
        write_plan_mcap(result, outside / "b.mcap", allowed_dirs=[inside])
    with pytest.raises(ValueError, match="outside the allowed output folders"):
        write_plan_mcap(result, inside / ".." / "elsewhere" / "c.mcap", allowed_dirs=[inside])
    link = inside / "link"
    link.symlink_to(outside)
    with pytest.raises(ValueError, match="outside the allowed output folders"):
        write_plan_mcap(result, link / "d.mcap", allowed_dirs=[inside])
    assert _leftovers(outside) == []


@pytest.mark.skipif(not RERUN.is_file() and shutil.which("rerun") is None,
                    reason="the rerun CLI (rerun-sdk) is not installed")
def test_rerun_mcap_check(recording):
    rerun = str(RERUN) if RERUN.is_file() else shutil.which("rerun")
    help_text = subprocess.run([rerun, "mcap", "--help"], capture_output=True, text=True)
    if "check" not in help_text.stdout:
        pytest.skip("this rerun CLI has no `rerun mcap check`")
    for extra in ([], ["--full"]):
        done = subprocess.run([rerun, "mcap", "check", *extra, str(recording)],
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stdout + done.stderr
        rows = [line.split() for line in done.stdout.splitlines()
                if line.split()[:1] and line.split()[0] in ("ok", "warn", "error", "fail")]
        assert rows and all(row[0] == "ok" for row in rows), done.stdout
        assert {row[3] for row in rows if row[1] != "?"} == set(TOPICS)


@pytest.mark.parametrize("scene_name", ["walker2d", "compass"])
def test_planar_scenes_round_trip(scene_name, make_result, tmp_path):
    result = make_result(scene_name, intervals=4)
    recorded = read_plan_mcap(write_plan_mcap(result, tmp_path / "plan.mcap", 5 * 10**9))
    assert np.array_equal(recorded.q, result.q)
    assert recorded.joint_names == result.joint_angle_names
    assert recorded.scene_text == result.scene.source
    assert recorded.metadata["scene"] == scene_name


def test_same_plan_same_bytes(result, tmp_path):
    """Encoding zeroes CDR padding: recording a plan twice gives the same file."""
    first = write_plan_mcap(result, tmp_path / "a.mcap", 5 * 10**9)
    again = write_plan_mcap(result, tmp_path / "b.mcap", 5 * 10**9)
    assert first.read_bytes() == again.read_bytes()


def test_encoder_takes_exactly_the_fields_of_the_type():
    string = "std_msgs/msg/String"
    encoder = mcap_writer.encoder_for(((string, schema_text(string)),))
    assert encoder.encode(string, {"data": "ab"}) == b"\x00\x01\x00\x00\x03\x00\x00\x00ab\x00"
    for wrong in ({}, {"data": "ab", "extra": 1}):
        with pytest.raises(ValueError, match=r"has the fields \['data'\]"):
            encoder.encode(string, wrong)
