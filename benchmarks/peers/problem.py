"""A DMOCC plan as the peers' gait problem: problem.json and the walker's URDF (main venv).

    .venv/bin/python -m benchmarks.peers.problem walker2d 8 build/peers/walker2d-8

plans the scene at its default request with n intervals per phase (the base time step
scaled so that the durations stay reachable, as `benchmarks/work_precision.py` does) and
writes <dir>/problem.json and <dir>/<scene>.urdf (`gait_planner.io.urdf.scene_to_urdf`).

The half cycle is DMOCC's nodes 0 .. N-1 (K = N-1 intervals; DMOCC's node N is the mirror
image of node 1, the periodic continuation, left out here). Its phases, in the order the
intervals hold them, with DMOCC's durations and interval counts (the last phase, which
shares its time scale with the first, has one interval fewer: its last interval is the
continuation). Configurations are Pinocchio's of the URDF with a free-flyer root at the
root body's centre of mass (position, quaternion xyzw of [d1 d2 d3]), then the URDF's
revolute joint angles (`gait_planner.model.angles`) in the URDF model's order.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pinocchio as pin

from benchmarks.peers import exchange
from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.io.urdf import realisable_inertia, scene_to_urdf
from gait_planner.io.messages import node_efforts
from gait_planner.model.angles import angle_names, joint_angles
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.guess import kinematic_guess
from gait_planner.ocp.mirror import contact_partners
from gait_planner.ocp.settings import GaitSettings, settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.ocp.transcription import Transcription
from gait_planner.result import PlanResult
from gait_planner.verify.joined import angle_mirror
from gait_planner.verify.mechanics import Mechanics, parse_scene


def urdf_model(urdf: str) -> pin.Model:
    """Pinocchio's model of the walker's URDF text with a free-flyer root."""
    return pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())


def urdf_joint_names(model: pin.Model) -> list[str]:
    """The URDF's revolute joints in the model's (configuration) order."""
    return list(model.names[2:])


def pin_configurations(scene: Scene, model: pin.Model, q: np.ndarray) -> np.ndarray:
    """(n, 7 + nj) exchange configurations of director configurations q (n, 12 nb): the
    free flyer's position and quaternion, then the URDF joints' angles (rad; Pinocchio
    itself holds a continuous joint as (cos, sin))."""
    q = np.atleast_2d(q)
    root = scene.body_index(scene.root.body)
    angles = joint_angles(scene, q)  # (n, na) in the scene's angle order
    names = list(angle_names(scene))
    order = [names.index(n) for n in urdf_joint_names(model)]
    out = np.zeros((q.shape[0], exchange.BASE_NQ + len(order)))
    for n, row in enumerate(q):
        R = row[12 * root + 3:12 * root + 12].reshape(3, 3).T
        U, _, Vt = np.linalg.svd(R)
        out[n, :3] = row[12 * root:12 * root + 3]
        out[n, 3:7] = pin.Quaternion(U @ Vt).coeffs()
        out[n, 7:] = angles[n, order]
    return out


def half_cycle_phases(result: PlanResult) -> list[dict]:
    """[{name, duration, active, intervals}] of the half cycle, intervals 0 .. N-2."""
    K = len(result.times) - 2
    phases: list[dict] = []
    for n in range(K):
        if not phases or phases[-1]["name"] != result.phases[n]:
            phases.append({"name": result.phases[n], "start": float(result.times[n]),
                           "active": list(result.active_contacts[n]), "intervals": 0})
        phases[-1]["intervals"] += 1
    ends = [p["start"] for p in phases[1:]] + [float(result.times[K])]
    return [{"name": p["name"], "duration": end - p["start"], "active": p["active"],
             "intervals": p["intervals"]} for p, end in zip(phases, ends)]


def touchdowns(scene: Scene, phases: list[dict]) -> list[list[str]]:
    """Per phase, the contacts it holds that the phase before did not (phase 0: before it
    the last phase's mirror image, the previous half cycle)."""
    partners = contact_partners(scene)
    before = [[partners[c] for c in phases[-1]["active"]]] + [p["active"] for p in phases[:-1]]
    return [[c for c in p["active"] if c not in b] for p, b in zip(phases, before)]


def placements(scene: Scene, result: PlanResult, phases: list[dict]) -> list[dict]:
    """Per phase, contact -> world position (3,) of each held point at the phase's first
    node (held points do not move in a DMOCC plan)."""
    mech = Mechanics(parse_scene(scene.source))
    out, n = [], 0
    for phase in phases:
        q = np.asarray(result.q[n], float)
        out.append({c: mech.contact_matrix(c) @ q for c in phase["active"]})
        n += phase["intervals"]
    return out


def problem_of(result: PlanResult, settings: GaitSettings, urdf_path: Path) -> dict:
    """The problem.json dict (`exchange` module docstring) of a converged DMOCC plan."""
    scene = result.scene
    urdf = urdf_path.read_text()
    model = urdf_model(urdf)
    names = urdf_joint_names(model)
    K = len(result.times) - 2
    phases = half_cycle_phases(result)
    mirror = angle_mirror(parse_scene(scene.source), names)
    guess_tr = Transcription(DiscreteMechanics(Multibody(scene)), settings)
    guess = kinematic_guess(guess_tr, settings.step_length)[:K + 1]
    angle_of = {a: i for i, a in enumerate(result.joint_angle_names)}
    efforts = node_efforts(result)[:, [angle_of[n] for n in names]]
    return {
        "scene": scene.name, "urdf": str(urdf_path), "root_link": scene.root.body,
        "joint_names": names, "contact_frames": [c.name for c in scene.contacts],
        "phases": phases, "touchdown": touchdowns(scene, phases),
        "placements": placements(scene, result, phases),
        "friction_coefficient": settings.friction_coefficient,
        "step_length": settings.step_length,
        "speed": settings.step_length / float(result.times[K]),
        "slope": settings.slope, "gravity": [0.0, 0.0, -scene.gravity],
        "joint_speed_limit": math.radians(settings.joint_speed_max),
        "joint_ranges": {n: [lo, hi] for n, lo, hi in settings.joint_limits},
        "torso_lean_max_deg": settings.torso_lean_max,
        "swing_clearance": settings.swing_clearance,
        "mirror": {"joint_map": [[int(i), int(np.flatnonzero(mirror[:, i])[0]),
                                  float(mirror[:, i].sum())] for i in range(len(names))],
                   "base": {"x_shift": settings.step_length, "reflect_y": True}},
        "guess": {"times": result.times[:K + 1],
                  "q": pin_configurations(scene, model, guess)},
        "dmocc": {"times": result.times[:K + 1],
                  "q": pin_configurations(scene, model, result.q[:K + 1]),
                  "tau_nodes": efforts[:K + 1]},
        "cost": ["squared_torque", "kinetic_energy"],
        "inertia_overrides": {b.name: list(b.inertia) for b in scene.bodies
                              if realisable_inertia(b.inertia) != tuple(b.inertia)},
    }


def dmocc_settings(scene: Scene, intervals_per_phase: int, time_limit: float) -> GaitSettings:
    """The scene's default request on a grid of n intervals per phase (compiled)."""
    return settings_for(scene, intervals_per_phase=intervals_per_phase,
                        max_solve_time=time_limit, compiled=True)


def export(scene_name: str, intervals_per_phase: int, out_dir: Path, *,
           time_limit: float = 300.0, planner: Planner | None = None
           ) -> tuple[PlanResult, GaitSettings, Path]:
    """Plan the scene by DMOCC, cold (never from a plan `planner` stored before: a second
    export of the same problem solves it as the first did), and write
    <out_dir>/problem.json and its URDF; returns the plan, its settings and problem.json's
    path. Raises RuntimeError if DMOCC fails."""
    scene = load_scene(scene_name)
    settings = dmocc_settings(scene, intervals_per_phase, time_limit)
    result = plan_once(planner or Planner(), scene, settings, warm_start=False)
    if not result.success:
        raise RuntimeError(f"DMOCC did not plan {scene_name} at {intervals_per_phase}: "
                           f"{result.message}")
    out_dir.mkdir(parents=True, exist_ok=True)
    urdf_path = out_dir / f"{scene.name}.urdf"
    urdf_path.write_text(scene_to_urdf(scene))
    path = exchange.write_problem(out_dir / "problem.json",
                                  problem_of(result, settings, urdf_path.resolve()))
    return result, settings, path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("intervals_per_phase", type=int)
    parser.add_argument("out_dir", type=Path)
    args = parser.parse_args()
    result, _, path = export(args.scene, args.intervals_per_phase, args.out_dir)
    print(f"{path}: DMOCC {result.stats.iterations} iterations, J {result.cost_value:.4f}")


if __name__ == "__main__":
    main()
