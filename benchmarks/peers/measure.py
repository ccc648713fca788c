"""A peer's plan.npz measured by the project's instruments (main venv).

    .venv/bin/python -m benchmarks.peers.measure build/peers/walker2d-4/problem.json PLAN.npz

`plan_result(problem, plan)` turns the plan into a `PlanResult` of the project's scene:
director configurations by forward kinematics of the URDF's body links (a link's origin is
its parent-joint point, the root's its centre of mass, axes the directors:
`gait_planner.io.urdf`), one node appended as the periodic continuation (node K + 1 =
mirror(node 1) + step, interval K holding the mirror image of interval 0's contacts, as
DMOCC's node N: `gait_planner.result`), joint rates by central differences continued
periodically as DMOCC's (`ocp.solution.joint_rates`). `measure(...)` then reports
* `verify.drift.physics_error` at reset "node" (one interval's drift) and "phase", the
  plan's torques applied as what they are: the URDF joints' efforts (conjugate to the
  angles; spherical joints by their pitch/roll/yaw efforts at the simulated configuration),
  held constant over each interval (tau, zero-order hold) or linear between nodes
  (tau_nodes), through `EffortSimulation`; velocities at segment starts from the plan's
  configurations (one-sided second-order differences), the same for every method;
* contact hold: the largest distance (mm) of a held point from DMOCC's placement, at both
  nodes of every interval holding it;
* cone: the largest violation (N) of |f_t| <= mu f_z and f_z >= 0 of the plan's forces
  (NaN without forces);
* joint limits: the largest excursion (deg) of a joint angle outside problem.joint_ranges;
* the plan's own periodicity error (mm): node K against mirror(node 0) + step;
* the squared-torque cost: integral of |efforts|^2 over the half cycle (N^2 m^2 s), with the
  plan's own hold;
* if asked (`walk_to`), the walk in MuJoCo: the plan recorded by the product's MCAP writer
  and walked `WALK_STEPS` half cycles by the reference controller
  (`gait_planner.walk.walk_plan.walk`, config/walk.yaml), as a user walks a DMOCC plan.
DMOCC's own rows (`measure_dmocc`) use its `PlanResult` and `physics_error` unchanged.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from unittest import mock

import numpy as np
import pinocchio as pin

from benchmarks.peers import exchange
from benchmarks.peers.problem import urdf_joint_names, urdf_model
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.io.messages import node_efforts
from gait_planner.io.urdf import kinematic_tree
from gait_planner.model.angles import angle_names, conjugate_torques, joint_angles
from gait_planner.model.ground import Ground
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.mirror import configuration_mirror, contact_partners
from gait_planner.ocp.solution import joint_rates, node_kinetic_energy
from gait_planner.result import PlanResult, SolverStats
from gait_planner.verify import drift
from gait_planner.verify.constrained import ConstrainedModel
from gait_planner.verify.continuous import cardan_efforts, effort_names
from gait_planner.verify.mechanics import Mechanics, parse_scene
from gait_planner.walk.walk_plan import walk

HOLDS = ("zero", "linear")
WALK_STEPS = 10  # half cycles walked in MuJoCo (`gait-planner walk`'s default)
_S = np.diag([1.0, -1.0, 1.0])


class EffortModel(ConstrainedModel):
    """The constrained model driven by URDF joint efforts instead of couples."""

    def efforts(self, q: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Generalised forces (nv,) of efforts tau (na,) in `effort_names` order, after
        `_frames_at(q)`: a spherical joint's Pinocchio effort m (the couple in the child
        frame) solves E^T m = (pitch, roll, yaw efforts) (`continuous.cardan_efforts`)."""
        out, i = np.zeros(self.nv), 0
        for spherical, jid in self.joint_slots:
            s = self.model.joints[jid].idx_v
            if spherical:
                R_rel = self.data.liMi[jid].rotation
                Et = np.column_stack([cardan_efforts(R_rel, u) for u in np.eye(3)])
                out[s:s + 3] = np.linalg.solve(Et, tau[i:i + 3])
                i += 3
            else:
                out[s] = tau[i]
                i += 1
        return out


class EffortSimulation(drift.PlanSimulation):
    """`PlanSimulation` of efforts (N+1, na) (`effort_names` order) held "zero" (row n over
    interval n) or "linear" between nodes."""

    def __init__(self, result: PlanResult, efforts: np.ndarray, hold: str):
        super().__init__(result)
        self.cm = EffortModel(self.scene)
        self.tau, self.hold = np.asarray(efforts, float), hold

    def _torque(self, t: float) -> np.ndarray:
        if self.hold == "linear":
            return super()._torque(t)
        return self.tau[int(np.clip(np.searchsorted(self.times, t, side="right") - 1,
                                    0, self.N - 1))]


def effort_physics_error(result: PlanResult, efforts: np.ndarray, hold: str, reset: str):
    """`physics_error` of `result` driven by `efforts` (module docstring)."""
    if hold not in HOLDS:
        raise ValueError(f"hold must be one of {HOLDS}, got {hold!r}")
    with mock.patch.object(drift, "PlanSimulation",
                           lambda r: EffortSimulation(r, efforts, hold)):
        return drift.physics_error(result, reset=reset)


def director_configurations(scene: Scene, model: pin.Model, q: np.ndarray) -> np.ndarray:
    """(n, 12 nb) director coordinates of exchange configurations q (n, 7 + nj) of the
    URDF model: each body's link frame by forward kinematics, phi = origin - R offset."""
    data = model.createData()
    offsets = kinematic_tree(scene).link_offsets
    nqs = [model.joints[j].nq for j in range(2, model.njoints)]
    frames = {b.name: model.getFrameId(b.name) for b in scene.bodies}
    out = np.zeros((len(q), 12 * len(scene.bodies)))
    for n, row in enumerate(exchange.to_pinocchio(q, nqs)):
        pin.framesForwardKinematics(model, data, row)
        for i, body in enumerate(scene.bodies):
            M = data.oMf[frames[body.name]]
            out[n, 12 * i:12 * i + 3] = M.translation - M.rotation @ offsets[body.name]
            out[n, 12 * i + 3:12 * i + 12] = M.rotation.T.reshape(-1)
    return out


def couples_of_efforts(scene: Scene, angles: np.ndarray, efforts: np.ndarray) -> np.ndarray:
    """(n, na) plan torques (`PlanResult.tau`: couples) of efforts (n, na), both in the
    scene's angle order: the inverse of the linear map `conjugate_torques` at each node."""
    eye = np.eye(angles.shape[1])
    return np.array([np.linalg.solve(np.column_stack([conjugate_torques(scene, a, u)
                                                      for u in eye]), e)
                     for a, e in zip(angles, efforts)])


def plan_result(problem: dict, plan: exchange.Plan) -> tuple[PlanResult, np.ndarray, str]:
    """(PlanResult with the continuation node, efforts (K+2, na) in `effort_names` order,
    hold) of a peer's plan (module docstring)."""
    scene = load_scene(problem["scene"])
    data = parse_scene(scene.source)
    mech = Mechanics(data)
    model = urdf_model(Path(problem["urdf"]).read_text())
    if urdf_joint_names(model) != problem["joint_names"]:
        raise ValueError("the URDF's joints are not problem.json's joint_names")
    step = problem["step_length"]
    K = len(plan.times) - 1
    q = director_configurations(scene, model, plan.q)
    q = np.vstack([q, mech.mirror(q[1], step)])
    times = np.append(plan.times, plan.times[K] + plan.times[1] - plan.times[0])
    hold = "zero" if plan.tau is not None else "linear"
    given = plan.tau if plan.tau is not None else plan.tau_nodes
    rows = np.vstack([given[:K + 1] if hold == "linear" else
                      np.vstack([given, exchange.mirror_efforts(problem, given[0])]),
                      exchange.mirror_efforts(problem, given[1])])  # (K+2, nj)
    names = list(angle_names(scene))
    by_name = {n: rows[:, k] for k, n in enumerate(problem["joint_names"])}
    efforts_angles = np.column_stack([by_name[n] for n in names])
    angles = joint_angles(scene, q)
    partners = contact_partners(scene)
    phases = problem["phases"]
    active = [tuple(phases[p]["active"]) for p in plan.phase_of_node[:K]]
    active += [tuple(partners[c] for c in active[0]), tuple(partners[c] for c in active[1])]
    forces = {}
    for c in problem["contact_frames"]:
        f = plan.forces.get(c, np.zeros((K + 1, 3)))
        partner = plan.forces.get(partners[c], np.zeros((K + 1, 3)))
        forces[c] = np.vstack([f, _S @ partner[1]])
    mb = Multibody(scene)
    velocity, acceleration = joint_rates(
        scene, configuration_mirror(mb, Ground(slope=problem["slope"])), q, times, step)
    result = PlanResult(
        success=bool(plan.meta["converged"]), message=str(plan.meta["status"]), scene=scene,
        cost_name="torque_squared", cost_value=float(plan.meta["objective"]),
        step_length=step, friction_coefficient=problem["friction_coefficient"], times=times,
        q=q, tau=couples_of_efforts(scene, angles, efforts_angles), joint_angle_names=tuple(names),
        joint_angles=angles, joint_velocities=velocity,
        joint_accelerations=acceleration,
        phases=tuple(phases[p]["name"] for p in plan.phase_of_node) + (phases[-1]["name"],),
        active_contacts=tuple(active), contact_forces=forces, roll_moments={},
        generalized_force=np.zeros_like(q),
        kinetic_energy=node_kinetic_energy(mb.mass_diagonal, q, np.diff(times)),
        potential_energy=np.array([mech.potential_energy(row) for row in q]),
        phase_scaling=np.zeros(0), duration=float(times[K] - times[0]),
        stats=SolverStats(status=str(plan.meta["status"]),
                          iterations=int(plan.meta["iterations"]),
                          solve_time=float(plan.meta["solve_time"]),
                          build_time=float(plan.meta["build_time"])),
        settings={"slope": str(problem["slope"]), "step_height": "0"})
    order = [names.index(n) for n in effort_names(data)]
    return result, efforts_angles[:, order], hold


def squared_torque(times: np.ndarray, efforts: np.ndarray, hold: str, K: int) -> float:
    """Integral of |efforts|^2 (N^2 m^2 s) over intervals 0 .. K-1: rows per interval
    ("zero") or linear between node rows ("linear": h (a^2 + a b + b^2) / 3)."""
    h = np.diff(times)[:K]
    a, b = efforts[:K], efforts[1:K + 1]
    per = (a * a).sum(1) if hold == "zero" else ((a * a + a * b + b * b).sum(1) / 3.0)
    return float(h @ per)


def held_measures(result: PlanResult, problem: dict, K: int) -> dict:
    """Contact hold (mm), cone violation (N), joint-limit excursion (deg) of a plan over its
    half cycle (nodes 0 .. K) and its own periodicity error (mm): node K against the mirror
    image of node 0, over the bodies' centres of mass and the contact points."""
    mech = Mechanics(parse_scene(result.scene.source))
    q = np.asarray(result.q, float)
    image = mech.mirror(q[0], result.step_length)
    pieces = [mech.point_matrix(b.name, np.zeros(3)) for b in result.scene.bodies]
    periodic = max(1e3 * float(np.linalg.norm(C @ (q[K] - image)))
                   for C in pieces + [mech.contact_matrix(c) for c in problem["contact_frames"]])
    phase_index = {p["name"]: i for i, p in enumerate(problem["phases"])}
    hold = 0.0
    for n in range(K):
        placed = problem["placements"][phase_index[result.phases[n]]]
        for c in result.active_contacts[n]:
            C = mech.contact_matrix(c)
            hold = max(hold, max(1e3 * float(np.linalg.norm(C @ q[m] - placed[c]))
                                 for m in (n, n + 1)))
    mu = problem["friction_coefficient"]
    cone = 0.0
    for f in result.contact_forces.values():
        f = np.asarray(f, float)[:K + 1]
        cone = max(cone, float(np.max(np.maximum(np.linalg.norm(f[:, :2], axis=1)
                                                 - mu * f[:, 2], -f[:, 2]), initial=0.0)))
    limits = 0.0
    for name, (lo, hi) in problem["joint_ranges"].items():
        a = np.asarray(result.joint_angles, float)[:K + 1, result.joint_angle_names.index(name)]
        limits = max(limits, float(np.degrees(max(lo - a.min(), a.max() - hi, 0.0))))
    return {"contact_hold_mm": hold, "cone_violation_n": cone, "joint_limit_deg": limits,
            "plan_periodicity_mm": periodic}


def _physics(node, phase) -> dict:
    return {"drift_node_rms_deg": node.angle_drift_rms_deg,
            "drift_node_max_deg": node.angle_drift_max_deg,
            "drift_phase_rms_deg": phase.angle_drift_rms_deg,
            "drift_phase_max_deg": phase.angle_drift_max_deg,
            "swing_phase_mm": phase.swing_drift_max_mm,
            "periodicity_gap_mm": phase.periodicity_gap_mm,
            "periodicity_gap_deg": phase.periodicity_gap_deg,
            "force_error_n": phase.force_error_max_n,
            "physics_failure": node.failure or phase.failure}


def walk_measures(result: PlanResult, path: Path) -> dict:
    """The plan recorded to `path` (MCAP) and walked `WALK_STEPS` half cycles in MuJoCo
    (module docstring): half cycles walked, why the walk stopped, the joints' RMS tracking
    error (deg) and the feedback's share of the joint torques."""
    out = walk(write_plan_mcap(result, path), WALK_STEPS)
    return {"walk_half_cycles": out["half_cycles_walked"], "walk_steps": WALK_STEPS,
            "walk_stopped": out["stopped"], "walk_joint_rms_deg": out["joint_rms_deg"],
            "walk_feedback_share": out["feedback_share"]}


def measure(problem: dict, plan: exchange.Plan, walk_to: Path | None = None) -> dict:
    """Every measure of a peer's plan (module docstring), the walk if `walk_to` names its
    recording; a plan with a NaN or an infinity is measured as a failure."""
    torques = plan.tau if plan.tau is not None else plan.tau_nodes
    if not (np.isfinite(plan.q).all() and np.isfinite(torques).all()):
        return {"physics_failure": "the plan is not finite"}
    result, efforts, hold = plan_result(problem, plan)
    K = len(plan.times) - 1
    node, phase = (effort_physics_error(result, efforts, hold, reset)
                   for reset in ("node", "phase"))
    row = {**_physics(node, phase), **held_measures(result, problem, K),
           "squared_torque": squared_torque(result.times, efforts, hold, K), "hold": hold}
    if not plan.forces:
        row["cone_violation_n"] = row["force_error_n"] = float("nan")
    return {**row, **(walk_measures(result, walk_to) if walk_to is not None else {})}


def measure_dmocc(result: PlanResult, problem: dict, walk_to: Path | None = None) -> dict:
    """The same measures of DMOCC's own plan, by its own `physics_error` (node torques
    linear between nodes, as couples), and its walk if `walk_to` names its recording."""
    K = len(result.times) - 2
    node, phase = (drift.physics_error(result, reset=r) for r in ("node", "phase"))
    names = list(result.joint_angle_names)
    order = [names.index(n) for n in effort_names(parse_scene(result.scene.source))]
    return {**_physics(node, phase), **held_measures(result, problem, K),
            "squared_torque": squared_torque(result.times, node_efforts(result)[:, order],
                                             "linear", K), "hold": "linear",
            **(walk_measures(result, walk_to) if walk_to is not None else {})}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problem", type=Path)
    parser.add_argument("plan", type=Path)
    args = parser.parse_args()
    row = measure(exchange.read_problem(args.problem), exchange.read_plan(args.plan))
    print(json.dumps(row, indent=1))


if __name__ == "__main__":
    main()
