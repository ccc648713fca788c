"""The opensim peer's walker against Pinocchio (benchmarks/peers/opensim_walker.py, run in the
opensim env `.venv-peers/opensim`; skipped when that env is missing): the OpenSim Model
built from the URDF has the URDF's total mass, a known Pinocchio configuration through
OpenSim's coordinates and back through the exchange format is the same configuration,
OpenSim places every contact frame where Pinocchio does, the joints' block of OpenSim's
mass matrix is Pinocchio's (the URDF's inertias: overrides off), and the coordinates' mirror
map (the periodicity pairs) puts each contact at its partner's mirror image."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from benchmarks.peers import exchange

# the drake test's helpers (same folder, on sys.path under pytest's default import mode)
from test_drake_peer import _configurations, _problem, assert_peer_walker_agrees

ROOT = Path(__file__).resolve().parents[2]
OPENSIM_PYTHON = ROOT / ".venv-peers" / "opensim" / "bin" / "python"

# Runs in the opensim env: configurations through opensim_walker and the exchange format.
SCRIPT = """
import json, sys
import numpy as np
import opensim as osim
from benchmarks.peers import exchange
from benchmarks.peers.opensim_walker import Walker
problem = json.load(open(sys.argv[1]))
walker = Walker(problem, inertia_overrides=False)
qs = np.asarray(json.load(open(sys.argv[2])))
values = [walker.from_exchange(q) for q in qs]
exchange.write_plan(sys.argv[3], exchange.configurations_plan(
    np.array([walker.to_exchange(v) for v in values])))
signs = walker.mirror_signs()
names = walker.coordinates
step = problem["mirror"]["base"]["x_shift"]
mirrored, mass_matrices = [], []
for v in values:
    image = np.zeros_like(v)
    for k, name in enumerate(names):
        partner, sign = signs[name]
        image[names.index(partner)] = sign * v[k]
    image[names.index("base_x")] += step
    mirrored.append(walker.to_exchange(image).tolist())
    walker.set_coordinates(v, np.zeros(len(v)))
    coordinates = walker.model.getCoordinateSet()
    nu = walker.state.getNU()
    units = []
    for name in walker.joint_names:
        for other in names:
            coordinates.get(other).setSpeedValue(walker.state, 0.0)
        coordinates.get(name).setSpeedValue(walker.state, 1.0)
        u = walker.state.getU()
        units.append([u.get(k) for k in range(nu)])
    matrix = osim.Matrix()
    walker.model.getMatterSubsystem().calcM(walker.state, matrix)
    M = np.array([[matrix.get(i, j) for j in range(nu)] for i in range(nu)])
    E = np.array(units).T
    mass_matrices.append((E.T @ M @ E).tolist())
out = {"mass": walker.total_mass(),
       "points": [{c: walker.point(v, c).tolist() for c in walker.frames} for v in values],
       "mirror": mirrored, "mass_matrix": mass_matrices}
print("RESULT " + json.dumps(out))
"""


@pytest.mark.skipif(not OPENSIM_PYTHON.exists(),
                    reason=f"the opensim env {OPENSIM_PYTHON.parent.parent} is not set up "
                           "(benchmarks/peers/setup_env.sh opensim)")
@pytest.mark.parametrize("scene_name", ["walker2d", "walker3d"])
def test_configurations_through_opensim(scene_name, tmp_path):
    problem, model = _problem(scene_name, tmp_path)
    problem.update({"gravity": [0.0, 0.0, -9.81], "friction_coefficient": 0.8,
                    "scene": scene_name})
    planar = scene_name == "walker2d"
    qs = _configurations(len(problem["joint_names"]), planar=planar)
    (tmp_path / "problem.json").write_text(json.dumps(problem))
    (tmp_path / "q.json").write_text(json.dumps(qs.tolist()))
    run = subprocess.run([str(OPENSIM_PYTHON), "-c", SCRIPT, str(tmp_path / "problem.json"),
                          str(tmp_path / "q.json"), str(tmp_path / "plan.npz")],
                         cwd=ROOT, capture_output=True, text=True, timeout=300, check=True)
    line = next(x for x in run.stdout.splitlines() if x.startswith("RESULT "))
    out = json.loads(line[len("RESULT "):])
    assert not (ROOT / "opensim.log").exists()
    np.testing.assert_allclose(out["mass"], pin.computeTotalMass(model), rtol=1e-12)
    assert_peer_walker_agrees(scene_name, problem, model, qs, tmp_path / "plan.npz", out)
    data = model.createData()
    nqs = [model.joints[j].nq for j in range(2, model.njoints)]
    joint_v = [model.joints[model.getJointId(n)].idx_v for n in problem["joint_names"]]
    for q, mass_matrix in zip(qs, out["mass_matrix"]):
        M = pin.crba(model, data, exchange.to_pinocchio(q, nqs))
        M = np.triu(M) + np.triu(M, 1).T
        np.testing.assert_allclose(mass_matrix, M[np.ix_(joint_v, joint_v)], atol=1e-9)


# Runs in the opensim env: the study's solver parallelism for --threads 1 and 0
PARALLEL = """
import sys
from pathlib import Path
import opensim as osim
from benchmarks.peers import exchange
from benchmarks.peers.opensim_peer import build_study
from benchmarks.peers.opensim_walker import Walker
problem = exchange.read_problem(sys.argv[1])
for threads in (1, 0):
    study = build_study(problem, Walker(problem), 4, "dmocc", 2, Path(sys.argv[2]), threads)
    solver = osim.MocoCasADiSolver.safeDownCast(study.updSolver())
    optional = solver.getPropertyByName("parallel")  # an optional property: empty if unset
    print("PARALLEL", threads, solver.get_parallel() if optional.size() else "unset")
"""


@pytest.mark.skipif(not OPENSIM_PYTHON.exists(),
                    reason=f"the opensim env {OPENSIM_PYTHON.parent.parent} is not set up "
                           "(benchmarks/peers/setup_env.sh opensim)")
def test_moco_runs_on_one_thread_unless_told_otherwise(walker2d_dmocc, tmp_path):
    """Moco's CasADi solver evaluates on every core by default (its `parallel` property 1,
    which OMP_NUM_THREADS does not change): --threads 1 (the peer's default) sets it to 0,
    --threads 0 leaves Moco's default (the property unset)."""
    _, _, path = walker2d_dmocc
    run = subprocess.run([str(OPENSIM_PYTHON), "-c", PARALLEL, str(path), str(tmp_path)],
                         cwd=ROOT, capture_output=True, text=True, timeout=300, check=True)
    seen = [line.split()[1:] for line in run.stdout.splitlines() if line.startswith("PARALLEL")]
    assert seen == [["1", "0"], ["0", "unset"]]
