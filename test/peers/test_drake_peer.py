"""The drake peer's walker against Pinocchio (benchmarks/peers/drake_walker.py, run in the
drake env `.venv-peers/drake`; skipped when that env is missing): a known Pinocchio
configuration through Drake's plant and back through the exchange format gives the same
configuration in problem.json's joint order, Drake places every contact frame where
Pinocchio does, and Drake's mirror of a configuration puts each contact at its partner's
mirror image, shifted by the step."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from benchmarks.peers import exchange
from benchmarks.peers.problem import urdf_joint_names, urdf_model
from gait_planner.io.urdf import scene_to_urdf
from gait_planner.model.loader import load_scene
from gait_planner.ocp.mirror import contact_partners
from gait_planner.verify.joined import angle_mirror
from gait_planner.verify.mechanics import parse_scene

ROOT = Path(__file__).resolve().parents[2]
DRAKE_PYTHON = ROOT / ".venv-peers" / "drake" / "bin" / "python"
STEP = 0.6338  # m, the mirror's x shift

# Runs in the drake env: configurations through drake_walker and the exchange format.
SCRIPT = """
import json, sys
import numpy as np
from benchmarks.peers import exchange
from benchmarks.peers.drake_walker import Walker
problem = json.load(open(sys.argv[1]))
walker = Walker(problem)
qs = np.asarray(json.load(open(sys.argv[2])))
reduced = [walker.from_pin(q) for q in qs]
exchange.write_plan(sys.argv[3], exchange.configurations_plan(
    np.array([walker.to_pin(r) for r in reduced])))
out = {"points": [{c: walker.point(r, c).tolist() for c in walker.frames} for r in reduced],
       "mirror": [walker.to_pin(walker.mirror_q(r)).tolist() for r in reduced]}
print(json.dumps(out))
"""


def _problem(scene_name: str, tmp_path: Path) -> tuple[dict, pin.Model]:
    """The problem.json keys the walker reads, for the scene's URDF."""
    scene = load_scene(scene_name)
    urdf = tmp_path / f"{scene_name}.urdf"
    urdf.write_text(scene_to_urdf(scene))
    model = urdf_model(urdf.read_text())
    names = urdf_joint_names(model)
    mirror = angle_mirror(parse_scene(scene.source), names)
    problem = {"urdf": str(urdf), "root_link": scene.root.body, "joint_names": names,
               "contact_frames": [c.name for c in scene.contacts],
               "mirror": {"joint_map": [[i, int(np.flatnonzero(mirror[:, i])[0]),
                                         float(mirror[:, i].sum())]
                                        for i in range(len(names))],
                          "base": {"x_shift": STEP, "reflect_y": True}}}
    return problem, model


def _configurations(nj: int, planar: bool) -> np.ndarray:
    """(3, 7 + nj) exchange configurations: base moved and turned, joints bent."""
    rng = np.random.default_rng(7)
    out = []
    for _ in range(3):
        axis = np.array([0.0, 1.0, 0.0]) if planar else rng.normal(size=3)
        rotation = pin.exp3(rng.uniform(0.1, 0.4) * axis / np.linalg.norm(axis))
        position = rng.uniform(-0.2, 0.2, 3) + [0.0, 0.0, 1.1]
        if planar:
            position[1] = 0.0
        out.append(np.concatenate([position, pin.Quaternion(rotation).coeffs(),
                                   rng.uniform(-0.6, 0.6, nj)]))
    return np.array(out)


def _frame_points(model: pin.Model, q: np.ndarray, contacts) -> dict[str, np.ndarray]:
    """Pinocchio's world positions of the contact frames at exchange configuration q."""
    data = model.createData()
    nqs = [model.joints[j].nq for j in range(2, model.njoints)]
    pin.framesForwardKinematics(model, data, exchange.to_pinocchio(q, nqs))
    return {c: data.oMf[model.getFrameId(c)].translation.copy() for c in contacts}


@pytest.mark.skipif(not DRAKE_PYTHON.exists(),
                    reason=f"the drake env {DRAKE_PYTHON.parent.parent} is not set up "
                           "(benchmarks/peers/setup_env.sh drake)")
@pytest.mark.parametrize("scene_name", ["walker2d", "walker3d"])
def test_configurations_through_drake(scene_name, tmp_path):
    problem, model = _problem(scene_name, tmp_path)
    qs = _configurations(len(problem["joint_names"]), planar=scene_name == "walker2d")
    (tmp_path / "problem.json").write_text(json.dumps(problem))
    (tmp_path / "q.json").write_text(json.dumps(qs.tolist()))
    run = subprocess.run([str(DRAKE_PYTHON), "-c", SCRIPT, str(tmp_path / "problem.json"),
                          str(tmp_path / "q.json"), str(tmp_path / "plan.npz")],
                         cwd=ROOT, capture_output=True, text=True, timeout=300, check=True)
    out = json.loads(run.stdout)
    assert_peer_walker_agrees(scene_name, problem, model, qs, tmp_path / "plan.npz", out)


def assert_peer_walker_agrees(scene_name: str, problem: dict, model: pin.Model,
                              qs: np.ndarray, plan_path: Path, out: dict) -> None:
    """A peer's walker against Pinocchio: configurations qs through the peer and back
    (plan_path) are qs, the peer's contact points out["points"] are Pinocchio's, and its
    mirror images out["mirror"] put each contact at its partner's mirror image, shifted by
    the step (the drake and opensim tests)."""
    back = exchange.read_plan(plan_path).q
    for q, q_back in zip(qs, back):  # the quaternion up to its sign
        sign = np.sign(q[3:7] @ q_back[3:7])
        np.testing.assert_allclose(q_back[3:7] * sign, q[3:7], atol=1e-12)
        np.testing.assert_allclose(np.delete(q_back, range(3, 7)),
                                   np.delete(q, range(3, 7)), atol=1e-12)
    contacts = problem["contact_frames"]
    partners = contact_partners(load_scene(scene_name))
    reflect = np.array([1.0, -1.0, 1.0])
    for q, points, image in zip(qs, out["points"], out["mirror"]):
        expected = _frame_points(model, q, contacts)
        for c in contacts:
            np.testing.assert_allclose(points[c], expected[c], atol=1e-9)
        mirrored = _frame_points(model, np.asarray(image), contacts)
        for c in contacts:
            np.testing.assert_allclose(mirrored[partners[c]],
                                       reflect * expected[c] + [STEP, 0.0, 0.0], atol=1e-9)
