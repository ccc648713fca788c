"""One problem from plan to files: plan (`gait_planner.strategies`: certified, refined,
the step searched), join the half cycles, record (MCAP + rerun .rrd).

Shared by the command line, the ROS node, the gait libraries and the Python API; knows
nothing of ROS. Every function takes a `Problem`: the request resolved once and checked
(`gait_planner.problem.resolve`, which refuses with `RequestError`); a plan that does not
converge is a `PlanResult` with success False (nothing is recorded for it).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from gait_planner.model.scene import Scene
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.walk_on import walk_on
from gait_planner.ocp.warm_starts import StoredPlan
from gait_planner.problem import Problem
from gait_planner.request import PlanRequest
from gait_planner.result import PlanResult
from gait_planner.ocp.transition import StartState
from gait_planner.strategies import plan_certified, plan_free_step
from gait_planner.transitions import plan_transition


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


def plan_problem(planner: Planner, problem: Problem, seed: StoredPlan | None = None,
                 start: StartState | None = None, halves: int | None = None,
                 stop: bool = False) -> PlanResult:
    """The plan of `problem`, nothing written (`plan_joined` with its steps and start;
    seed: a gait library's start, `gaitlib.serve.library_start`); with `start`, the
    transition of `halves` half cycles (None: the default) from it onto the gait and then
    the gait's steps half cycles (`gait_planner.transitions.plan_transition`;
    `ocp.transition.StartError` if it cannot start there); with `stop`, from `start` (or
    the gait's first node) to standing at rest in `halves` half cycles."""
    if start is not None or stop:
        return plan_transition(planner, problem.scene, problem.settings, start,
                               steps=problem.steps, warm_start=problem.warm_start,
                               halves=halves, stop=stop)
    return plan_joined(planner, problem.scene, problem.settings, steps=problem.steps,
                       warm_start=problem.warm_start, seed=seed)


def plan_joined(planner: Planner, scene: Scene, settings: GaitSettings, *, steps: int = 1,
                warm_start: bool = True, seed: StoredPlan | None = None) -> PlanResult:
    """A plan certified against the continuous dynamics and refined while the certificate
    asks (`strategies.plan_certified`; a speed without a step length searches the step:
    `strategies.plan_free_step`; seed: a start they may take), then joined to `steps`
    half cycles (`ocp.walk_on`) and certified again; the certificate's maxima in its
    settings (`certificate_metadata`). A plan that does not converge has success False."""
    from gait_planner.verify.certify import certificate_metadata, certified

    plan = plan_free_step if settings.step_length_free else plan_certified
    result, cert = plan(planner, scene, settings, warm_start=warm_start, seed=seed)
    if not result.success:
        return result
    walked = walk_on(result, steps)
    if walked is not result:  # more half cycles: certify what is published
        result, cert = certified(walked)
    return dataclasses.replace(result, settings={**result.settings,
                                                 **certificate_metadata(cert)})


def plan_and_record(planner: Planner, problem: Problem, output_dir: str | Path, *,
                    rrd: bool = True, stage: Callable[[str], None] | None = None,
                    seed: StoredPlan | None = None, start: StartState | None = None,
                    halves: int | None = None, stop: bool = False) -> Outcome:
    """Plan `problem` (`plan_problem`, from `seed` or the state `start` if given); on
    success write
    <output_dir>/<stem>.mcap (and .rrd).

    stage: called with "recording" once the plan is found, before anything is written (an
    exception it raises ends the request with nothing recorded)."""
    request = problem.request
    stem = output_stem(request, problem.scene.name)
    folder = Path(output_dir)
    folder.mkdir(parents=True, exist_ok=True)
    result = plan_problem(planner, problem, seed, start, halves, stop)
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
