"""The peer table's run (benchmarks/peers/run.py): the load beside a solve recovered from
the 1-minute load average's decay, and the solves' thread environments."""

from __future__ import annotations

import math

from benchmarks.peers.run import MAIN_VENV_ENV, THREAD_ENV, other_load, thread_env


def test_other_load_recovers_the_load_beside_a_solve():
    """The kernel's 1-minute average relaxes towards the runnable tasks with a 60 s time
    constant: a solve of one core for 90 s beside 0.7 of other load, started at 0.3."""
    before, wall, own, other = 0.3, 90.0, 1.0, 0.7
    e = math.exp(-wall / 60.0)
    after = before * e + (own + other) * (1.0 - e)
    assert math.isclose(other_load(before, after, wall, own), other, abs_tol=1e-12)
    assert other_load(before, after, 10.0, own) is None  # too short to say


def test_thread_env_pins_or_unsets_the_thread_variables(monkeypatch):
    """A peer's environment: the thread variables at 1 or unset, and nothing the main venv
    set for DMOCC (gait_planner's OpenBLAS kernel choice)."""
    monkeypatch.setenv("OMP_NUM_THREADS", "4")
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    pinned, default = thread_env(True), thread_env(False)
    assert all(pinned[k] == "1" for k in THREAD_ENV)
    assert not any(k in default for k in THREAD_ENV)
    assert not any(k in env for env in (pinned, default) for k in MAIN_VENV_ENV)
