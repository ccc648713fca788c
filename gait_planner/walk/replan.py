"""Walk by re-planning (issue #63): from standing to standing in MuJoCo, each step planned
again from the walker's measured state.

`walk_replanned(planner, scene, settings, half_cycles)`:

1. Before the walk, with the walker standing (not charged to the walk): the start from
   standing (`transitions.plan_transition` from `standing_start`: the scene's start phases,
   `START_HALVES` half cycles onto the gait, then `AHEAD` of the gait's half cycles), and
   one re-plan and one stop planned from the gait's own first node, so that the problems of
   the walk's re-plans are built and each has a last transition to start from.
2. The walker stands at the start plan's first node, at rest, and tracks it with the
   reference controller (`walk.simulation`, config/walk.yaml).
3. At every strike of the plan it follows (a node where the gait's first phase begins:
   `strikes`), the walker's state is measured (`measured_start`: the joints and the root
   body's frame, as a robot publishes them) and a transition from it back onto the gait is
   planned (`HALVES` half cycles, then `AHEAD` of the gait's). **The simulated clock waits
   for no plan**: the walker goes on with the plan it has for as long as the solve took on
   this machine (wall time), then switches to the new plan at that plan's time (the new
   plan begins at the measured state, so it starts late by the solve). A strike passed
   while a plan is being solved is not re-planned; a re-plan's solver stops after `DEADLINE`
   of the gait's half cycle; one that fails, stops or is refused is recorded and the walker
   keeps its plan.
4. At strike `half_cycles` - `STOP_LEAD` the stop is planned (`plan_transition(stop=True)`,
   `STOP_HALVES`: to standing at rest) from the plan's own state at strike `half_cycles`,
   where it takes over; a stop that arrives after that strike is dropped and planned again
   for a strike further on (a stop taking over 0.74 s late made walker2d fall at once): planned from the measured state it took
   165-208 iterations (walker2d, 2.5-3.4 s, 2026-12-07) and the walker was far past it when
   it arrived. When the stop ends the walker holds its last node for `stand` s.

standing=False begins the walk moving at the gait's first node instead (walker3d's start
from standing is not robust yet, docs/design.md section 16). replan=False is the same walk
with one plan: the start plan carries `half_cycles` of the
gait and only the stop is planned from the measured state (a walker cannot stop
otherwise), so the gain of re-planning is measured, not assumed.

The summary (JSON-ready): half cycles walked, why the walk ended, every plan (kind, the
simulated time of its measured state, converged, iterations, wall time, when it took over),
the feedback share (RMS feedback over RMS planned effort), unplanned touches (each plan's,
in its own time), slides, the walker's centre-of-mass speed when it stood still at the end.
"""

from __future__ import annotations

import dataclasses
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from gait_planner.model.angles import angle_names
from gait_planner.model.scene import Scene
from gait_planner.ocp.joint_state import start_of_joint_state
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.transition import StartError, StartState, standing_start, start_of_plan
from gait_planner.result import PlanResult
from gait_planner.strategies import plan_certified
from gait_planner.transitions import plan_transition, start_of_node
from gait_planner.walk.clock import PlanClock
from gait_planner.walk.controller import ReferenceController
from gait_planner.walk.reference import Reference
from gait_planner.walk.simulation import Simulation
from gait_planner.walk.slides import Slides
from gait_planner.walk.touches import Touches

__all__ = ["AHEAD", "HALVES", "START_HALVES", "STOP_HALVES", "measured_start", "strikes",
           "walk_replanned"]

START_HALVES = 2  # half cycles of the start from standing (issue #62: K=1 missed the check)
HALVES = 2  # half cycles of a re-plan onto the gait (`transitions.HALVES`)
STOP_HALVES = 1  # of the stop (`transitions.STOP_HALVES`)
AHEAD = 4  # the gait's half cycles a plan carries after its transition: what the walker
#            follows while the next plan is solved
# A re-plan's solver stops after this share of the gait's half cycle (its time limit): a
# plan that would take over later than that, at a state the walker has long left, is
# dropped and the walker keeps the plan it has (walker2d: a re-plan of 303 iterations took
# 4.6 s and the walker then ran out of plan, 2026-12-07).
DEADLINE = 0.75
# The stop is planned this many strikes before it takes over: from the plan's state at the
# strike that ends the walk's last half cycle (one strike ahead, walker2d's stop of 72
# iterations took 1.2 s and the walker was past that strike when it arrived, 2026-12-07).
STOP_LEAD = 2
TOUCH_SHARE = 0.1  # of the weight: a point carrying more is touching (`walk_plan`)


def measured_start(sim: Simulation, scene: Scene, origin: str) -> StartState:
    """The walker's state as a robot publishes it (joint states and the root frame's pose
    and twist in the world: the root body's centre of mass and directors, a drafted
    robot's base link), converted by `ocp.joint_state.start_of_joint_state`."""
    import mujoco

    model, data, wm = sim.model, sim.data, sim.wm
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    twist = np.zeros(6)
    if scene.robot is None:
        kind, index = mujoco.mjtObj.mjOBJ_SITE, wm.root_site
        position, R = data.site_xpos[index].copy(), data.site_xmat[index].reshape(3, 3)
    else:
        kind, index = mujoco.mjtObj.mjOBJ_BODY, model.body(wm.root).id
        position, R = data.xpos[index].copy(), data.xmat[index].reshape(3, 3)
    mujoco.mj_objectVelocity(model, data, kind, index, twist, 0)
    wxyz = np.zeros(4)
    mujoco.mju_mat2Quat(wxyz, np.ascontiguousarray(R).reshape(-1))
    return start_of_joint_state(scene, angle_names(scene), data.qpos[wm.qpos],
                                data.qvel[wm.dof], position, np.r_[wxyz[1:], wxyz[0]],
                                twist[3:], twist[:3], origin)


def strikes(result: PlanResult) -> np.ndarray:
    """Times (s from the plan's start) of the nodes after node 0 at which the gait's first
    phase begins (phase names without their "~k" copy suffix): where a re-plan may start."""
    first = result.scene.gait.phases[0].name
    base = [p.split("~")[0] for p in result.phases]
    t = np.asarray(result.times, float) - float(result.times[0])
    return np.array([t[n] for n in range(1, len(base))
                     if base[n] == first and base[n - 1] != first])


@dataclasses.dataclass
class _Segment:
    """The plan the walker follows, from simulated time `begin` (its node 0's state)."""

    result: PlanResult
    ref: Reference
    clock: PlanClock
    control: ReferenceController
    touches: Touches
    strikes: np.ndarray
    kind: str


def walk_replanned(planner: Planner, scene: Scene, settings: GaitSettings,
                   half_cycles: int = 10, *, replan: bool = True, standing: bool = True,
                   stand: float = 2.0,
                   config: dict[str, Any] | None = None,
                   wall: Callable[[], float] = time.perf_counter,
                   plan: Callable[..., PlanResult] = plan_transition,
                   progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """The walk of the module docstring. standing False: the walk begins moving, at the
    gait's first node (its start plan the transition from it, which is the gait), as
    `walk.walk_plan.walk` begins. wall: the clock the solves are timed with; plan:
    `transitions.plan_transition` (a test may pass a slower one); progress(line) hears each
    plan and strike."""
    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.io.mcap_writer import write_plan_mcap
    from gait_planner.walk.walk_plan import (check_feet, load_config, stop_reason,
                                             walking_direction)

    if isinstance(half_cycles, bool) or not isinstance(half_cycles, int) or half_cycles < 1:
        raise ValueError(f"half_cycles must be an integer >= 1, got {half_cycles!r}")
    check_feet(scene, scene.name)
    say = progress or (lambda line: None)
    cfg = config or load_config()
    plans: list[dict[str, Any]] = []

    def timed(kind: str, start: StartState | None, at: float, limit: float | None = None,
              **kw) -> PlanResult | None:
        began = wall()
        try:
            r = plan(planner, scene, settings if limit is None else
                     settings.with_solve(max_solve_time=limit), start, **kw)
        except StartError as err:
            r, message = None, f"refused: {err}"
        else:
            message = r.message if not r.success else "converged"
        took = wall() - began
        plans.append({"kind": kind, "measured_at_s": round(at, 4),
                      "success": r is not None and r.success,
                      "iterations": None if r is None else r.stats.iterations,
                      "wall_s": round(took, 4), "message": message[:200]})
        say(f"{kind} at t = {at:.3f} s: {message[:80]} "
            f"({plans[-1]['iterations']} iterations, {took:.2f} s)")
        return r if r is not None and r.success else None

    ahead = AHEAD if replan else half_cycles + 1
    gait, _ = plan_certified(planner, scene, settings)
    if not gait.success:
        return {"scene": scene.name, "half_cycles_walked": 0, "replan": replan,
                "stopped": f"the gait was not planned: {gait.message}", "plans": plans}
    first = timed("start", standing_start(scene) if standing else start_of_plan(gait), 0.0,
                  steps=ahead, halves=START_HALVES)
    if first is None:
        return {"scene": scene.name, "half_cycles_walked": 0, "replan": replan,
                "stopped": "the start was not planned", "plans": plans}
    if replan:  # build the re-plan's problem and give it a last transition to start from
        timed("prepare re-plan", start_of_plan(gait), 0.0, steps=AHEAD, halves=HALVES)
    timed("prepare stop", None, 0.0, stop=True, halves=STOP_HALVES, steps=1)
    prepared = len(plans)

    with tempfile.TemporaryDirectory() as folder:  # the walker's model from a recording
        rec = read_plan_mcap(write_plan_mcap(first, Path(folder) / "start.mcap"))
    sim = Simulation.build(rec, scene, cfg, None)
    model, data, gains = sim.model, sim.data, sim.gains
    h = model.opt.timestep
    names = [c.name for c in scene.contacts]
    threshold = TOUCH_SHARE * sim.weight()
    slides = Slides(names, threshold, np.asarray(first.ground.normal, float))
    pace, place, stop = cfg["clock"], cfg["placement"], cfg["stop"]
    period = float(first.settings["gait_duration"])  # s, the gait's half cycle
    gait_speed = first.step_length / period

    def segment(result: PlanResult, begin: float, kind: str) -> _Segment:
        ref = Reference.from_result(result)
        clock = PlanClock(pace["pace_gain"], pace["rate_min"], pace["rate_max"])
        clock.offset = -begin
        control = ReferenceController(model, sim.wm, ref, gains, place["max_shift"], 1.0,
                                      clock)
        return _Segment(result, ref, clock, control,
                        Touches(ref.times, ref.active, names, threshold),
                        strikes(result) if kind != "stop" else np.array([]), kind)

    seg = segment(first, 0.0, "start")
    sim.place(seg.ref)
    along = walking_direction(seg.ref)
    touches: list[dict[str, Any]] = []
    fbs, efforts, parts = [], [], []
    pending: tuple[float, float, PlanResult, str] | None = None  # (switch at, begin, plan)
    busy_until = 0.0  # simulated time at which the solver is free again
    walked, next_strike, standing_since = 0, 0, None
    reason = "completed"
    while True:
        step = sim.step(seg.control, seg.clock, seg.ref, seg.touches, slides)
        fbs.append(step.fb)
        efforts.append(step.plan_effort)
        parts.append("standing" if standing_since is not None else seg.kind)
        seg.clock.pace(h, float(along @ (data.subtree_com[seg.control.root]
                                         - seg.ref.com_at(step.tau))), gait_speed)
        reason = stop_reason(stop, data, step.com[2], step.phi_ref[2], step.tilt, step.error,
                             angle_names(scene), step.time)
        if reason != "completed":
            break
        t, tau = data.time, seg.clock(data.time)
        if pending is not None and t >= pending[0]:
            touches += [dict(x, plan=len(touches)) for x in seg.touches.summary()]
            seg = segment(pending[2], pending[1], pending[3])
            # the strikes the new plan had before it took over are the old plan's
            pending, next_strike = None, int(np.sum(seg.strikes <= seg.clock(t) + 0.5 * h))
            plans[-1]["took_over_s"] = round(t, 4)
            continue
        if seg.kind == "stop" and tau >= seg.ref.times[-1]:
            standing_since = t if standing_since is None else standing_since
            if t - standing_since >= stand:
                break
            continue
        if tau > seg.ref.times[-1]:
            reason = f"the plan ran out at t = {t:.3f} s (its re-plans failed)"
            break
        if next_strike < len(seg.strikes) and tau >= seg.strikes[next_strike] - 0.5 * h:
            next_strike += 1
            walked += 1
            say(f"strike {walked} at t = {t:.3f} s")
            if pending is not None or t < busy_until or seg.kind == "stop":
                continue  # a plan is being solved, or the walker stops
            ahead = min(STOP_LEAD, len(seg.strikes) - next_strike) - 1
            if walked >= half_cycles - STOP_LEAD and ahead >= 0:
                # the stop, from the plan's state at a strike ahead, taking over there
                n = int(np.searchsorted(seg.ref.times,
                                        seg.strikes[next_strike + ahead] - 0.5 * h))
                at = t + float(seg.ref.times[n]) - tau
                start = start_of_node(scene, seg.result.q, seg.result.times,
                                      seg.result.generalized_force, n,
                                      f"the plan at its strike at t = {at:.3f} s")
                r = timed("stop", start, at, stop=True, halves=STOP_HALVES, steps=1)
                busy_until = t + plans[-1]["wall_s"]
                if r is not None and busy_until > at + 0.5 * h:  # planned again further on
                    plans[-1].update(dropped=True, message=f"arrived {busy_until - at:.3f} s "
                                     "after its strike: dropped")
                elif r is not None:
                    pending = (at, at, r, "stop")
                continue
            if not replan or (standing and seg.kind == "start" and next_strike == 1):
                continue  # one plan / the end of the start phases
            start = measured_start(sim, scene, f"the walker at t = {t:.3f} s")
            r = timed("re-plan", start, t, DEADLINE * period, steps=AHEAD, halves=HALVES)
            busy_until = t + plans[-1]["wall_s"]
            if r is not None:
                pending = (busy_until, t, r, "walk")
    touches += [dict(x, plan=len(touches)) for x in seg.touches.summary()]
    import mujoco

    mujoco.mj_subtreeVel(model, data)
    speed = float(np.linalg.norm(data.subtree_linvel[seg.control.root]))
    rms = lambda x: float(np.sqrt(np.mean(np.square(x)))) if len(x) else 0.0  # noqa: E731
    walk_plans = plans[prepared:]
    replans = [p for p in walk_plans if p["kind"] == "re-plan"]
    return {
        "scene": scene.name, "replan": replan, "from_standing": standing,
        "half_cycles": half_cycles,
        "half_cycles_walked": walked, "stopped": reason,
        "stood": standing_since is not None and reason == "completed",
        "final_com_speed_m_s": round(speed, 4), "time_walked_s": round(float(data.time), 4),
        "feedback_share": rms(fbs) / max(rms(efforts), 1e-12),
        "feedback_share_by_part": {  # start, walk (the re-plans), stop, standing after it
            part: rms([f for f, p in zip(fbs, parts) if p == part])
            / max(rms([e for e, p in zip(efforts, parts) if p == part]), 1e-12)
            for part in dict.fromkeys(parts)},
        "replans": len(replans), "replans_converged": sum(p["success"] for p in replans),
        "replan_wall_median_s": (float(np.median([p["wall_s"] for p in replans]))
                                 if replans else None),
        "replan_iterations_median": (float(np.median([p["iterations"] for p in replans
                                                      if p["iterations"] is not None]))
                                     if replans else None),
        "plans": plans, "unplanned_touches": touches, "foot_slide": slides.summary(),
        "charged": "each plan took over after its solve's wall time on this machine",
    }
