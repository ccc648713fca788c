"""Crash safety: a recorder killed (SIGKILL) at any moment leaves under a final .mcap name
only complete recordings, and `remove_stale_temporaries` removes its leftovers and nothing
else."""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from gait_planner.atomic import remove_stale_temporaries
from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.io.mcap_writer import TOPICS

PER_NODE = ("/gait_planner/state", "/gait_planner/contact_forces", "/tf", "/joint_states")

# The child plans compass (a real plan, about 1 s), says READY on its stdout (the solver's
# own output goes to /dev/null) and then records the plan again and again under three names.
CHILD = """
import itertools, os, sys
from pathlib import Path
ready = os.fdopen(os.dup(1), "w")
os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
scene = load_scene("compass")
result = plan_once(Planner(), scene, settings_for(scene))
assert result.success, result.message
print("READY", result.n_nodes, file=ready, flush=True)
for i in itertools.count():
    write_plan_mcap(result, Path(sys.argv[1]) / f"plan{i % 3}.mcap", 1_700_000_000 * 10**9)
"""


def _dead_pid() -> int:
    done = subprocess.Popen(["true"])
    done.wait()
    return done.pid


def _decoys(folder: Path, dead: int) -> dict[str, bytes | None]:
    """Files and folders that must survive a clean-up (name -> content, None: a folder)."""
    decoys = {
        "notes.txt": b"mine",
        ".plan0.mcap.tmp": b"not named as atomic_target names its files",
        f".plan0.mcap.{dead}.0123456789ab.tmp.keep": b"suffix differs",
        f".plan1.mcap.{dead}.ABCDEF012345.tmp": b"upper-case hex: not ours",
        f".plan2.mcap.{os.getpid()}.0123456789ab.tmp": b"a running writer's (this test's)",
        f".plan2.mcap.{dead}.0123456789ab.tmp": None,  # a folder named like a leftover
    }
    for name, content in decoys.items():
        if content is None:
            (folder / name).mkdir()
        else:
            (folder / name).write_bytes(content)
    return decoys


def _assert_decoys_intact(folder: Path, decoys: dict[str, bytes | None]) -> None:
    for name, content in decoys.items():
        path = folder / name
        assert path.is_dir() if content is None else path.read_bytes() == content, name


def test_remove_stale_temporaries_removes_leftovers_and_nothing_else(tmp_path):
    dead = _dead_pid()
    decoys = _decoys(tmp_path, dead)
    leftovers = [tmp_path / f".plan{i}.mcap.{dead}.{i:012x}.tmp" for i in range(2)]
    for path in leftovers:
        path.write_bytes(b"\x89MCAP0\r\n half")
    (tmp_path / "sub").mkdir()
    inner = tmp_path / "sub" / f".x.mcap.{dead}.0123456789ab.tmp"
    inner.write_bytes(b"in a subfolder: not looked at")
    assert remove_stale_temporaries(tmp_path) == leftovers
    assert remove_stale_temporaries(tmp_path) == []
    _assert_decoys_intact(tmp_path, decoys)
    assert inner.exists()
    assert remove_stale_temporaries(tmp_path / "missing") == []


def _check_complete(path: Path, n_nodes: int) -> None:
    """The recording reads back completely: CRCs, counts, metadata, attachment, arrays."""
    with path.open("rb") as stream:
        reader = make_reader(stream, validate_crcs=True)
        counts = {topic: 0 for topic in TOPICS}
        for _, channel, _ in reader.iter_messages():
            counts[channel.topic] += 1
        summary = reader.get_summary()
        assert summary.statistics.message_count == sum(counts.values())
        assert [m.name for m in reader.iter_metadata()] == ["gait_planner.plan"]
        assert [a.name for a in reader.iter_attachments()] == ["compass.yaml"]
    assert counts == {topic: n_nodes if topic in PER_NODE else 1 for topic in TOPICS}
    recorded = read_plan_mcap(path)
    assert recorded.n_nodes == n_nodes and np.all(np.isfinite(recorded.q))


def _start_child(folder: Path) -> tuple[subprocess.Popen, int]:
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(folder)], stdout=subprocess.PIPE,
                             stderr=subprocess.DEVNULL, text=True)
    if not select.select([child.stdout], [], [], 120)[0]:
        child.kill()
        pytest.fail("the recording child did not get ready within 120 s")
    line = child.stdout.readline().split()
    if line[:1] != ["READY"]:
        child.kill()
        pytest.fail(f"the recording child failed to plan (exit {child.wait()})")
    return child, int(line[1])


@pytest.mark.slow
def test_sigkill_while_recording_leaves_complete_files_or_removable_leftovers(tmp_path):
    dead = _dead_pid()
    killed_mid_write = 0
    for seed in range(5):
        folder = tmp_path / f"seed{seed}"
        folder.mkdir()
        decoys = _decoys(folder, dead)
        planted = folder / f".plan0.mcap.{dead}.{seed:012x}.tmp"  # an earlier crash's
        planted.write_bytes(b"\x89MCAP0\r\n half")
        rng = np.random.default_rng(seed)
        child, n_nodes = _start_child(folder)
        try:
            time.sleep(rng.uniform(0.0, 0.15))
            # a clean-up while the child writes removes only the dead writer's leftover
            assert remove_stale_temporaries(folder) == [planted]
            time.sleep(rng.uniform(0.0, 0.15))
            assert child.poll() is None, "the child stopped writing by itself"
            os.kill(child.pid, signal.SIGKILL)
        finally:
            child.kill()
            child.wait()
        assert child.returncode == -signal.SIGKILL

        finals = sorted(p for p in folder.glob("plan*.mcap"))
        for path in finals:
            _check_complete(path, n_nodes)
        leftovers = sorted(p for p in folder.iterdir()
                           if p.name.startswith(".plan") and f".{child.pid}." in p.name)
        killed_mid_write += bool(leftovers)
        assert set(folder.iterdir()) == {*finals, *leftovers, *(folder / n for n in decoys)}
        assert remove_stale_temporaries(folder) == leftovers
        _assert_decoys_intact(folder, decoys)
        assert sorted(p for p in folder.glob("plan*.mcap")) == finals
    assert killed_mid_write >= 1  # some kill hit a write in progress
