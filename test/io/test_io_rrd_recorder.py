"""The helper process that writes .rrd files after a plan is answered: the file it writes
holds what `save_rrd` writes in the process, and a failure, a dead helper or a closed
recorder is reported, never raised into the node."""

from __future__ import annotations

import os
import queue
import signal
from pathlib import Path

import pytest

pytest.importorskip("rerun")

from rerun.chunk import RrdReader  # noqa: E402

from gait_planner.io.rerun_view import save_rrd  # noqa: E402
from gait_planner.io.rrd_recorder import RrdRecorder  # noqa: E402

WAIT = 120  # s for a helper to start (imports rerun) and write one file


@pytest.fixture
def recorder():
    rec = RrdRecorder()
    yield rec
    rec.close(WAIT)


def _submit(recorder: RrdRecorder, result, path: Path):
    """(path, error) that `done` was given."""
    reports: queue.Queue = queue.Queue()
    recorder.submit(result, path, lambda *report: reports.put(report))
    return reports.get(timeout=WAIT)


def _contents(path: Path) -> list[tuple]:
    """(entity, static, rows) of every chunk: the data, not the recording's ids and times."""
    return sorted((c.entity_path, c.is_static, c.to_record_batch().num_rows)
                  for c in RrdReader(path).stream())


def test_the_helper_writes_what_save_rrd_writes(recorder, result, tmp_path):
    written, error = _submit(recorder, result, tmp_path / "plan.rrd")
    assert error is None and written == (tmp_path / "plan.rrd").resolve()
    here = save_rrd(result, tmp_path / "here.rrd")
    assert _contents(written) == _contents(here)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["here.rrd", "plan.rrd"]


def test_a_failed_write_is_reported_and_the_next_one_written(recorder, result, tmp_path):
    written, error = _submit(recorder, result, tmp_path / "missing" / "plan.rrd")
    assert written is None and isinstance(error, OSError)
    assert "missing" in str(error)
    written, error = _submit(recorder, result, tmp_path / "plan.rrd")
    assert error is None and written.is_file()


def test_a_dead_helper_is_replaced(recorder, result, tmp_path):
    _submit(recorder, result, tmp_path / "first.rrd")
    for pid in list(recorder._pool._processes):  # the helper, killed as by the OOM killer
        os.kill(pid, signal.SIGKILL)
    reports = [_submit(recorder, result, tmp_path / "second.rrd")]
    if reports[0][1] is not None:  # submitted before the pool saw its helper die
        reports.append(_submit(recorder, result, tmp_path / "second.rrd"))
    assert reports[-1] == ((tmp_path / "second.rrd").resolve(), None)


def test_a_closed_recorder_reports_at_once(result, tmp_path):
    recorder = RrdRecorder()
    assert recorder.close(WAIT)
    written, error = _submit(recorder, result, tmp_path / "late.rrd")
    assert written is None and "late.rrd" in str(error) and "closed" in str(error)
    assert not (tmp_path / "late.rrd").exists()


def test_close_waits_until_the_files_submitted_are_reported(result, tmp_path):
    recorder = RrdRecorder()
    reports: queue.Queue = queue.Queue()
    for name in ("a", "b"):
        recorder.submit(result, tmp_path / f"{name}.rrd", lambda *report: reports.put(report))
    assert recorder.close(WAIT)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.rrd", "b.rrd"]
    assert {reports.get_nowait()[1] for _ in range(2)} == {None}  # reported before close returned
