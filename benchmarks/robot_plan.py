"""One robot planned in this process as a user plans it (`benchmarks/robots.py` runs it in a
fresh process per row): the URDF drafted (`model.urdf_import.draft_scene`), the scene
written, the problem built (`Planner.prepare`), the request planned and recorded
(`pipeline.plan_and_record`: cold from the kinematic guess, refined while the certificate
asks for it), then the plan's measures; one JSON line on stdout.

    .venv/bin/python benchmarks/robot_plan.py bolt --out DIR [--compiled] [--time-limit S]
    .venv/bin/python benchmarks/robot_plan.py walker3d --out DIR --compiled
    .venv/bin/python benchmarks/robot_plan.py walker3d --scaled-to g1 --out DIR --compiled

Compiled derivative elements go to $GAIT_PLANNER_CACHE (the caller points it at an empty
folder for a first build). `--scaled-to ROBOT`: walker3d with its lengths scaled to the
robot's leg length and its masses to the robot's (`scaled_walker.py`).

Measures (`measures`), over the half cycle t_0 .. t_(N-1), as `gait_trends.py` defines
them: the efforts conjugate to the joint angles (`model.angles.conjugate_torques`: the
published efforts) times the joint-angle rates give each joint's power; W+ the time
integral of the positive part summed over the joints (trapezoidal rule), the cost of
transport W+ / (m g s) with m the total mass and s the step length; the peak |effort| and,
per joint with an effort limit, its peak over the limit (the largest share named); for a
robot, how it walks (`robot_posture.py`: pelvis attitude, knees, step width, every
published effort's share of its URDF limit, the locked joints' apart).
"""

from __future__ import annotations

import argparse
import json
import re
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

START = time.perf_counter()


@dataclass(frozen=True)
class Robot:
    """A robot of the example-robot-data wheel: its URDF (in the wheel's robots folder)
    and the importer's options for it (`draft_scene` keywords: feet, locked, ...)."""

    urdf: str
    importer: dict = field(default_factory=dict)


# The robots benchmarked, in order, with the importer options they need.
ROBOTS = {
    "bolt": Robot("bolt_description/robots/bolt.urdf"),
    "g1": Robot("g1_description/urdf/g1_29dof_rev_1_0.urdf"),
    "talos": Robot("talos_data/robots/talos_reduced.urdf", {"mirror_tolerance": 0.06}),
    "icub": Robot("icub_description/robots/icub_reduced.urdf"),  # x backwards (#61 item 4)
    "alexander": Robot("alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf"),
    "romeo": Robot("romeo_description/urdf/romeo_small.urdf"),  # per-joint speeds (#61)
}


def robots_folder() -> Path:
    """The robots folder of the example-robot-data wheel (a bench and test dependency);
    its parents[1] resolves the URDFs' package:// paths."""
    dist = metadata.distribution("example-robot-data")
    return Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))


def draft(name: str):
    """The `UrdfDraft` of ROBOTS[name] and the URDF's path."""
    from gait_planner.model.urdf_import import draft_scene

    robot, folder = ROBOTS[name], robots_folder()
    path = folder / robot.urdf
    packages = [str(folder.parents[1])]
    return draft_scene(path.read_text(), package_dirs=packages, robot_dirs=packages,
                       urdf_file=str(path), **robot.importer), path


def leg_length(draft_yaml: str) -> float:
    """The leg length (hip to sole, m) the draft's header states."""
    return float(re.search(r"Leg length \(hip to sole\) L = ([0-9.]+) m", draft_yaml).group(1))


def _trapezoid(y, t) -> float:
    return float(((y[1:] + y[:-1]) * 0.5 * (t[1:] - t[:-1])).sum())


def measures(result) -> dict:
    """The plan's numbers (module docstring)."""
    import numpy as np

    from gait_planner.model.angles import conjugate_torques

    scene, N = result.scene, result.n_nodes - 1
    efforts = conjugate_torques(scene, result.joint_angles, result.tau)[:N]
    power = (efforts * result.joint_velocities[:N])
    mass = sum(b.mass for b in scene.bodies)
    work = _trapezoid(np.clip(power, 0, None).sum(axis=1), result.times[:N])
    peak = np.abs(efforts).max(axis=0)
    limits = dict(scene.gait.options.get("effort_limits", {}))
    names = list(result.joint_angle_names)
    shares = {n: float(peak[i] / limits[n]) for i, n in enumerate(names) if n in limits}
    worst = max(shares, key=shares.get) if shares else None
    return {"mass_kg": mass, "duration_s": result.duration,
            "step_length_m": result.step_length,
            "speed_m_s": result.step_length / result.duration,
            "positive_work_J": work,
            "cost_of_transport": work / (mass * scene.gravity * result.step_length),
            "peak_torque_Nm": float(peak.max()), "peak_torque_joint": names[int(peak.argmax())],
            "peak_torque_share": shares[worst] if worst else None,
            "peak_share_joint": worst}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("name", help=f"a robot ({', '.join(ROBOTS)}) or walker3d")
    parser.add_argument("--out", type=Path, required=True, help="folder for scene and MCAP")
    parser.add_argument("--compiled", action="store_true")
    parser.add_argument("--scaled-to", choices=sorted(ROBOTS), help="walker3d scaled to it")
    parser.add_argument("--time-limit", type=float, default=600.0, help="s, the plan's limit")
    args = parser.parse_args()

    from gait_planner.model.loader import find_scene, load_scene
    from gait_planner.ocp.solve import Planner
    from gait_planner.pipeline import plan_and_record
    from gait_planner.problem import resolve
    from gait_planner.request import PlanRequest

    row: dict = {"name": args.name, "compiled": args.compiled}
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    if args.name in ROBOTS:
        from gait_planner.cli.robot import write_draft

        drafted, urdf = draft(args.name)
        scene_ref = str(write_draft(drafted, args.out / f"{args.name}.yaml"))
        row.update(urdf=str(urdf), importer=ROBOTS[args.name].importer,
                   joints_planned=len(drafted.joints), joints_locked=len(drafted.locked),
                   leg_length_m=leg_length(drafted.yaml))
        lookup = find_scene
    elif args.name == "walker3d":
        from gait_planner.model.urdf_import import WALKER3D_LEG

        scene, leg = load_scene("walker3d"), WALKER3D_LEG
        if args.scaled_to:
            from gait_planner.model.loader import scene_from_text
            from scaled_walker import scaled_walker3d

            target, _ = draft(args.scaled_to)
            leg = leg_length(target.yaml)
            mass = sum(b.mass for b in scene_from_text(target.yaml, "target.yaml").bodies)
            scene = scaled_walker3d(leg, mass)
            row.update(scaled_to=args.scaled_to)
        scene_ref = scene.name
        row.update(joints_planned=len(scene.joints), joints_locked=0, leg_length_m=leg)
        lookup = lambda _name: scene  # noqa: E731
    else:
        parser.error(f"unknown robot {args.name!r}")
    row["draft_s"] = time.perf_counter() - start
    request = PlanRequest(scene=scene_ref, output_name=args.name, compiled=args.compiled,
                          max_solve_time=args.time_limit)
    stages: list[str] = []
    planner = Planner(stage=stages.append)
    problem = resolve(request, lookup)
    scene, settings = problem.scene, problem.settings
    start = time.perf_counter()
    row["derivatives"] = planner.prepare(scene, settings)
    row["build_s"] = time.perf_counter() - start
    row["ready_s"] = time.perf_counter() - START
    row.update(planner.problem_size(scene, settings))
    start = time.perf_counter()
    outcome = plan_and_record(planner, problem, args.out, rrd=False)
    row["plan_s"] = time.perf_counter() - start
    result = outcome.result
    row["compiling"] = [s for s in stages if "compiling" in s]
    row.update(success=bool(result.success), message=result.message,
               iterations=result.stats.iterations, solve_s=result.stats.solve_time,
               cost=result.cost_value, nodes=result.n_nodes,
               refinement=result.settings.get("refinement", ""),
               certificate=result.settings.get("continuous_dynamics", ""),
               mcap=str(outcome.mcap_path or ""))
    if result.success:
        row.update(measures(result))
        if args.name in ROBOTS:
            from robot_posture import posture

            row["posture"] = posture(str(outcome.mcap_path))
    row["process_inner_s"] = time.perf_counter() - START
    print(json.dumps(row))


if __name__ == "__main__":
    main()
