"""Building a gait library on Ray (local, 2 workers): a 3 x 3 walker2d grid by
continuation, a worker killed mid-build, the driver killed and the build resumed."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import psutil
import pytest

from gait_planner.gaitlib.build import build_library
from gait_planner.gaitlib.index import INDEX, PLANS, LibraryIndex, Manifest
from gait_planner.verify import verify_recording

pytest.importorskip("ray")

GRID = "step_length=0.5/0.6/0.7,friction_coefficient=0.6/0.8/1.0"
MANIFEST = Manifest(scene="walker2d", gait="", grid=GRID, request={})
BIN = Path(sys.executable).parent  # the environment's commands


def _rows(folder: Path):
    if not (folder / INDEX).exists():
        return []
    index = LibraryIndex(folder)
    try:
        return index.rows()
    finally:
        index.close()


def _kill_a_planning_worker(folder: Path, killed: list, stop: threading.Event) -> None:
    """Once the first point is finished, SIGKILL a Ray worker that is planning a point."""
    while not stop.is_set() and not killed:
        if _rows(folder):
            for proc in psutil.process_iter(["pid", "cmdline"]):
                if any("_plan_point" in part for part in (proc.info["cmdline"] or [])):
                    os.kill(proc.info["pid"], signal.SIGKILL)
                    killed.append(proc.info["pid"])
                    return
        time.sleep(0.05)


def test_a_library_is_built_by_continuation_and_survives_a_killed_worker(tmp_path):
    """Every point finishes once, converged, from a finished neighbour unless it was a
    seed; a worker killed while planning costs that point a re-run, not the build; every
    recording passes the verifier."""
    killed: list[int] = []
    stop = threading.Event()
    watcher = threading.Thread(target=_kill_a_planning_worker, args=(tmp_path, killed, stop))
    watcher.start()
    try:
        summary = build_library(tmp_path, MANIFEST, workers=2, progress=lambda line: None)
    finally:
        stop.set()
        watcher.join()
    assert killed, "no worker was planning after the first point finished"
    rows = _rows(tmp_path)
    assert [r.name for r in rows] == sorted(f"p{i:02d}-{j:02d}" for i in range(3) for j in range(3))
    assert (summary.planned, summary.failed, summary.skipped) == (9, 0, 0)
    names = {r.name for r in rows}
    for row in rows:
        assert row.status == "ok", row.reason
        assert row.start == "cold" or row.start in names
        if row.start != "cold":  # a neighbour: one index away along one axis
            a, b = (tuple(int(k) for k in n[1:].split("-")) for n in (row.name, row.start))
            assert sum(abs(x - y) for x, y in zip(a, b)) == 1
        report = verify_recording(tmp_path / PLANS / row.mcap)
        assert report.ok, (row.name, report.failures)
    assert sum(r.start == "cold" for r in rows) <= 2  # the seeds: one per worker
    assert sum(r.iterations for r in rows if r.start != "cold") < \
        sum(r.iterations for r in rows if r.start == "cold") * 7 / 2


@pytest.mark.slow
def test_a_killed_build_resumes_without_repeating_a_finished_point(tmp_path):
    """The driver is killed (SIGKILL) once three points are finished; building again
    plans only the others, and the finished points' files are untouched."""
    command = [str(BIN / "gait-planner"), "library", "build",
               "--scene", "walker2d", "--grid", GRID, "--out", str(tmp_path), "--workers", "2"]
    driver = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True)
    try:
        deadline = time.monotonic() + 600
        while len(_rows(tmp_path)) < 3 and driver.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        os.killpg(driver.pid, signal.SIGKILL)
    finally:
        driver.wait()
    # its local Ray instance outlives a killed driver (as after any crash: `ray stop`)
    subprocess.run([str(BIN / "ray"), "stop", "--force"], capture_output=True, timeout=120)
    before = {r.name: r for r in _rows(tmp_path)}
    assert 3 <= len(before) < 9
    stamps = {name: (tmp_path / PLANS / row.mcap).stat().st_mtime_ns
              for name, row in before.items()}
    summary = build_library(tmp_path, MANIFEST, workers=2, progress=lambda line: None)
    assert summary.skipped == len(before) and summary.planned == 9 - len(before)
    after = {r.name: r for r in _rows(tmp_path)}
    assert len(after) == 9 and all(r.status == "ok" for r in after.values())
    for name, row in before.items():
        assert after[name] == row
        assert (tmp_path / PLANS / row.mcap).stat().st_mtime_ns == stamps[name]
    assert not list((tmp_path / PLANS).glob(".*.tmp"))
