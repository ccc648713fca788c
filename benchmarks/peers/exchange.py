"""The exchange format between the main venv and the peer venvs (numpy only, so that every
env imports it): problem.json (the gait problem, written by problem.py from a DMOCC plan)
and plan.npz (a peer's plan, read by measure.py).

problem.json keys (lengths: P phases, K DMOCC intervals, nq = 7 + nj configuration: a
free-flyer base [x y z qx qy qz qw] (Pinocchio's order) then the angles (rad) of the URDF's
joints in `joint_names` order; the URDF's joints are `continuous`, which Pinocchio holds as
(cos, sin): `to_pinocchio`, `from_pinocchio`):
  scene, urdf (path), root_link, joint_names (nj), contact_frames,
  phases [{name, duration s, active [contacts], intervals}] (P),
  touchdown [[contacts]] (P): contacts that establish contact at the start of each phase,
  placements [{contact: (3,) m}] (P): world position of every held contact point,
  friction_coefficient, step_length m, speed m/s, slope, gravity (3,) m/s^2,
  joint_speed_limit rad/s, joint_ranges {name: [lo, hi] rad},
  mirror {joint_map [[i, j, sign]]: the mirror image's angle (and effort) j is sign x
    angle i; base {x_shift m, reflect_y bool}} (`mirror_configuration`),
  guess {times (K+1) s, q (K+1, nq)}: the kinematic guess DMOCC starts from,
  dmocc {times (K+1), q (K+1, nq), tau_nodes (K+1, nj) efforts, linear between nodes},
  torso_lean_max_deg, swing_clearance m (DMOCC constraints a peer may or may not express),
  cost ["squared_torque", "kinetic_energy"],
  inertia_overrides {link: (3,) kg m^2}: the scene's principal moments (about the link's
    centre of mass and axes) of a body whose URDF inertia is the nearest realisable one
    instead (walker3d's torso, `gait_planner.io.urdf.realisable_inertia`); the project's
    instruments use the scene's, so a peer that can should too.

plan.npz keys: times (K+1,) s; q (K+1, nq) (node K is the half cycle's end, ideally the
mirror image of node 0); tau (K, nj) N m per interval (zero-order hold) or tau_nodes
(K+1, nj) at nodes (linear between them): the URDF joints' efforts, conjugate to their
angles; phase_of_node (K+1,) int (node n's interval n; node K the last phase);
force:<contact> (K+1, 3) N, the ground's force on the body, world frame (optional; a
full-foot wrench's force on one of its points); meta (json string: peer, version, solver,
formulation, grid, cost, build_time, solve_time, iterations, converged, status, objective,
notes; a peer may add keys).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

BASE_NQ = 7  # free-flyer: position (3,) + quaternion xyzw (4,)
BASE_NV = 6
META_KEYS = ("peer", "version", "solver", "formulation", "grid", "cost", "build_time",
             "solve_time", "iterations", "converged", "status", "objective", "notes")


def _plain(value):
    """numpy scalars and arrays as JSON (results_io's twin: this module must import in the
    peer envs, which have no casadi)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def write_problem(path: str | Path, problem: dict) -> Path:
    """problem.json from a dict of the keys above (numpy arrays become lists)."""
    path = Path(path)
    path.write_text(json.dumps(problem, indent=1, default=_plain) + "\n")
    return path


def read_problem(path: str | Path) -> dict:
    """problem.json as a dict; guess/dmocc arrays and placements become numpy arrays."""
    problem = json.loads(Path(path).read_text())
    for key in ("guess", "dmocc"):
        if key in problem:
            problem[key] = {k: np.asarray(v, dtype=float) for k, v in problem[key].items()}
    problem["placements"] = [{c: np.asarray(p, dtype=float) for c, p in phase.items()}
                             for phase in problem["placements"]]
    problem["gravity"] = np.asarray(problem["gravity"], dtype=float)
    return problem


def phase_grid(problem: dict, intervals_per_phase: int) -> tuple[np.ndarray, np.ndarray]:
    """Uniform nodes within each phase at the problem's durations: times (K+1,) s and
    phase_of_node (K+1,) (the last node belongs to the last phase), K = P * n."""
    times, phase_of_node, start = [0.0], [0], 0.0
    for p, phase in enumerate(problem["phases"]):
        steps = start + phase["duration"] * np.arange(1, intervals_per_phase + 1) \
            / intervals_per_phase
        times.extend(steps.tolist())
        phase_of_node[-1] = p
        phase_of_node.extend([p] * intervals_per_phase)
        start = float(steps[-1])
    return np.asarray(times), np.asarray(phase_of_node, dtype=int)


def mirror_configuration(problem: dict, q: np.ndarray) -> np.ndarray:
    """The next half cycle's configuration(s) (..., nq) of q: the base reflected about y = 0
    (position (x + step, -y, z), rotation S R S with S = diag(1, -1, 1): quaternion
    (-qx, qy, -qz, qw)), each angle moved to its partner joint (`mirror_efforts`)."""
    q = np.asarray(q, dtype=float)
    out = np.empty_like(q)
    out[..., :3] = q[..., :3] * [1.0, -1.0, 1.0] + [problem["mirror"]["base"]["x_shift"], 0, 0]
    out[..., 3:7] = q[..., 3:7] * [-1.0, 1.0, -1.0, 1.0]
    out[..., BASE_NQ:] = mirror_efforts(problem, q[..., BASE_NQ:])
    return out


def mirror_efforts(problem: dict, values: np.ndarray) -> np.ndarray:
    """Joint angles or efforts (..., nj) of the mirror image: value j = sign x value i for
    every [i, j, sign] of the joint map."""
    values = np.asarray(values, dtype=float)
    out = np.empty_like(values)
    for i, j, sign in problem["mirror"]["joint_map"]:
        out[..., int(j)] = sign * values[..., int(i)]
    return out


def to_pinocchio(q: np.ndarray, joint_nqs: list[int]) -> np.ndarray:
    """Exchange configurations (..., 7 + nj) as Pinocchio's (..., 7 + sum joint_nqs): a
    joint of nq 2 (a URDF `continuous` joint) holds (cos, sin) of its angle."""
    q = np.asarray(q, dtype=float)
    parts = [q[..., :BASE_NQ]]
    for k, nq in enumerate(joint_nqs):
        angle = q[..., BASE_NQ + k:BASE_NQ + k + 1]
        parts.append(np.concatenate([np.cos(angle), np.sin(angle)], axis=-1) if nq == 2
                     else angle)
    return np.concatenate(parts, axis=-1)


def from_pinocchio(q_pin: np.ndarray, joint_nqs: list[int]) -> np.ndarray:
    """The inverse of `to_pinocchio`."""
    q_pin = np.asarray(q_pin, dtype=float)
    parts, i = [q_pin[..., :BASE_NQ]], BASE_NQ
    for nq in joint_nqs:
        parts.append(np.arctan2(q_pin[..., i + 1:i + 2], q_pin[..., i:i + 1]) if nq == 2
                     else q_pin[..., i:i + 1])
        i += nq
    return np.concatenate(parts, axis=-1)


@dataclasses.dataclass
class Plan:
    """A peer's plan in Pinocchio's conventions (shapes in the module docstring)."""

    times: np.ndarray
    q: np.ndarray
    phase_of_node: np.ndarray
    meta: dict
    tau: np.ndarray | None = None
    tau_nodes: np.ndarray | None = None
    forces: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)

    def interval_torques(self) -> np.ndarray:
        """(K, nj) torque per interval: tau, or the mean of tau_nodes at its two ends."""
        if self.tau is not None:
            return self.tau
        return 0.5 * (self.tau_nodes[:-1] + self.tau_nodes[1:])


def configurations_plan(q: np.ndarray) -> Plan:
    """A Plan of configurations q (K + 1, nq) alone, one per unit of time, one phase, zero
    torques and placeholder meta: what the adapters' round-trip tests write to check a
    peer's configurations through the exchange format."""
    n = len(q)
    return Plan(times=np.arange(n, dtype=float), q=np.asarray(q),
                phase_of_node=np.zeros(n, dtype=int), meta={k: 0 for k in META_KEYS},
                tau=np.zeros((n - 1, 1)))


def write_plan(path: str | Path, plan: Plan) -> Path:
    """plan.npz from a Plan; checks the shapes and that meta has META_KEYS."""
    k = len(plan.times) - 1
    if plan.q.shape[0] != k + 1 or len(plan.phase_of_node) != k + 1:
        raise ValueError(f"q {plan.q.shape} / phase_of_node {len(plan.phase_of_node)} "
                         f"do not match {k + 1} nodes")
    if (plan.tau is None) == (plan.tau_nodes is None):
        raise ValueError("give exactly one of tau (K, nj) and tau_nodes (K+1, nj)")
    if plan.tau is not None and plan.tau.shape[0] != k:
        raise ValueError(f"tau {plan.tau.shape} is not ({k}, nj)")
    if plan.tau_nodes is not None and plan.tau_nodes.shape[0] != k + 1:
        raise ValueError(f"tau_nodes {plan.tau_nodes.shape} is not ({k + 1}, nj)")
    missing = [key for key in META_KEYS if key not in plan.meta]
    if missing:
        raise ValueError(f"meta lacks {missing}")
    arrays = {"times": plan.times, "q": plan.q, "phase_of_node": plan.phase_of_node,
              "meta": np.asarray(json.dumps(plan.meta, default=_plain))}
    if plan.tau is not None:
        arrays["tau"] = plan.tau
    else:
        arrays["tau_nodes"] = plan.tau_nodes
    for contact, force in plan.forces.items():
        arrays[f"force:{contact}"] = force
    path = Path(path)
    with path.open("wb") as handle:
        np.savez(handle, **arrays)
    return path


def read_plan(path: str | Path) -> Plan:
    """A Plan from plan.npz."""
    with np.load(path, allow_pickle=False) as data:
        forces = {key.split(":", 1)[1]: data[key] for key in data.files
                  if key.startswith("force:")}
        return Plan(times=data["times"], q=data["q"],
                    phase_of_node=data["phase_of_node"].astype(int),
                    meta=json.loads(str(data["meta"])),
                    tau=data["tau"] if "tau" in data.files else None,
                    tau_nodes=data["tau_nodes"] if "tau_nodes" in data.files else None,
                    forces=forces)
