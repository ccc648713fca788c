"""The helper process that writes .rrd files after a plan is answered: the file it writes
holds what `save_rrd` writes in the process, and a failure, a dead helper or a closed
recorder is reported, never raised into the node."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rerun")

from rerun.chunk import RrdReader  # noqa: E402

from gait_planner.viz.rerun_view import save_rrd  # noqa: E402
from gait_planner.viz.rrd_recorder import RrdRecorder  # noqa: E402

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
    helper = recorder._helper.process
    os.kill(helper.pid, signal.SIGKILL)  # as by the OOM killer
    helper.wait(WAIT)
    assert _submit(recorder, result, tmp_path / "second.rrd") == (
        (tmp_path / "second.rrd").resolve(), None)
    assert recorder._helper.process.pid != helper.pid


def test_files_given_to_a_helper_that_dies_are_reported(recorder, result, tmp_path):
    reports: queue.Queue = queue.Queue()
    recorder.submit(result, tmp_path / "a.rrd", lambda *report: reports.put(report))
    recorder.submit(result, tmp_path / "b.rrd", lambda *report: reports.put(report))
    os.kill(recorder._helper.process.pid, signal.SIGKILL)
    answers = [reports.get(timeout=WAIT) for _ in range(2)]
    for written, error in answers:  # written before the kill, or reported not written
        assert (written is None) != (error is None)
        if error is not None:
            assert "helper process ended" in str(error)


def test_a_script_without_a_main_guard_is_not_run_again(tmp_path):
    """The helper is no multiprocessing child: a script that records at its top level
    (no `if __name__ == "__main__"`) runs once, and its file is written."""
    script = tmp_path / "script.py"
    marker = tmp_path / "runs"
    script.write_text(
        "import sys\n"
        "sys.path.insert(0, sys.argv[1])\n"
        "import queue\n"
        "from synthetic_result import make_result\n"
        "from gait_planner.viz.rrd_recorder import RrdRecorder\n"
        f"open({str(marker)!r}, 'a').write('run\\n')\n"
        "reports = queue.Queue()\n"
        "recorder = RrdRecorder()\n"
        f"recorder.submit(make_result(), {str(tmp_path / 'top.rrd')!r}, "
        "lambda *r: reports.put(r))\n"
        "print(reports.get(timeout=120))\n"
        "recorder.close(120)\n")
    done = subprocess.run([sys.executable, str(script), str(Path(__file__).parents[1])],
                          capture_output=True, text=True, timeout=WAIT)
    assert done.returncode == 0, done.stderr
    assert marker.read_text() == "run\n"
    assert (tmp_path / "top.rrd").is_file() and "None)" in done.stdout


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
