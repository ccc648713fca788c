"""`gait-planner call --action` against a real node: feedback lines as they arrive, the
result, a rejection while the node is busy, and Ctrl-C (SIGINT) canceling the goal with
nothing recorded."""

from __future__ import annotations

import queue
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

pytestmark = pytest.mark.timeout(180)

GAIT_PLANNER = str(Path(sys.executable).parent / "gait-planner")


def _call(*arguments: str) -> tuple[subprocess.Popen, queue.Queue]:
    """Start `gait-planner call --action ARGUMENTS`; its stderr lines arrive in the queue,
    then None. Its SIGINT is the default whatever the suite inherited: a shell starts a
    background job with SIGINT ignored, and Python then keeps ignoring it (the Ctrl-C test
    failed so in a fresh clone's `make test-slow` started with `&`, 2026-11-29; CI's
    `timeout` gives its child the default)."""
    process = subprocess.Popen([GAIT_PLANNER, "call", "--action", *arguments],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    lines: queue.Queue = queue.Queue()

    def read() -> None:
        for line in process.stderr:
            lines.put(line)
        lines.put(None)

    threading.Thread(target=read, daemon=True).start()
    return process, lines


def _finish(process: subprocess.Popen, lines: queue.Queue, timeout: float) -> tuple[str, list]:
    """Wait for the call to end: its stdout and its remaining stderr lines."""
    out = process.stdout.read()
    process.wait(timeout)
    return out, list(iter(lambda: lines.get(timeout=timeout), None))


def _until(lines: queue.Queue, words: str, timeout: float = 60.0) -> list[str]:
    seen = []
    while True:
        line = lines.get(timeout=timeout)
        seen.append(line)
        if words in line:
            return seen


def test_call_action_prints_feedback_and_the_result(planner_node, tmp_path):
    planner_node(default_scene="compass", compile_derivatives=False)
    process, lines = _call("--cold-start", "--output-name", "called", "--timeout", "120")
    out, err = _finish(process, lines, 150)
    assert process.returncode == 0, out + "".join(err)
    assert "status: succeeded" in out and f"mcap_path: {tmp_path / 'called.mcap'}" in out
    solver = [line for line in err if "iteration" in line]
    assert solver and all("cost" in line and "violation" in line for line in solver)
    assert any(line.split()[2:3] == ["building"] for line in err)


@pytest.mark.slow
def test_a_busy_node_rejects_and_ctrl_c_cancels_the_goal(node_process, tmp_path):
    """Against a `gait-planner node` process, as a user runs it. With the node inside the
    test process (`planner_node`) the Ctrl-C's cancel did not stop the plan in three
    fresh-clone runs of the whole suite on 2026-11-25 (one of them of code that had passed
    CI the same morning), with the plan running 5 s or 17 s after the second call's
    rejection; alone the test passed every time. The first goal is walker2d on 16 intervals
    per phase, uncompiled (about 10 s), so that it still runs when the second call ends."""
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    node_process("--ros-args", "-p", "default_scene:=walker2d",
                 "-p", "compile_derivatives:=false", "-p", "prepare_on_start:=false",
                 "-p", "warm_start_store:=false", "-p", f"output_dir:={out_dir}",
                 "-p", f"allowed_output_dirs:=['{out_dir}']")
    process, lines = _call("--cold-start", "--intervals-per-phase", "16",
                           "--output-name", "interrupted")
    _until(lines, "building")
    second = subprocess.run([GAIT_PLANNER, "call", "--action", "--scene", "compass"],
                            capture_output=True, text=True, timeout=60)
    assert second.returncode == 1
    assert second.stdout.startswith("rejected: busy") and len(second.stdout.splitlines()) == 1
    process.send_signal(signal.SIGINT)
    out, err = _finish(process, lines, 60)
    assert out == "canceled: stopped on request\n", out + "".join(err)
    assert any("cancel accepted" in line for line in err), err
    assert process.returncode == 1
    assert not list(out_dir.glob("*.mcap"))
