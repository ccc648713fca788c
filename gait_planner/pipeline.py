"""One problem from plan to files: plan, certify, refine, record (MCAP + rerun .rrd).

Shared by the command line, the ROS node, the gait libraries and the Python API; knows
nothing of ROS. Every function takes a `Problem`: the request resolved once and checked
(`gait_planner.problem.resolve`, which refuses with `RequestError`); a plan that does not
converge is a `PlanResult` with success False (nothing is recorded for it).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from gait_planner.model.scene import Scene
from gait_planner.ocp.refine import refined_settings
from gait_planner.ocp.settings import GaitSettings, free_step_range
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.walk_on import walk_on
from gait_planner.problem import Problem
from gait_planner.request import PlanRequest
from gait_planner.result import PlanResult


@dataclass(frozen=True)
class Outcome:
    result: PlanResult
    mcap_path: Path | None
    rrd_path: Path | None


def output_stem(request: PlanRequest, scene_name: str) -> str:
    """The file stem for a checked request: its output_name (a bare file name,
    `request.checked`), or scene + time (`plan_and_record` adds _2, _3, ... if that name is
    taken: `unused_stem`)."""
    if request.output_name:
        return request.output_name.removesuffix(".mcap")
    return f"{scene_name}_{time.strftime('%Y%m%d-%H%M%S')}"


def unused_stem(folder: Path, stem: str) -> str:
    """`stem`, or else `stem`_2, _3, ...: the first with no .mcap or .rrd in `folder` (two
    automatic names made within the same second would otherwise be one file)."""
    candidate, number = stem, 1
    while any((folder / f"{candidate}{suffix}").exists() for suffix in (".mcap", ".rrd")):
        number += 1
        candidate = f"{stem}_{number}"
    return candidate


def prepare(planner: Planner, problem: Problem, rrd: bool = True) -> str:
    """Build `problem` in `planner` now (`Planner.prepare`), so that a request like it pays
    no build, and load what certifies and records a plan, which `plan_and_record` would
    load on first use: Pinocchio, the MCAP writer and its message
    encoder (~0.4 s) and, with rrd, rerun (~0.45 s; the node leaves it to its .rrd helper,
    `viz.rrd_recorder`). Returns how the problem's derivatives are evaluated."""
    how = planner.prepare(problem.scene, problem.settings)
    from gait_planner.io.mcap_writer import recording_encoder

    recording_encoder()
    import gait_planner.verify.continuous  # noqa: F401
    import gait_planner.verify.mechanics  # noqa: F401
    if rrd:
        import gait_planner.viz.rerun_view  # noqa: F401
    return how


def plan_problem(planner: Planner, problem: Problem) -> PlanResult:
    """The plan of `problem`, nothing written (`plan_joined` with its steps and start)."""
    return plan_joined(planner, problem.scene, problem.settings, steps=problem.steps,
                       warm_start=problem.warm_start)


def plan_joined(planner: Planner, scene: Scene, settings: GaitSettings, *, steps: int = 1,
                warm_start: bool = True) -> PlanResult:
    """A plan certified against the continuous dynamics and refined while the certificate
    asks (`plan_certified`; a speed without a step length searches the step:
    `plan_free_step`), then joined to `steps` half cycles (`ocp.walk_on`) and certified
    again; the certificate's maxima in its settings (`certificate_metadata`). A plan that
    does not converge has success False."""
    plan = plan_free_step if settings.step_length_free else plan_certified
    result, cert = plan(planner, scene, settings, warm_start=warm_start)
    if not result.success:
        return result
    walked = walk_on(result, steps)
    if walked is not result:  # more half cycles: certify what is published
        result, cert = certified(walked)
    return dataclasses.replace(result, settings={**result.settings,
                                                 **certificate_metadata(cert)})


def plan_and_record(planner: Planner, problem: Problem, output_dir: str | Path, *,
                    rrd: bool = True, stage: Callable[[str], None] | None = None) -> Outcome:
    """Plan `problem` (`plan_problem`); on success write <output_dir>/<stem>.mcap (and .rrd).

    stage: called with "recording" once the plan is found, before anything is written (an
    exception it raises ends the request with nothing recorded)."""
    request = problem.request
    stem = output_stem(request, problem.scene.name)
    folder = Path(output_dir)
    folder.mkdir(parents=True, exist_ok=True)
    result = plan_problem(planner, problem)
    if not result.success:
        return Outcome(result, None, None)
    if stage is not None:
        stage("recording")
    from gait_planner.io.mcap_writer import write_plan_mcap

    if not request.output_name:  # an automatic name never replaces an earlier recording
        stem = unused_stem(folder, stem)
    mcap = write_plan_mcap(result, folder / f"{stem}.mcap", allowed_dirs=[folder])
    rrd_path = None
    if rrd:
        from gait_planner.viz.rerun_view import save_rrd

        rrd_path = save_rrd(result, folder / f"{stem}.rrd")
    return Outcome(result, mcap, rrd_path)


def plan_certified(planner: Planner, scene: Scene, settings: GaitSettings, *,
                   warm_start: bool = True, guess: str = "kinematic"):
    """`Planner.plan`, then, while the latest converged plan has defects of its grid (it
    misses the continuous-dynamics certificate, or its efforts zigzag: `grid_defects`) and
    `settings.refinements` allow, the same request on a grid twice as fine from that plan
    (`ocp.refine`). Of the converged plans the one with the fewest defects (then the
    smallest torque error) is returned: a refinement may cure the certificate and still
    zigzag (walker3d on 3 intervals per phase: on 6 the certificate is 0.221 % and the
    knee's effort zigzags, on 12 every check passes). All plans share
    settings.max_solve_time. Returns (result, certificate; None if the plan failed); after
    a refinement the result's stats count every plan's iterations and time, and its
    settings["refinement"] says what was refined and why."""
    start = time.perf_counter()
    result = planner.plan(scene, settings, warm_start=warm_start, guess=guess)
    if not result.success:
        return result, None
    result, cert = certified(result)
    best = latest = (result, cert, grid_defects(result, cert))
    coarse, notes, runs = settings, [], [result.stats]
    for _ in range(settings.refinements):
        defects = latest[2]
        if not defects:
            break
        left = settings.max_solve_time - (time.perf_counter() - start)
        fine = dataclasses.replace(refined_settings(coarse), max_solve_time=max(left, 1e-3))
        why = (f"the plan on {sum(coarse.intervals)} intervals "
               f"({latest[0].settings['initial_guess']}): {'; '.join(defects)}")
        if left <= 0:
            notes.append(f"{why}; no time left to refine")
            break
        planner.stage(f"refining the grid to {sum(fine.intervals)} intervals")
        refined = planner.plan(scene, fine, warm_start=warm_start, refine_from=coarse)
        runs.append(refined.stats)
        if not refined.success:
            notes.append(f"{why}; refined to {sum(fine.intervals)}: {refined.message}")
            break
        refined, refined_cert = certified(refined)
        latest, coarse = (refined, refined_cert, grid_defects(refined, refined_cert)), fine
        notes.append(f"{why}; refined to {sum(fine.intervals)}: "
                     + ("; ".join(latest[2]) or refined_cert.summary()))
        if (len(latest[2]), refined_cert.max_torque_calm) < (len(best[2]), best[1].max_torque_calm):
            best = latest
    result, cert, _ = best
    if len(runs) > 1:
        stats = dataclasses.replace(
            result.stats, iterations=sum(r.iterations for r in runs),
            solve_time=sum(r.solve_time for r in runs),
            evaluation_time=sum(r.evaluation_time for r in runs))
        grid = ("on the refined grid" if result.n_nodes - 1 != sum(settings.intervals)
                else "on the requested grid")
        result = dataclasses.replace(
            result, stats=stats,
            message=f"{result.message} {grid} ({stats.iterations} iterations in all)")
    if notes:
        result = dataclasses.replace(result, settings={**result.settings,
                                                       "refinement": " | ".join(notes)})
    return result, cert


STEP_TOLERANCE = 0.005  # m: a free step length is found to within this


def plan_free_step(planner: Planner, scene: Scene, settings: GaitSettings, *,
                   warm_start: bool = True):
    """The plan at settings.speed whose step length, within `ocp.settings.free_step_range`,
    has the least cost per metre walked (J / step length): people choose the step of
    least cost at a speed, and J over one half cycle alone would favour the shortest
    steps. Golden-section search over the step length to `STEP_TOLERANCE` (each trial a
    plan of the same built problem, warm-started from the last: the step length is a
    parameter), then `plan_certified` at the best step. Returns (result, certificate) as
    `plan_certified`, its stats counting every trial's iterations and solve time; its
    settings["step_length_search"] says what was tried."""
    low, high = free_step_range(settings)
    tried: dict[float, float] = {}
    spent = [0, 0.0]  # the trials' iterations and solve time
    start = time.perf_counter()

    def cost_per_metre(step: float) -> float:
        trial = planner.plan(scene, dataclasses.replace(settings, step_length=step),
                             warm_start=warm_start or bool(tried))
        spent[0] += trial.stats.iterations
        spent[1] += trial.stats.solve_time
        tried[step] = trial.cost_value / step if trial.success else math.inf
        return tried[step]

    golden = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = low, high
    c, d = b - golden * (b - a), a + golden * (b - a)
    fc, fd = cost_per_metre(c), cost_per_metre(d)
    while b - a > STEP_TOLERANCE:
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - golden * (b - a)
            fc = cost_per_metre(c)
        else:
            a, c, fc = c, d, fd
            d = a + golden * (b - a)
            fd = cost_per_metre(d)
    best = min(tried, key=tried.get)
    result, cert = plan_certified(planner, scene, dataclasses.replace(settings, step_length=best),
                                  warm_start=True)
    result = dataclasses.replace(result, stats=dataclasses.replace(
        result.stats, iterations=result.stats.iterations + spent[0],
        solve_time=result.stats.solve_time + spent[1]))
    search = (f"step length free at {settings.speed:g} m/s within [{low:.4f}, {high:.4f}] m: "
              f"{len(tried)} plans in {time.perf_counter() - start:.1f} s, least J per metre "
              f"at {best:.4f} m; J/m tried: "
              + ", ".join(f"{s:.4f} m: {j:.4f}" for s, j in sorted(tried.items())))
    return dataclasses.replace(result, settings={**result.settings,
                                                 "step_length_search": search}), cert


def grid_defects(result: PlanResult, cert) -> list[str]:
    """What a finer grid can cure, in sentences: the continuous-dynamics certificate's
    failures (`cert`, of `result`) and efforts that zigzag from node to node away from
    contact switches (`gait_planner.verify.physical`; walker2d and walker3d on 6 intervals
    per phase: the swing knee's effort as it reaches its 75 deg limit)."""
    from gait_planner.io.messages import node_efforts
    from gait_planner.verify.physical import effort_zigzags

    zigzags = effort_zigzags(node_efforts(result), result.active_contacts,
                             result.joint_angle_names)
    return list(cert.failures) + ([f"efforts zigzag at (angle, node) {zigzags[:4]}"]
                                  if zigzags else [])


def continuous_certificate(result: PlanResult):
    """The certificate of `certified(result)`, the result left as it is."""
    return certified(result)[1]


def certified(result: PlanResult):
    """(result, certificate): `gait_planner.verify.continuous` on what the result's messages
    will publish: the efforts of `node_efforts` and the foot wrenches of `foot_wrenches`
    (moved to the world origin), so the certificate in the metadata is the one a reader of
    the recording gets. A scene drafted from a URDF is certified on that URDF
    (`gait_planner.verify.robot`), and the result returned carries its locked joints'
    `held_efforts` (a new result; `result` is not changed)."""
    from gait_planner.io.messages import foot_wrenches, node_efforts
    from gait_planner.verify.continuous import certificate
    from gait_planner.verify.mechanics import parse_scene

    scene = parse_scene(result.scene.source)
    wrenches = {body: np.zeros((result.n_nodes, 6)) for body, _ in scene.contacts.values()}
    for n in range(result.n_nodes):
        for body, r, F, M, _ in foot_wrenches(result, n):
            wrenches[body][n] = np.concatenate([F, M + np.cross(r, F)])
    if result.scene.robot is not None:  # drafted from a URDF: certified on it
        from gait_planner.verify.robot import robot_certificate

        cert, held = robot_certificate(
            scene, result.scene.robot.urdf, result.times, result.q, result.joint_angles,
            node_efforts(result), wrenches, result.active_contacts)
        return dataclasses.replace(result, held_efforts={**result.held_efforts, **held}), cert
    return result, certificate(scene, result.times, result.q, node_efforts(result), wrenches,
                               result.active_contacts)


def certificate_metadata(cert) -> dict[str, str]:
    """The certificate's maxima as metadata strings (MCAP record, service response): torque
    errors relative to the peak effort away from contact switches and at them, the floating
    base's residual force (N) and moment (N m) away from switches, and the summary line."""
    return {"continuous_torque_error": repr(cert.max_torque_calm),
            "continuous_torque_error_at_switches": repr(cert.max_torque_switch),
            "continuous_base_force": repr(cert.max_force_calm),
            "continuous_base_moment": repr(cert.max_moment_calm),
            "continuous_dynamics": cert.summary()}


def summary(outcome: Outcome | PlanResult) -> dict:
    """The JSON summary of a plan (command line, logs, the Python API), its files' paths
    empty for a result not recorded."""
    if isinstance(outcome, PlanResult):
        outcome = Outcome(outcome, None, None)
    r, s = outcome.result, outcome.result.stats
    return {
        "success": r.success, "message": r.message, "scene": r.scene.name,
        "cost": r.cost_name, "cost_value": r.cost_value, "duration": r.duration,
        "step_length": r.step_length, "friction_coefficient": r.friction_coefficient,
        "phase_scaling": [float(x) for x in r.phase_scaling], "iterations": s.iterations,
        "solve_time_s": s.solve_time, "build_time_s": s.build_time,
        "derivatives": r.settings.get("derivatives", ""),
        "max_constraint_violation": s.max_constraint_violation,
        "max_dynamics_residual": s.max_dynamics_residual,
        "max_friction_violation": s.max_friction_violation,
        "continuous_dynamics": r.settings.get("continuous_dynamics", ""),
        "refinement": r.settings.get("refinement", ""),
        "nodes": r.n_nodes, "mcap": str(outcome.mcap_path or ""),
        "rrd": str(outcome.rrd_path or ""),
    }
