"""Walk by re-planning (issue #63): from standing to standing in MuJoCo, each step planned
again from the walker's measured state.

`walk_replanned(planner, scene, settings, half_cycles)` (plans from `planner`; another
`walk.followed.Planning` may answer instead, e.g. the ROS node):

1. Before the walk, with the walker standing (not charged to the walk): the start from
   standing (`transitions.plan_transition` from `standing_start`: the scene's start phases,
   `transitions.HALVES` half cycles onto the gait, then `AHEAD` of the gait's), and
   one re-plan and one stop planned from the gait's own first node, so that the problems of
   the walk's re-plans are built and each has a last transition to start from.
2. The walker stands at the start plan's first node, at rest, and tracks it with the
   reference controller (`walk.simulation`, config/walk.yaml).
3. At every strike of the plan it follows (a node where the gait's first phase begins:
   `walk.followed.strikes`), the walker's state is measured (`walk.followed.measure`: the
   joints and the root body's frame, as a robot publishes them) and a transition from it
   back onto the gait is planned (`HALVES` half cycles again, then `AHEAD`). **The
   simulated clock waits for no plan**: the walker goes on with the plan it has for as
   long as the solve took on this machine (wall time), then switches to the new plan at
   that plan's time (the new plan begins at the measured state, so it starts late by the
   solve). A strike passed while a plan is being solved is not re-planned; a re-plan's
   solver stops after `DEADLINE` of the gait's half cycle; one that fails, stops or is
   refused is recorded and the walker keeps its plan.
4. At strike `half_cycles` - `STOP_LEAD` the stop is planned (`plan_transition(stop=True)`,
   `transitions.STOP_HALVES`: to standing at rest) from the plan's own state at strike
   `half_cycles`, where it takes over. A stop that fails or arrives after that strike is
   dropped (one taking over 0.74 s late made walker2d fall at once) and planned again for a
   strike further on, after a re-plan that extends the walk; it is solved to the end (a
   late one is kept by the planner and the next starts from it). From the plan's own state
   at a strike of its gait the stop repeats the one prepared before the walk, warm, in one
   iteration (`transitions.REPEATED_ATTEMPT`). A walk that has not stopped
   `half_cycles` + `lead` strikes past the last asked ends there. Planned from the
   measured state the stop took 165-208 iterations (walker2d, 2.5-3.4 s, 2026-12-07) and
   the walker was far past it when it arrived. When the stop ends the walker holds its last
   node for `stand` s.

standing=False begins the walk moving at the gait's first node instead. replan=False is
the same walk with one plan: the start plan carries `half_cycles` of the gait and only the
stop is planned during the walk (a walker cannot stop otherwise), so the gain of
re-planning is measured, not assumed.

The summary (JSON-ready): half cycles walked, why the walk ended, every plan (kind, the
simulated time of its measured state, converged, iterations, wall time, when it took over),
the feedback share (RMS feedback over RMS planned effort), unplanned touches (each plan's,
in its own time), slides, the walker's centre-of-mass speed when it stood still at the end.
"""

from __future__ import annotations

import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from gait_planner.model.angles import angle_names
from gait_planner.model.scene import Scene
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.transition import StartState, standing_start
from gait_planner.result import PlanResult
from gait_planner.transitions import HALVES, STOP_HALVES, plan_transition, start_of_node
from gait_planner.walk.clock import PlanClock
from gait_planner.walk.controller import ReferenceController
from gait_planner.walk.followed import (Answer, Followed, Measured, Planning, local_planning,
                                        measure, measured_start)
from gait_planner.walk.model_error import ModelError
from gait_planner.walk.simulation import Simulation
from gait_planner.walk.slides import Slides
from gait_planner.walk.touches import Touches

__all__ = ["AHEAD", "DEADLINE", "STOP_LEAD", "walk_replanned"]

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


@dataclass
class _Segment:
    """The plan the walker follows since it took over."""

    plan: Followed
    clock: PlanClock
    control: ReferenceController
    touches: Touches
    kind: str  # "start", "walk" (a re-plan), "stop"
    strikes: np.ndarray  # where a re-plan may start (none once the walker stops)


def walk_replanned(planner: Planner | None, scene: Scene, settings: GaitSettings | None,
                   half_cycles: int = 10, *, replan: bool = True, standing: bool = True,
                   stand: float = 2.0, deadline: float = DEADLINE, carry: int | None = None,
                   config: dict[str, Any] | None = None,
                   wall: Callable[[], float] = time.perf_counter,
                   plan: Callable[..., PlanResult] = plan_transition,
                   planning: Planning | None = None,
                   progress: Callable[[str], None] | None = None,
                   model_error: ModelError | None = None) -> dict[str, Any]:
    """The walk of the module docstring. standing False: the walk begins moving, at the
    gait's first node (its start plan the transition from it, which is the gait), as
    `walk.walk_plan.walk` begins. deadline: a re-plan's time limit in half cycles of the
    gait (`DEADLINE`; above 1, the stop is planned ceil(deadline) + 1 strikes ahead and a
    plan carries 2 ceil(deadline) + 2 of the gait's half cycles); carry: how many of the
    gait's half cycles a plan carries instead (more keeps the walker in plan through more
    late answers; each answer is larger). wall: the clock the
    solves are timed with; plan:
    `transitions.plan_transition` (a test may pass a slower one) for `local_planning` of
    (planner, scene, settings); planning: another `walk.followed.Planning` instead (planner
    and settings unused); progress(line) hears each plan and strike; model_error: how the
    simulated walker differs from the plans' model (`walk.model_error`, as in
    `walk.walk_plan.walk`, whose summary key "model_error" this one has too; the plans
    know nothing of it)."""
    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.io.mcap_writer import write_plan_mcap
    from gait_planner.walk.walk_plan import (TOUCH_SHARE, check_feet, load_config,
                                             recorded_robot, stop_reason, walking_direction)

    if isinstance(half_cycles, bool) or not isinstance(half_cycles, int) or half_cycles < 1:
        raise ValueError(f"half_cycles must be an integer >= 1, got {half_cycles!r}")
    check_feet(scene, scene.name)
    say = progress or (lambda line: None)
    cfg = config or load_config()
    planning = planning or local_planning(planner, scene, settings, plan)
    plans: list[dict[str, Any]] = []

    def timed(kind: str, start: StartState | None, at: float, limit: float | None = None,
              measured: Measured | None = None, **fields) -> Followed | None:
        began = wall()
        answer: Answer = planning(kind, start, measured, limit, **fields)
        took = wall() - began
        # unrounded: the walk compares them (a plan takes over at measured_at_s + wall_s)
        plans.append({"kind": kind, "measured_at_s": at, "success": answer.success,
                      "iterations": answer.iterations, "wall_s": took,
                      "message": answer.message[:200]})
        say(f"{kind} at t = {at:.3f} s: {answer.message[:80]} "
            f"({answer.iterations} iterations, {took:.2f} s)")
        return answer.followed if answer.success else None

    # a slower limit keeps more of the gait ahead and plans the stop earlier: two late
    # plans in a row must not run the walker out of plan (walker3d, limit 2 half cycles)
    lead = max(STOP_LEAD, math.ceil(deadline) + 1)
    carried = carry or max(AHEAD, 2 * math.ceil(deadline) + 2)
    ahead = carried if replan else half_cycles + 1
    first = timed("start", standing_start(scene) if standing else None, 0.0, steps=ahead,
                  halves=HALVES)
    if first is None:
        return {"scene": scene.name, "half_cycles_walked": 0, "replan": replan,
                "stopped": f"the start was not planned: {plans[-1]['message']}",
                "plans": plans}
    if replan:  # build the re-plan's problem and give it a last transition to start from
        timed("prepare re-plan", None, 0.0, steps=carried, halves=HALVES)
    timed("prepare stop", None, 0.0, stop=True, halves=STOP_HALVES, steps=1)
    prepared = len(plans)

    rec = first.recording
    if rec is None:  # the walker's model from a recording of the start
        with tempfile.TemporaryDirectory() as folder:
            rec = read_plan_mcap(write_plan_mcap(first.result, Path(folder) / "start.mcap"))
    robot = recorded_robot(rec, scene) if scene.robot is not None else None  # as `walk`
    sim = Simulation.build(rec, scene, cfg, robot, model_error)
    model, data, gains = sim.model, sim.data, sim.gains
    h = model.opt.timestep
    joint_names = angle_names(scene)
    names = [c.name for c in scene.contacts]
    threshold = TOUCH_SHARE * sim.weight()
    slides = Slides(names, threshold, np.asarray(first.ref.normal, float))
    pace, place, stop = cfg["clock"], cfg["placement"], cfg["stop"]
    period = first.gait_duration  # s, the gait's half cycle
    gait_speed = first.step_length / period

    def segment(followed: Followed, begin: float, kind: str) -> _Segment:
        clock = PlanClock(pace["pace_gain"], pace["rate_min"], pace["rate_max"])
        clock.offset = -begin
        control = ReferenceController(model, sim.wm, followed.ref, gains, place["max_shift"],
                                      1.0, clock)
        return _Segment(followed, clock, control,
                        Touches(followed.ref.times, followed.ref.active, names, threshold),
                        kind, followed.strikes if kind != "stop" else np.array([]))

    seg = segment(first, 0.0, "start")
    sim.place(seg.plan.ref)
    along = walking_direction(seg.plan.ref)
    touches: list[dict[str, Any]] = []
    fbs, efforts, parts = [], [], []
    pending: tuple[float, float, Followed, str] | None = None  # (switch at, begin, plan)
    busy_until = 0.0  # simulated time at which the solver is free again
    walked, next_strike, standing_since = 0, 0, None
    followed = 0  # the plans the walker has followed before the current one
    stop_late = False  # the last stop failed or came late (a re-plan comes first)
    stop_strike = 0  # the strike the pending stop takes over at
    reason = "completed"
    while True:
        ref = seg.plan.ref
        step = sim.step(seg.control, seg.clock, ref, seg.touches, slides)
        fbs.append(step.fb)
        efforts.append(step.plan_effort)
        parts.append("standing" if standing_since is not None else seg.kind)
        seg.clock.pace(h, float(along @ (data.subtree_com[seg.control.root]
                                         - ref.com_at(step.tau))), gait_speed)
        reason = stop_reason(stop, data, step.com[2], step.phi_ref[2], step.tilt, step.error,
                             joint_names, step.time)
        if reason != "completed":
            break
        t, tau = data.time, seg.clock(data.time)
        if pending is not None and t >= pending[0]:
            touches += [dict(x, plan=followed) for x in seg.touches.summary()]
            seg, followed = segment(pending[2], pending[1], pending[3]), followed + 1
            # the strikes the new plan had before it took over are the old plan's
            pending, next_strike = None, int(np.sum(seg.strikes <= seg.clock(t) + 0.5 * h))
            plans[-1]["took_over_s"] = float(t)
            if seg.kind == "stop":  # at its strike, whichever step saw it first
                walked = max(walked, stop_strike)
            continue
        if seg.kind == "stop" and tau >= ref.times[-1]:
            standing_since = t if standing_since is None else standing_since
            if t - standing_since >= stand:
                break
            continue
        if tau > ref.times[-1]:
            reason = f"the plan ran out at t = {t:.3f} s (no new plan took over in time)"
            break
        strikes = seg.strikes
        if next_strike < len(strikes) and tau >= strikes[next_strike] - 0.5 * h:
            next_strike += 1
            walked += 1
            say(f"strike {walked} at t = {t:.3f} s")
            if walked > 2 * half_cycles + lead and seg.kind != "stop":
                reason = (f"no stop arrived in time in the {walked - half_cycles - 1} half "
                          f"cycles walked past the {half_cycles} asked")
                break
            if pending is not None or t < busy_until or seg.kind == "stop":
                continue  # a plan is being solved, or the walker stops
            ahead = min(lead, len(strikes) - next_strike) - 1
            if walked >= half_cycles - lead and ahead >= 0 and not (stop_late and replan):
                # the stop, from the plan's state at a strike ahead, taking over there
                n = int(np.searchsorted(ref.times, strikes[next_strike + ahead] - 0.5 * h))
                at = t + float(ref.times[n]) - tau
                start = start_of_node(scene, seg.plan.q, seg.plan.times,
                                      seg.plan.generalized_force, n,
                                      f"the plan at its strike at t = {at:.3f} s")
                r = timed("stop", start, at, stop=True, halves=STOP_HALVES, steps=1,
                          source=(seg.plan, n))
                busy_until = t + plans[-1]["wall_s"]
                # failed or late: a re-plan next (the walk goes on), then the stop again
                stop_late = r is None or busy_until > at + 0.5 * h
                if r is not None and stop_late:
                    plans[-1].update(dropped=True, message=f"arrived {busy_until - at:.3f} s "
                                     "after its strike: dropped")
                if not stop_late:
                    pending = (at, at, r, "stop")
                    stop_strike = walked + ahead + 1  # the strike it takes over at
                continue
            if not replan or (standing and seg.kind == "start" and next_strike == 1):
                continue  # one plan / the end of the start phases
            stop_late = False
            state = measure(sim, scene)
            start = measured_start(scene, state, f"the walker at t = {t:.3f} s")
            r = timed("re-plan", start, t, deadline * period, state, steps=carried,
                      halves=HALVES)
            busy_until = t + plans[-1]["wall_s"]
            if r is not None:
                pending = (busy_until, t, r, "walk")
    touches += [dict(x, plan=followed) for x in seg.touches.summary()]
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
        "replan_iterations_median": (float(np.median(counted)) if (counted := [
            p["iterations"] for p in replans if p["iterations"] is not None]) else None),
        "plans": plans, "unplanned_touches": touches, "foot_slide": slides.summary(),
        "charged": "each plan took over after its solve's wall time on this machine",
        **sim.model_error_summary(),
    }
