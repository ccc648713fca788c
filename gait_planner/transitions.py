"""Planning a transition: from a given start state onto the request's periodic gait
(`ocp.transition`, docs/design.md section 16), then as many of the gait's half cycles as the
request's steps ask, as one motion, certified against the continuous dynamics like every
plan; or, with `stop`, to standing at rest.

The gait is planned (or found in the planner's store) first, with `strategies.
plan_certified`; the transition is then solved on the gait's grid, starting from the gait
itself (its inner nodes, torques and phase durations; the start at node 0 and the gait's
next half cycle at nodes N-1 and N: from the gait's own first state, `start_of_plan`, that
is the optimum) or, re-planning, from the planner's last transition of the same shape with
its multipliers. A start on the other foot is planned as its mirror image; a state of a
recording is `start_of_recording`'s.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.guess import initial_multipliers
from gait_planner.ocp.mirror import mirror_parts
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solution import failed_result
from gait_planner.ocp.solve import Clock, Planner, Start
from gait_planner.ocp.warm_starts import StoredPlan
from gait_planner.ocp.transcription import TORQUE_SCALE, Transcription
from gait_planner.ocp.transition import (StartError, StartState, check_start, join,
                                         join_targets, mirrored_result, mirrored_start,
                                         stance_offset, start_of_plan, transition_scene,
                                         transition_settings)
from gait_planner.ocp.walk_on import walk_on
from gait_planner.result import PlanResult
from gait_planner.strategies import COLD_ATTEMPTS, plan_certified

VARIANTS = ("cold", "cold_inertia")  # the IPOPT instances a transition may use
# A transition's first attempt, from the gait or from the last transition: IPOPT's cold
# variant without its relaxed stage. Its bound push and adaptive barrier beat the warm
# variant's (built for a previous optimum's active set) here: walker3d, two half cycles,
# from the gait (no multipliers) from its own first node and a start 1.3 cm and 0.1 rad/s
# off, 21 and 23 iterations against 279 and 162; re-planned from the last transition with
# its multipliers, 5 seeded starts, median 16 against 22 (2026-12-07, benchmarks/HISTORY.md).
FIRST_ATTEMPT = ([("cold", False, False)],)
MAX_HALVES = 4  # half cycles a transition may take
# Half cycles by default: walker3d from starts 1.3-1.4 cm and 0.1 rad/s off its first node
# needed 2 (in one: 2021-4621 iterations, J 40-43 against 21, the certificate missed or the
# efforts zigzag; in two: 22-24 iterations, every check passed; benchmarks/HISTORY.md,
# 2026-12-07).
HALVES = 2
# Half cycles of a stop by default: walker2d's stop in two did not converge (benchmarks/
# HISTORY.md, 2026-12-07), in one it did once.
STOP_HALVES = 1


def transition_start(tr: Transcription, gait: PlanResult, walked: PlanResult,
                     start: StartState, offset: float, end_scaling: float,
                     halves: int = 1) -> Start:
    """The transition's first iterate: every node at its reference (u = 0), the references
    the start, the gait walked on (`walked`, `ocp.walk_on`) at the inner nodes
    1..N-2 moved `offset` m along x, and the targets (`join_targets`; a stop has none: its
    nodes from where it stands on are the walk's node there); that walk's node torques and
    the gait's phase scalings for each half cycle (a stop's STAND phase: the upper bound);
    the contact multipliers of `ocp.guess.initial_multipliers`."""
    N = tr.N
    along = mirror_parts(tr.mb)[1]
    inner = walked.q[1 : N - 1] + offset * along
    sigma = np.tile(gait.phase_scaling, halves)
    if tr.layout.rest:
        stand = N - tr.settings.intervals[-1]
        inner[stand - 1 :] = inner[stand - 1]
        qref = np.vstack([start.q, inner])
        sigma = np.append(sigma, tr.settings.scaling_bounds[1])
    else:
        qref = np.vstack([start.q, inner, join_targets(gait, offset, halves)])
    x = np.concatenate([np.zeros(tr.U.numel()), walked.tau[:N].ravel() / TORQUE_SCALE,
                        initial_multipliers(tr), sigma, [end_scaling]])
    zeros_g = np.zeros(int(tr.g.shape[0]))
    return Start(x, np.zeros_like(x), zeros_g, qref, f"a transition from {start.origin}")


def last_transition(tr: Transcription, last: StoredPlan, start: StartState, offset: float,
                    gait: PlanResult, halves: int) -> Start:
    """A re-plan's first iterate: the last transition's optimum with its multipliers, its
    inner references moved along x as far as the new start is from the last one, the new
    start and targets at the ends."""
    N = tr.N
    along = mirror_parts(tr.mb)[1]
    shift = offset - stance_offset(tr.mb.scene, last.qref[0], gait)
    ends = [] if tr.layout.rest else [join_targets(gait, offset, halves)]
    qref = np.vstack([start.q, last.qref[1 : N - 1] + shift * along, *ends])
    return Start(last.x, last.lam_x, last.lam_g, qref,
                 f"a transition from {start.origin}, re-planned from the last transition")


def plan_transition(planner: Planner, scene: Scene, settings: GaitSettings,
                    start: StartState | None, *, steps: int = 1, warm_start: bool = True,
                    halves: int | None = None, from_last: bool = True, stop: bool = False
                    ) -> PlanResult:
    """The transition of `halves` half cycles (1 to MAX_HALVES; None: HALVES, a stop
    STOP_HALVES) from `start` onto the gait
    of (scene, settings), followed by `steps` of the gait's half cycles, certified (module
    docstring). A start the first phase cannot hold but its mirror image can (on the
    other foot: every other strike of a walk) is planned mirrored and the answer mirrored
    back (`mirrored_start`, `mirrored_result`). warm_start: the gait from the planner's
    store (`strategies.plan_certified`); from_last: the transition from the planner's last
    transition of this shape if it has one (`last_transition`), else from the gait.
    stop: the transition ends standing at rest, both feet flat (`ocp.transition.STAND`),
    instead of joining the gait; steps are not walked then; without a start it begins at
    the gait's first node.
    `ocp.transition.StartError` if the start cannot be planned from; a failed plan (of the
    gait or the transition) has success False and says which in its message."""
    halves = (STOP_HALVES if stop else HALVES) if halves is None else halves
    if not 1 <= halves <= MAX_HALVES:
        raise StartError(f"a transition takes 1 to {MAX_HALVES} half cycles, got {halves}")
    from gait_planner.verify.certify import certificate_metadata, certified

    if start is None and not stop:
        raise StartError("a transition onto the gait needs a start state")
    mirrored = False
    try:
        if start is not None:
            check_start(scene, settings, start)
    except StartError as err:  # on the other foot? planned as its mirror image
        start, mirrored = mirrored_start(scene, start), True
        try:
            check_start(scene, settings, start)
        except StartError:
            raise err from None
    gait, _ = plan_certified(planner, scene, settings, warm_start=warm_start)
    if not gait.success:
        return dataclasses.replace(gait, message=f"the gait to join: {gait.message}")
    start = start_of_plan(gait) if start is None else start
    walked = walk_on(gait, halves + max(steps, 1))  # the guess, the references, the answer
    tr_settings = transition_settings(settings, gait, walked, start, halves, stop)
    tr_scene = transition_scene(scene, halves, stop)
    offset = stance_offset(scene, start.q, gait)
    planner.stage("building the transition")
    try:
        tr = planner.build(tr_scene, tr_settings, VARIANTS, refinement=True)
    except (ValueError, RuntimeError) as err:
        return failed_result(scene, tr_settings, f"could not build the transition: {err}")
    first = transition_start(tr, gait, walked, start, offset, tr_settings.end_scaling,
                             halves)
    kept = planner.stored_plans(tr_scene, tr_settings) if from_last else []
    begin = last_transition(tr, kept[-1], start, offset, gait, halves) if kept else first
    clock = Clock.begin(settings.solve.max_solve_time)
    # A stop's guess is not near its optimum (it stands where the gait walks on): the cold
    # attempts, relaxed first; a transition: FIRST_ATTEMPT, then those.
    attempts = (() if stop and not kept else FIRST_ATTEMPT) + COLD_ATTEMPTS
    reached = planner.attempt(tr_scene, tr_settings, attempts[0], begin, clock)
    origin = begin.origin
    for attempt in attempts[1:] if not reached.success else ():
        if planner.stopped() or clock.expired():
            break
        origin += f"; the {attempt[0][0]} attempt follows ({reached.status})"
        reached = planner.attempt(tr_scene, tr_settings, attempt, first, clock)
        if reached.success:
            break
    result = planner.result(tr_scene, tr_settings, reached, clock, origin)
    if not result.success:
        return dataclasses.replace(result, scene=scene)
    if stop:
        joined = dataclasses.replace(result, scene=scene, settings={
            **result.settings, "transition_half_cycles": str(halves), "transition_stop": "true"})
    else:
        joined = join(result, walked, offset, halves)
    joined, cert = certified(mirrored_result(joined) if mirrored else joined)
    return dataclasses.replace(joined, settings={
        **joined.settings, **certificate_metadata(cert),
        "gait_cost_value": repr(gait.cost_value), "gait_duration": repr(gait.duration)})


def start_of_recording(scene: Scene, path: str, time: float | None = None) -> StartState:
    """The state of the recording `path` (an MCAP of this product: a plan's, a
    transition's) at `time` s from its start (None: its first node): the last node at or
    before it, with the discrete momentum the recording's own equations give it,
    p-_n = D2 L_d(q_{n-1}, q_n, h_{n-1}) + f+_{n-1}, f+_{n-1} the share h_{n-1} / (h_{n-1} +
    h_n) of the published discrete force of node n (at node 0: M (q_1 - q_0) / h_0).
    StartError if the recording is of another robot or the time outside it."""
    from gait_planner.io.mcap_reader import read_plan_mcap

    try:
        rec = read_plan_mcap(path)
    except (OSError, ValueError) as err:
        raise StartError(f"cannot read the start's recording {path}: {err}") from None
    names = tuple(b.name for b in scene.bodies)
    if tuple(rec.body_names) != names:
        raise StartError(f"the recording {path} is of bodies {', '.join(rec.body_names)}, "
                         f"not {scene.name}'s ({', '.join(names)})")
    times = np.asarray(rec.times, float)
    t = float(times[0]) if time is None else float(time)
    if not times[0] <= t <= times[-1]:
        raise StartError(f"time {t:g} s is outside the recording {path} "
                         f"({times[0]:g} to {times[-1]:g} s)")
    n = min(int(np.searchsorted(times, t, side="right")) - 1, len(times) - 2)
    q, h = np.asarray(rec.q, float), np.diff(times)
    mb = Multibody(scene)
    if n == 0:
        momentum = mb.mass_diagonal * (q[1] - q[0]) / h[0]
    else:
        share = h[n - 1] / (h[n - 1] + h[n])
        momentum = (np.array(DiscreteMechanics(mb).discrete_lagrangian_d2(
            q[n - 1], q[n], h[n - 1])).ravel() + share * np.asarray(rec.generalized_force[n]))
    return StartState(q[n].copy(), momentum, f"{path} at {times[n]:.4g} s (node {n})")
