"""The Crocoddyl peer (benchmarks/peers/crocoddyl_peer.py, run in `.venv-peers/crocoddyl`;
skipped with the reason when that env is missing, `benchmarks/peers/setup_env.sh
crocoddyl`): its plan.npz has the exchange format's shapes and order, and a plan started
from DMOCC's state starts in DMOCC's configuration (the conversion exchange -> Pinocchio's
(cos, sin) joints -> exchange is exact); the peer runs its shooting problem on one thread
unless told otherwise, and says so."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from benchmarks.peers import exchange

ROOT = Path(__file__).resolve().parents[2]
PYTHON = ROOT / ".venv-peers" / "crocoddyl" / "bin" / "python"


@pytest.mark.skipif(not PYTHON.exists(), reason=f"no Crocoddyl env {PYTHON.parent.parent} "
                    "(benchmarks/peers/setup_env.sh crocoddyl)")
def test_a_crocoddyl_plan_starts_at_dmocc_and_has_the_exchange_shapes(walker2d_dmocc,
                                                                      tmp_path):
    _, problem, path = walker2d_dmocc
    out = tmp_path / "plan.npz"
    subprocess.run([str(PYTHON), "-m", "benchmarks.peers.crocoddyl_peer",
                    str(path), str(out), "--start", "dmocc",
                    "--integrator", "rk4", "--max-iterations", "3"],
                   cwd=ROOT, check=True, capture_output=True, timeout=120)
    plan = exchange.read_plan(out)
    K = sum(p["intervals"] for p in problem["phases"])
    nj = len(problem["joint_names"])
    assert plan.q.shape == (K + 1, exchange.BASE_NQ + nj) and plan.tau.shape == (K, nj)
    np.testing.assert_allclose(plan.times, problem["dmocc"]["times"], atol=1e-9)
    np.testing.assert_allclose(plan.q[0], problem["dmocc"]["q"][0], atol=1e-12)
    assert list(plan.phase_of_node[[0, -1]]) == [0, len(problem["phases"]) - 1]
    assert plan.meta["peer"] == "crocoddyl" and plan.meta["start"] == "dmocc"
    assert set(plan.forces) == set(problem["contact_frames"])


# the library's own default of ShootingProblem.nthreads (CROCODDYL_WITH_NTHREADS), in the env
DEFAULT_NTHREADS = """
import crocoddyl, numpy as np
model = crocoddyl.ActionModelLQR(2, 2)
print(crocoddyl.ShootingProblem(np.zeros(2), [model], model).nthreads)
"""


@pytest.mark.skipif(not PYTHON.exists(), reason=f"no Crocoddyl env {PYTHON.parent.parent} "
                    "(benchmarks/peers/setup_env.sh crocoddyl)")
def test_crocoddyl_peer_sets_and_reports_its_thread_count(walker2d_dmocc, tmp_path):
    """One thread by default whatever OMP_NUM_THREADS says (Crocoddyl's nthreads does not
    read it); --threads 0 leaves the library's default, and the plan reports that."""
    _, _, path = walker2d_dmocc
    library_default = int(subprocess.run([str(PYTHON), "-c", DEFAULT_NTHREADS], cwd=ROOT,
                                         check=True, capture_output=True, text=True,
                                         timeout=60).stdout.split()[-1])
    reported = {}
    for argv in ([], ["--threads", "0"]):
        out = tmp_path / f"plan{len(argv)}.npz"
        subprocess.run([str(PYTHON), "-m", "benchmarks.peers.crocoddyl_peer", str(path),
                        str(out), "--start", "dmocc", "--max-iterations", "2", *argv],
                       cwd=ROOT, check=True, capture_output=True, timeout=120,
                       env={**os.environ, "OMP_NUM_THREADS": "2"})
        reported[len(argv)] = exchange.read_plan(out).meta["threads"]
    assert reported == {0: 1, 2: library_default}
