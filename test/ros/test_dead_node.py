"""`gait-planner call` (service and action) against a node process that dies mid-plan: the
call ends with an error naming the cause within `DEAD_WITHIN` s of the signal, whether the
node stops (SIGTERM: it leaves the ROS graph at once) or is killed (SIGKILL: it leaves when
its DDS lease, `gait_planner.ros.node.DDS_PROFILE`, ends), instead of waiting for its
timeout. The client's rule itself (seen, then gone for a grace period) is checked without
ROS in `test_presence_*`."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gait_planner.ros.client import GONE_GRACE, NodeGone, Presence

pytestmark = pytest.mark.timeout(300)

GAIT_PLANNER = str(Path(sys.executable).parent / "gait-planner")
DEAD_WITHIN = 10.0  # s from the signal to the call's end
START_WAIT = 120.0  # s for the node to serve and its plan to iterate (a loaded machine)


def _wait_for(log: Path, words: str, process: subprocess.Popen, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while words not in log.read_text(errors="replace"):
        assert process.poll() is None, log.read_text(errors="replace")
        assert time.monotonic() < deadline, f"no {words!r} in the node's log within {timeout} s"
        time.sleep(0.1)


@pytest.mark.parametrize("signum, action", [
    (signal.SIGTERM, False), (signal.SIGTERM, True),
    (signal.SIGKILL, False), (signal.SIGKILL, True),
])
def test_a_call_ends_soon_after_its_node_dies(node_process, tmp_path, signum, action):
    out = tmp_path / "out"
    out.mkdir()
    node = node_process("--ros-args", "-p", "default_scene:=walker3d",
                        "-p", "prepare_on_start:=false", "-p", "warm_start_store:=false",
                        "-p", f"output_dir:={out}", "-p", f"allowed_output_dirs:=['{out}']")
    log = tmp_path / "node.log"
    _wait_for(log, "serving the service and the action", node, START_WAIT)
    call = subprocess.Popen([GAIT_PLANNER, "call", "--cold-start", "--timeout", "600",
                             *(["--action"] if action else [])],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for(log, "iteration 0:", node, START_WAIT)  # the solve runs
        signalled = time.monotonic()
        node.send_signal(signum)
        try:
            call.wait(timeout=DEAD_WITHIN + 20)
        except subprocess.TimeoutExpired:
            pytest.fail(f"the call still waits {DEAD_WITHIN + 20} s after the node's "
                        f"{signal.Signals(signum).name}")
        took = time.monotonic() - signalled
        out_text, err_text = call.communicate()
    finally:
        if call.poll() is None:
            call.kill()
            call.wait()
    how = f"{signal.Signals(signum).name}, {'action' if action else 'service'}"
    if call.returncode == 1:  # a stopping node may still answer its plan: stopped
        assert signum == signal.SIGTERM, out_text + err_text
        # "failed: stopped: the node is shutting down (...)", "refused: the node is shutting down"
        assert re.fullmatch(r"(failed|refused|aborted|canceled): [^\n]*shutting down[^\n]*\n",
                            out_text), out_text
    else:
        assert call.returncode == 2, out_text + err_text
        assert out_text == ""
        error = err_text.strip().splitlines()[-1]
        assert error.startswith("gait-planner: error: the node serving /gait_planner/plan_gait "
                                "left the ROS graph"), err_text
        assert "without answering (it stopped or died" in error
    assert took < DEAD_WITHIN, f"{how}: the call ended {took:.1f} s after the signal"
    print(f"{how}: the call ended {took:.2f} s after the signal: "
          f"{(out_text or err_text).strip().splitlines()[-1]}")


class _Graph:
    """A server's presence in the graph over a fake clock: `ready()` at each `now`."""

    def __init__(self, monkeypatch, *absent: tuple[float, float]):
        self.now, self.absent = 0.0, absent
        monkeypatch.setattr("gait_planner.ros.client.time.monotonic", lambda: self.now)

    def ready(self) -> bool:
        return not any(start <= self.now < end for start, end in self.absent)


def test_presence_forgives_an_absence_shorter_than_the_grace(monkeypatch):
    graph = _Graph(monkeypatch, (1.0, 1.0 + GONE_GRACE - 0.2), (5.0, 5.0 + GONE_GRACE - 0.2))
    presence = Presence(graph.ready, "/x")
    for step in range(100):
        graph.now = step * 0.1
        presence.check()  # never raises


def test_presence_declares_a_server_gone_after_the_grace(monkeypatch):
    graph = _Graph(monkeypatch, (3.0, float("inf")))
    presence = Presence(graph.ready, "/gait_planner/plan_gait")
    checked = []
    with pytest.raises(NodeGone, match="left the ROS graph 2.0 s ago without answering"):
        for step in range(100):
            graph.now = step * 0.1
            checked.append(graph.now)
            presence.check()
    assert checked[-1] == pytest.approx(2.9 + GONE_GRACE)  # last seen at 2.9 s
