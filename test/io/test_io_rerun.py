"""The rerun view: a saved .rrd is complete, loadable and holds the expected entities."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

rr = pytest.importorskip("rerun")

from gait_planner.io.rerun_view import log_plan, save_rrd, show  # noqa: E402

RERUN = Path(sys.executable).with_name("rerun")


def _rerun_cli() -> str | None:
    return str(RERUN) if RERUN.is_file() else shutil.which("rerun")


@pytest.fixture(scope="module")
def rrd(result, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("rrd") / "plan.rrd"
    assert save_rrd(result, path) == path.resolve()
    return path


def test_saved_rrd_is_non_empty_and_alone(rrd):
    assert rrd.stat().st_size > 10_000
    assert sorted(p.name for p in rrd.parent.iterdir()) == ["plan.rrd"]  # no temporary file


@pytest.mark.skipif(_rerun_cli() is None, reason="the rerun CLI (rerun-sdk) is not installed")
def test_rrd_verify_and_entities(rrd, result):
    done = subprocess.run([_rerun_cli(), "rrd", "verify", str(rrd)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    stats = subprocess.run([_rerun_cli(), "rrd", "stats", str(rrd)], capture_output=True,
                           text=True, timeout=120)
    assert stats.returncode == 0, stats.stderr
    for entity in ("/world/walker/torso", "/world/walker/foot_l", "/world/contacts/forces",
                   "/world/skeleton", "/plots/joint_angle/knee_r",
                   "/plots/joint_torque/hip_l_yaw", "/plots/contact_force/foot_r_heel/z",
                   "/plots/energy/total", "/plan"):
        assert entity in stats.stdout, entity


def test_failed_save_leaves_nothing(result, tmp_path, monkeypatch):
    import gait_planner.io.rerun_view as view

    def fail(*_args):
        raise RuntimeError("logging failed")

    monkeypatch.setattr(view, "_log_series", fail)
    with pytest.raises(RuntimeError, match="logging failed"):
        save_rrd(result, tmp_path / "plan.rrd")
    assert list(tmp_path.iterdir()) == []


def test_log_plan_into_a_memory_recording(result):
    rec = rr.RecordingStream("gait_planner_test")
    memory = rec.memory_recording()
    log_plan(result, rec)
    rec.flush()
    assert len(memory.drain_as_bytes()) > 10_000


def test_log_plan_with_a_node_without_contacts(result, make_result):
    active = (result.active_contacts[0], ()) + result.active_contacts[2:]
    rec = rr.RecordingStream("gait_planner_test")
    memory = rec.memory_recording()
    log_plan(make_result(active_contacts=active), rec)
    rec.flush()
    assert len(memory.drain_as_bytes()) > 0


def test_show_without_display_says_what_to_do(result, monkeypatch):
    if not sys.platform.startswith("linux"):
        pytest.skip("the display check applies to Linux")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(RuntimeError, match="save_rrd"):
        show(result)
