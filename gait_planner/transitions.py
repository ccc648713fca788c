"""Planning a transition: from a given start state onto the request's periodic gait
(`ocp.transition`, docs/design.md section 16), then as many of the gait's half cycles as the
request's steps ask, as one motion, certified against the continuous dynamics like every
plan; or, with `stop`, to standing at rest.

The gait is planned (or found in the planner's store) first, with `strategies.
plan_certified`, and kept by the planner for its next transitions (`gait_to_join`); the
transition is then solved on the gait's grid, starting from the gait itself (its inner
nodes, torques and phase durations; the start at node 0 and the gait's next half cycle at
nodes N-1 and N: from the gait's own first state, `start_of_plan`, that is the optimum) or,
re-planning, from a kept transition of the same shape with its multipliers: one that
began at the same state if there is one (warm, `REPEATED_ATTEMPT`), else the newest. A
start on the other foot is planned as its mirror image; a state of a recording is
`start_of_recording`'s.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.angles import blended, configuration
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.guess import initial_multipliers
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solution import failed_result
from gait_planner.ocp.solve import Clock, Planner, Start
from gait_planner.ocp.warm_starts import StoredPlan
from gait_planner.ocp.transcription import TORQUE_SCALE, Transcription
from gait_planner.ocp.transition import (StartError, StartState, check_start, end_intervals,
                                         ground_repeat, join, join_targets, mirrored_result,
                                         mirrored_start, stance_offset, start_of_plan,
                                         transition_scene, transition_settings, translated,
                                         translated_result)
from gait_planner.ocp.walk_on import walk_on
from gait_planner.result import PlanResult
from gait_planner.strategies import COLD_ATTEMPTS, plan_certified

VARIANTS = ("cold", "cold_inertia", "warm")  # the IPOPT instances a transition may use
# A transition's first attempt, from the gait or from the last transition: IPOPT's cold
# variant without its relaxed stage. Its bound push and adaptive barrier beat the warm
# variant's (built for a previous optimum's active set) here: walker3d, two half cycles,
# from the gait (no multipliers) from its own first node and a start 1.3 cm and 0.1 rad/s
# off, 21 and 23 iterations against 279 and 162; re-planned from the last transition with
# its multipliers, 5 seeded starts, median 16 against 22 (2026-12-07, benchmarks/HISTORY.md).
FIRST_ATTEMPT = ([("cold", False, False)],)
# ... except from a last transition that began where this one does (moved along x; the
# same configuration to SAME_START m): then IPOPT's warm variant, which keeps that
# optimum's active set. A walk's stop starts at a strike of its plan's gait, the state the
# prepared stop began at: walker2d's stop from it took 8 iterations cold, 1 warm; from the
# same foot's strike a half cycle later, after two other stops, 634 cold and 18 warm
# (2026-12-07, benchmarks/HISTORY.md). Measured states never repeat a start. The gait
# repeats itself mirrored to its solver's tolerance: walker3d's first node and its next
# half cycle's mirrored back differ by 1.4e-7 m (a stop from it took 11 iterations cold).
REPEATED_ATTEMPT = ([("warm", False, False)],)
SAME_START = 1e-6
SAME_MOMENTUM = 1e-3  # N s: a body of 10 kg 0.1 mm/s apart
GAITS_KEPT = 16  # the gaits a planner keeps for transitions (`gait_to_join`): those used last
MAX_HALVES = 4  # half cycles a transition may take
# Half cycles by default: walker3d from starts 1.3-1.4 cm and 0.1 rad/s off its first node
# needed 2 (in one: 2021-4621 iterations, J 40-43 against 21, the certificate missed or the
# efforts zigzag; in two: 22-24 iterations, every check passed; benchmarks/HISTORY.md,
# 2026-12-07).
HALVES = 2
# Half cycles of a stop by default: walker2d's stop in two did not converge (benchmarks/
# HISTORY.md, 2026-12-07), in one it did once.
STOP_HALVES = 1


# A start from standing joined after two half cycles or more makes its first step this
# share of the gait's step shorter (the stance foot of the gait's copies is placed that much
# further back): its stance foot stays where it stands through the first half cycle, so the
# targets fix how far it travels; with the gait's full first step walker2d found no plan
# from standing in 3400 iterations (the phases' durations at their upper bounds, the
# friction cones violated by 1.2 kN); half a step shorter, walker3d's converged from the
# warm-start store's gait (302 iterations) but not from the same gait planned cold (2706,
# the time limit) nor, later, from the store's (3800); 0.3 of a step shorter (a first step
# 0.7 of the gait's) from the gait planned cold in 130 iterations (walker2d 94, was 123)
# and from the store's in 65, every check passed (benchmarks/HISTORY.md, 2026-12-07).
# People begin to walk with a shorter step too.
FIRST_STEP = 0.3


def transition_start(tr: Transcription, gait: PlanResult, walked: PlanResult,
                     start: StartState, offset: float, end_scaling: float,
                     halves: int = 1) -> Start:
    """The transition's first iterate: every node at its reference (u = 0), the references
    the start, blended into the gait's first node through a standing start's phases
    (`transition_scene`; `model.angles.blended`, eased), then the gait walked on
    (`walked`, `ocp.walk_on`) moved `offset` m along x at the inner nodes up to N-2, and
    the targets (`join_targets`); a stop has none: its nodes blend from where its phases
    begin into the scene's standing pose, with its first stop phase's first contact point
    where the walk has it (`standing_guess_node`), at its last phase (at rest); that walk's node
    torques (held at node 0's through the start phases), the gait's phase scalings for
    each half cycle, the upper bound for the start and stop phases; the contact
    multipliers of `ocp.guess.initial_multipliers`."""
    N, settings, scene = tr.N, tr.settings, tr.mb.scene
    S, P = end_intervals(settings, scene, start.standing, tr.layout.rest)
    inner = translated(gait.scene, walked.q[: N - 1 - S], offset, 0.0)
    lead = [blended(scene, start.q, inner[0], _ease(n / S)) for n in range(S)]
    inner = np.vstack(lead + list(inner))[1 : N - 1]
    extra = tr.mb.scene.gait.n_scalings - halves * gait.scene.gait.n_scalings
    sigma = np.concatenate([np.tile(gait.phase_scaling, halves),
                            np.full(extra, settings.scaling_bounds[1])])
    if tr.layout.rest:
        rest = N - settings.intervals[-1]  # where the last stop phase (at rest) begins
        stand = standing_guess_node(tr, inner[N - P - 1])
        inner = np.array([blended(scene, q, stand, _ease((n + 1) / rest))
                          for n, q in enumerate(inner)])
        qref = np.vstack([start.q, inner])
    else:
        qref = np.vstack([start.q, inner, join_targets(gait, offset, halves)])
    torques = np.vstack([np.repeat(walked.tau[:1], S, axis=0), walked.tau[: N - S]])
    x = np.concatenate([np.zeros(tr.U.numel()), torques.ravel() / TORQUE_SCALE,
                        initial_multipliers(tr), sigma, [end_scaling]])
    zeros_g = np.zeros(int(tr.g.shape[0]))
    return Start(x, np.zeros_like(x), zeros_g, qref, f"a transition from {start.origin}")


def _ease(s: float) -> float:
    """A smooth step from 0 to 1 over s in [0, 1], level at both ends: 3 s^2 - 2 s^3."""
    s = min(max(s, 0.0), 1.0)
    return s * s * (3.0 - 2.0 * s)


def standing_guess_node(tr: Transcription, q: np.ndarray) -> np.ndarray:
    """(k,): the scene's standing pose moved in x and y so that the first contact point
    of the stop's first phase is where configuration q (k,) has it: a stop's guess at
    rest."""
    scene, mb = tr.mb.scene, tr.mb
    first = next(p for p in scene.gait.phases if p.name == scene.gait.stop[0].name)
    contact = scene.contact(first.contacts[0])
    point = mb.point_matrix(contact.body, contact.point)
    pose = configuration(scene)
    move = (point @ q - point @ pose) * np.array([1.0, 1.0, 0.0])
    return pose + np.tile(np.concatenate([move, np.zeros(9)]), mb.nb)


def last_transition(tr: Transcription, last: StoredPlan, start: StartState, offset: float,
                    gait: PlanResult, halves: int) -> Start:
    """A re-plan's first iterate: the last transition's optimum with its multipliers, its
    inner references moved along x as far as the new start is from the last one, the new
    start and targets at the ends."""
    N = tr.N
    shift = _shift(tr, last, start, gait)
    ends = [] if tr.layout.rest else [join_targets(gait, offset, halves)]
    qref = np.vstack([start.q, translated(gait.scene, last.qref[1 : N - 1], shift, 0.0), *ends])
    return Start(last.x, last.lam_x, last.lam_g, qref,
                 f"a transition from {start.origin}, re-planned from the last transition")


def repeats(tr: Transcription, last: StoredPlan, start: StartState, gait: PlanResult
            ) -> bool:
    """Whether `start` begins where the kept transition `last` began, moved along x (its
    configuration within `SAME_START` m of last's first reference moved by their stance
    offsets' difference, as `last_transition` moves it, and its momentum within
    `SAME_MOMENTUM` of last's)."""
    moved = translated(gait.scene, last.qref[0], _shift(tr, last, start, gait), 0.0)
    return (last.momentum.shape == start.momentum.shape
            and float(np.abs(start.q - moved).max()) <= SAME_START
            and float(np.abs(start.momentum - last.momentum).max()) <= SAME_MOMENTUM)


def _shift(tr: Transcription, last: StoredPlan, start: StartState, gait: PlanResult
           ) -> float:
    """How far (m) along x `start` is from where the kept transition `last` began."""
    scene = tr.mb.scene
    return stance_offset(scene, start.q, gait) - stance_offset(scene, last.qref[0], gait)


def gait_to_join(planner: Planner, scene: Scene, settings: GaitSettings,
                 warm_start: bool = True) -> PlanResult:
    """The certified periodic gait of (scene, settings) (`strategies.plan_certified`), kept
    in `planner.gaits` (the `GAITS_KEPT` used last) for the planner's next transitions onto
    it whatever their time limits: the same request's gait is planned once (re-solved from
    its stored optimum and certified again at every re-plan, it took 0.13 s of walker3d's
    0.96 s, 2026-12-07). warm_start False plans it again from its guess and keeps
    nothing."""
    if not warm_start:
        return plan_certified(planner, scene, settings, warm_start=False)[0]
    key = (scene.name, scene.source, settings.with_solve(max_solve_time=1.0))
    gait = planner.gaits.pop(key, None)
    if gait is None:
        gait, _ = plan_certified(planner, scene, settings)
        if not gait.success:
            return gait
    planner.gaits[key] = gait  # the newest last
    while len(planner.gaits) > GAITS_KEPT:
        del planner.gaits[next(iter(planner.gaits))]
    return gait


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
    transition of this shape that began at this start (kept by this process or, in the
    warm-start store, by another: `gait-planner prepare` plans the scene's start from
    standing and its stop), else from its newest (`last_transition`), else from the gait.
    A standing start (`ocp.transition.standing_start`) begins with the scene's start
    phases (gait.start: both feet flat, then the first heel off); on stairs it carries the
    stairs with the gait it joins (settings.stairs_shift: the robot stands as far from the
    first edge as that gait, joined `FIRST_STEP` of a step back, has them). A start treads up
    the stairs or along a ramp is planned moved back onto the gait's first tread and its
    answer moved forward again (`ocp.transition.ground_repeat`). stop: the transition
    ends with the scene's stop phases (gait.stop), the last standing at rest, instead of
    joining the gait; steps are not walked then; without a start it begins at the gait's
    first node.
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
    gait = gait_to_join(planner, scene, settings, warm_start)
    if not gait.success:
        return dataclasses.replace(gait, message=f"the gait to join: {gait.message}")
    start = start_of_plan(gait) if start is None else start
    dx, dz = ground_repeat(scene, start.q, gait)  # planned on the gait's first tread
    start = dataclasses.replace(start, q=translated(scene, start.q, -dx, -dz))
    walked = walk_on(gait, halves + max(steps, 1))  # the guess, the references, the answer
    tr_settings = transition_settings(settings, gait, walked, start, halves, stop)
    tr_scene = transition_scene(scene, halves, start.standing, stop)
    offset = stance_offset(scene, start.q, gait) - (
        FIRST_STEP * gait.step_length if start.standing and halves > 1 else 0.0)
    if start.standing:  # the stairs stand where the gait joined that far back has them
        tr_settings = dataclasses.replace(tr_settings, stairs_shift=offset)
    planner.stage("building the transition")
    try:
        tr = planner.build(tr_scene, tr_settings, VARIANTS, refinement=True)
    except (ValueError, RuntimeError) as err:
        return failed_result(scene, tr_settings, f"could not build the transition: {err}")
    first = transition_start(tr, gait, walked, start, offset, tr_settings.end_scaling,
                             halves)
    kept = planner.stored_plans(tr_scene, tr_settings) if from_last else []
    same = [plan for plan in kept if repeats(tr, plan, start, gait)]
    last = (same or kept)[-1] if kept else None  # one that began here, else the newest
    begin = first if last is None else last_transition(tr, last, start, offset, gait, halves)
    repeated = bool(same)
    clock = Clock.begin(settings.solve.max_solve_time)
    attempts = (REPEATED_ATTEMPT if repeated else FIRST_ATTEMPT) + COLD_ATTEMPTS
    reached = planner.attempt(tr_scene, tr_settings, attempts[0], begin, clock)
    origin = begin.origin + (" (warm: it began at this start)" if repeated else "")
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
        joined = join(result, walked, offset, halves,
                      end_intervals(tr_settings, scene, start.standing, stop)[0])
    joined = translated_result(joined, dx, dz)
    joined, cert = certified(mirrored_result(joined) if mirrored else joined)
    standing = {"transition_standing": "true"} if start.standing else {}
    return dataclasses.replace(joined, settings={
        **joined.settings, **certificate_metadata(cert), **standing,
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
    return start_of_node(scene, rec.q, times, rec.generalized_force, n,
                         f"{path} at {times[n]:.4g} s (node {n})")


def start_of_node(scene: Scene, q: np.ndarray, times: np.ndarray, generalized_force,
                  n: int, origin: str) -> StartState:
    """The state of node n (0 <= n < N) of a plan or recording of `scene` (q (N+1, k),
    times (N+1,) s, its published discrete forces (N+1, k) N s) with the discrete momentum
    its own equations give it (`start_of_recording`)."""
    q, h = np.asarray(q, float), np.diff(np.asarray(times, float))
    mb = Multibody.of(scene)
    if n == 0:
        momentum = mb.mass_diagonal * (q[1] - q[0]) / h[0]
    else:
        share = h[n - 1] / (h[n - 1] + h[n])
        momentum = (np.array(DiscreteMechanics(mb).discrete_lagrangian_d2(
            q[n - 1], q[n], h[n - 1])).ravel() + share * np.asarray(generalized_force[n]))
    return StartState(q[n].copy(), momentum, origin)
