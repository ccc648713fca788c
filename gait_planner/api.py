"""The Python API: plan a gait, check it, record it and summarise it, as the command line
and the ROS node do (`gait_planner.pipeline`), from a script or a notebook:

    from gait_planner import PlanRequest, check, plan, record, summary

    result = plan(PlanRequest("walker3d", slope=5.0, compiled=True))  # RequestError if it
    # cannot be planned; result.success False if it did not converge
    print(check(result).summary())
    record(result, "runs/ramp.mcap")
    print(summary(result))

`plan` keeps one `Planner` per process (its built problems and its warm starts: a second
request of the same form reuses the first's problem), and starts, as the node and
`gait-planner plan` do, from the nearest plan in the warm-start store (`ocp.warm_starts`:
`make setup`'s default plans and anchors, earlier processes' plans); a request with
cold_start=True ignores both. Pass your own `Planner` to keep several apart.
`compiled=True` evaluates the derivatives with the per-node elements compiled to C, as the
node and the command line do by default (`make setup` compiles the shipped scenes' once);
without it CasADi builds them for the process (walker3d: about 20 s).
"""

from __future__ import annotations

from pathlib import Path

from gait_planner.model.loader import load_scene
from gait_planner.ocp.joint_state import start_of_joint_state
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.transition import (StartError, StartState, standing_start, start_of_plan,
                                         start_of_velocity)
from gait_planner.ocp.warm_starts import WarmStartStore
from gait_planner.pipeline import plan_problem, summary
from gait_planner.problem import SceneLookup, resolve
from gait_planner.request import PlanRequest, RequestError
from gait_planner.result import PlanResult
from gait_planner.transitions import start_of_recording

__all__ = ["PlanRequest", "PlanResult", "Planner", "RequestError", "StartError", "StartState",
           "check", "plan", "record", "standing_start", "start_of_joint_state", "start_of_plan",
           "start_of_recording", "start_of_velocity", "summary", "walk_replanned"]

_planner: Planner | None = None


def plan(request: PlanRequest | str, planner: Planner | None = None,
         scenes: SceneLookup = load_scene, start: StartState | None = None,
         halves: int | None = None, stop: bool = False) -> PlanResult:
    """The plan of `request` (a `PlanRequest`, or a scene's name for its default request
    with compiled derivatives),
    certified against the continuous dynamics, refined while the certificate asks and
    joined to request.steps half cycles, as the node plans it; nothing is written.
    Raises `RequestError` naming what cannot be planned; a plan that does not converge has
    success False and says why in its message. planner: the process's own by default;
    scenes: finds a scene by its name (`model.loader.load_scene`: the shipped scenes);
    start: a state to begin at (`standing_start`: the scene's standing pose at rest, its
    start phases first; `start_of_recording`, `ocp.transition.start_of_plan`,
    `start_of_velocity`, `start_of_joint_state`): the answer is the transition of `halves`
    half cycles (1 to 4) from it onto the request's gait, then request.steps of the gait's
    half cycles (`StartError` if the first phase's contacts cannot hold it); stop: instead
    of joining the gait, end standing at rest, both feet flat (from `start`, or the gait's
    first node)."""
    return plan_problem(_planner_for(planner), _problem(request, scenes), start=start,
                        halves=halves, stop=stop)


def _planner_for(planner: Planner | None) -> Planner:
    """`planner`, or the process's own (with the warm-start store), made on first use."""
    global _planner
    if planner is None:
        _planner = planner = _planner or Planner(library=WarmStartStore())
    return planner


def _problem(request: PlanRequest | str, scenes: SceneLookup):
    """The request resolved (a scene's name: its default request, derivatives compiled)."""
    if isinstance(request, str):
        request = PlanRequest(request, compiled=True)
    return resolve(request, scenes)


def walk_replanned(request: PlanRequest | str, half_cycles: int = 10, replan: bool = True,
                   planner: Planner | None = None, scenes: SceneLookup = load_scene,
                   progress=None, model_error=None, deadline: float | None = None) -> dict:
    """Walk `request` in MuJoCo from standing, `half_cycles` half cycles re-planned at
    every strike from the walker's measured state (replan False: one plan), then stop and
    stand 2 s (`gait_planner.walk.replan`); the walk's summary. planner, scenes: as `plan`;
    progress(line) hears each plan and strike; model_error: a
    `gait_planner.walk.model_error.ModelError`, how the simulated walker differs from the
    plans' model (masses, friction, contacts, a torque delay); deadline: a re-plan's time
    limit in half cycles of the gait (None: `walk.replan.DEADLINE`, 0.75; walker3d's
    re-plans need about 2)."""
    from gait_planner.walk.replan import DEADLINE, walk_replanned as walk

    problem = _problem(request, scenes)
    return walk(_planner_for(planner), problem.scene, problem.settings, half_cycles,
                replan=replan, progress=progress, model_error=model_error,
                deadline=DEADLINE if deadline is None else deadline)


def check(result: PlanResult):
    """The independent verifier's report of `result` (`gait_planner.verify`: the plan
    recorded to a temporary MCAP and read back; `.ok`, `.failures`, `.summary()`)."""
    from gait_planner.verify import verify_result

    return verify_result(result)


def record(result: PlanResult, path: str | Path, rrd: bool = False) -> Path:
    """Write `result` to the MCAP recording `path` (atomically; its topics are the node's)
    and, with rrd, the rerun recording beside it (same stem, .rrd), making the folder if
    needed; the MCAP's path."""
    from gait_planner.io.mcap_writer import write_plan_mcap

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    mcap = write_plan_mcap(result, path)
    if rrd:
        from gait_planner.viz.rerun_view import save_rrd

        save_rrd(result, mcap.with_suffix(".rrd"))
    return mcap
