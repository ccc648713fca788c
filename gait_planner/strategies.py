"""How a request is planned: which start, which attempts, and what is tried when one fails.

`ocp.solve.Planner` builds a problem and runs one attempt from the start it is given; the
decisions are here, each a function that calls it:

* `plan_once`: one plan of a request. Its start is a gait library's seed (`seed`, given by
  `gaitlib.serve.library_start`), the nearest optimum the planner keeps on the same ground
  at the same speed (warm), the coarser grid's plan a refinement starts from
  (`refine_from`), the stairs-down start (`stair_start`), or the guess (cold). A cold plan
  whose inertia-free attempt fails is continued from the scene's step length on level
  ground (`continuation`), else restarted with IPOPT's inertia test.
* `plan_certified`: `plan_once`, then the grid refined while the continuous-dynamics
  certificate (or zigzagging efforts) asks (`ocp.refine`).
* `plan_free_step`: a speed without a step length: the step of least cost per metre,
  searched by golden section over plans of one built problem.

Every plan of one request shares the request's time limit (`ocp.solve.Clock`); a plan
stopped on request (`Planner.stop`) is a failed result of status `PlanStatus.STOPPED`.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from gait_planner.memory import gigabytes
from gait_planner.model.scene import Scene
from gait_planner.ocp.guess import GUESSES, guess_x
from gait_planner.ocp.refine import refined_memory, refined_settings, refined_start
from gait_planner.ocp.settings import GaitSettings, free_step_range, ground_of
from gait_planner.ocp.solution import STATUS_WORDS, failed_result
from gait_planner.ocp.solve import STOPPED, Clock, Planner, Reached, Start, stored
from gait_planner.ocp.warm_starts import StoredPlan
from gait_planner import parameter_path
from gait_planner.result import PlanResult, PlanStatus

# Attempts, each a list of stages (variant, sigma fixed, limits relaxed): a cold plan fixes
# sigma and relaxes the swing clearance and joint speed limits first
# (`Transcription.relaxed_lower_bounds`), then frees both; if its inertia-free attempt
# fails it starts again with the inertia test. The first stage is solved to the full
# tolerances: it ends at an optimum that does not depend on round-off, so the second stage
# reaches the same local minimum with compiled and CasADi derivatives (test_ocp_reproducible;
# stopped early, by IPOPT's tol 1e-3 or near the first stage's optimum, the sweeps took up
# to 10 % fewer iterations but CasADi's derivatives ended at J 20.8088 instead of 20.7648;
# benchmarks/HISTORY.md).
COLD_ATTEMPTS = ([("cold", True, True), ("cold", False, False)],
                 [("cold_inertia", True, True), ("cold_inertia", False, False)])
WARM_ATTEMPTS = ([("warm", False, False)],)
# A gait library's seed: the barrier fixed near zero (`ocp.solve.FIXED_BARRIER`, at most
# `SEEDED_ITERATIONS`), and if that attempt fails, a warm one from the same start with
# IPOPT's adaptive barrier; if that fails too, the request is planned cold (`plan_once`).
SEEDED_ATTEMPTS = ([("seeded", False, False)], WARM_ATTEMPTS[0])
# A refinement (a plan started from a coarser plan of the same request) gets no restart with
# the inertia test: the coarse plan stands if the refined grid fails. Measured 2026-11-26
# (walker3d, 1.0 m step, 600 s limit): the 40-interval plan missed the certificate (0.27 %),
# its refinement's inertia-free attempt stopped at the cap after 24 s, and the restart with
# the inertia test (regularisation 1e5-1e7, MUMPS reallocating) slowed from 0.1 s to over a
# minute an iteration, so the request ended at 617 s, past its limit, with the coarse plan.
# It starts with the barrier fixed from 1e-4 (`ocp.solve.VARIANTS["continued"]`), then, if
# that fails, from the same start as a cold plan's first attempt: walker3d's refinements to
# 80 intervals of four requests that missed their certificate or zigzagged on 40 took 167 /
# 247 / 347 / 448 iterations (9.5 / 6.2 / 13.8 / 14.7 s) cold, 114 / 220 / 176 / 337 (6.0
# / 4.9 / 7.0 / 11.5 s) this way, each plan passing the same checks (2026-11-29).
REFINE_ATTEMPTS = ([("continued", False, False)], COLD_ATTEMPTS[0])
# What the first attempt of a sequence whose failure the next retries from the same start
# (no continuation, no inertia test) is called, and what follows, in words
_RETRIED = {"seeded": ("fixed-barrier", "restarted with IPOPT's adaptive barrier"),
            "continued": ("fixed-barrier", "restarted with sigma fixed and limits relaxed, "
                                           "then free")}
# Stairs down (m per step) a cold plan starts on from its kinematic guess; a deeper stair
# is planned on this depth first and continued from that plan (warm). walker2d,
# 2026-11-27: 0.10 m down converged cold in 388 iterations, 0.15 m down found no plan in
# 300 s (1089 iterations), and from the 0.10 m plan it converged in 129 more, every check
# passing. Not for stairs up, which converge cold: walker2d's 0.15 m up continued from
# 0.10 m missed the certificate (0.692 %, refined 0.279 %). The start is planned with the
# edge margin, not the segment rows (`gait_planner.model.ground.Ground.segment_rows`):
# with the rows, cold plans on 0.10 m down found no plan in 300-600 s (walker2d 1220-2280
# iterations, walker3d 646-776), with the margin they converge (388 and 349 iterations).
STAIR_COLD_MAX = 0.10
STEP_TOLERANCE = 0.005  # m: a free step length is found to within this


def variants(attempts) -> tuple[str, ...]:
    """The solver variants of `attempts` (lists of stages), each once, in order."""
    return tuple(dict.fromkeys(variant for attempt in attempts for variant, *_ in attempt))


def continuation_base(scene: Scene, s: GaitSettings) -> GaitSettings | None:
    """The request a failed cold plan of `s` is continued from (`continuation`): `s` at
    the scene's step length and, on a ramp, on level ground (one problem: the same shape);
    None if that is `s` itself."""
    base = dataclasses.replace(s, step_length=scene.gait.step_length,
                               slope=0.0 if s.step_height == 0 else s.slope)
    return None if base == s else base


def _ground_words(slope: float, step_height: float) -> str:
    return (f"a {slope:g} deg ramp" if slope else
            f"{step_height:g} m stairs" if step_height else "level ground")


def described_plan(plan: StoredPlan) -> str:
    """A kept plan's request, in words."""
    pace = f" at {plan.speed:g} m/s" if plan.speed else ""
    return (f"step length {plan.step:.4f} m, mu {plan.mu:.3g} on "
            f"{_ground_words(plan.slope, plan.step_height)}{pace}")


def described(s: GaitSettings) -> str:
    """A request's step length and ground, in words."""
    return f"step length {s.step_length:.4f} m on {_ground_words(s.slope, s.step_height)}"


def guess_start(planner: Planner, scene: Scene, settings: GaitSettings, guess: str,
                origin: str) -> Start:
    """A cold start of the request `settings`: the reference configurations of the guess
    `guess` (a key of `ocp.guess.GUESSES`), zero torques and node multipliers, the scaled
    contact multipliers (`initial_multipliers`) and sigma at its upper bound, multipliers
    of the bounds and constraints zero."""
    tr = planner.build(scene, settings, ())
    qref = GUESSES[guess](tr, settings.step_length, ground_of(scene, settings))[: tr.N - 1]
    # sigma starts (fixed) at its upper bound, where every measured optimum of the
    # kinetic-energy cost puts it: the free stage then moves little, and the local
    # minimum reached depends less on round-off. walker3d's default request with
    # numpy's Haswell, Zen, SkylakeX, Prescott kernels (compiled) and CasADi
    # derivatives: J 20.7683, 20.7683, 20.7801, 20.7801, 20.7801 (0.06 % apart);
    # from sigma = 1: 20.7801, 20.7801, 20.8470, 20.8936, 20.7644 (0.6 %)
    x = guess_x(tr, settings.scaling_bounds[1])
    return Start(x, np.zeros(x.size), np.zeros(int(tr.g.shape[0])), qref, origin)


def refined_from(planner: Planner, scene: Scene, coarse: GaitSettings, fine: GaitSettings
                 ) -> Start:
    """The start of `fine` refined (`ocp.refine.refined_start`) from the planner's plan of
    the same request on the coarse grid of `coarse`, multipliers zero; ValueError if there
    is none."""
    plans = [r for r in planner.stored_plans(scene, coarse)
             if (r.step, r.mu) == (fine.step_length, fine.friction_coefficient) and r.on(coarse)]
    if not plans:
        raise ValueError(f"no plan of step length {fine.step_length} m, mu "
                         f"{fine.friction_coefficient} on the coarse grid to refine")
    coarse_tr, fine_tr = planner.build(scene, coarse, ()), planner.build(scene, fine, ())
    x, qref = refined_start(coarse_tr, plans[-1], fine_tr, coarse)
    return Start(x, np.zeros(x.size), np.zeros(int(fine_tr.g.shape[0])), qref,
                 f"refined from the plan on {coarse_tr.N} intervals to {fine_tr.N}, the "
                 "barrier fixed from 1e-4")


def stair_start(planner: Planner, scene: Scene, settings: GaitSettings, guess: str,
                clock: Clock) -> tuple[Start | None, PlanResult]:
    """The start of a cold plan on stairs down: the same request on stairs at most
    `STAIR_COLD_MAX` deep with the edge margin and midpoint rows instead of the segment
    rows, and the scene's own scaling bounds (not `stairs_down_scaling_bounds`), planned
    by `plan_once` (warm from a plan of that problem the planner keeps, else cold from
    `guess`; its problem is kept for later plans) within what is left of the request's
    `clock`. Returns (the start at its optimum, its
    multipliers of g zero: the segment rows are not its rows; its result), or (None, a
    failed result of `settings` saying so) if it failed."""
    lower = dataclasses.replace(
        settings, step_height=max(settings.step_height, -STAIR_COLD_MAX),
        stair_segment_rows=False, scaling_bounds=tuple(scene.gait.scaling_bounds)
    ).with_solve(max_solve_time=max(clock.deadline - time.perf_counter(), 1e-3))
    result = plan_once(planner, scene, lower, warm_start=True, guess=guess)
    if not result.success:
        return None, failed_result(
            scene, settings, f"the plan on stairs of {lower.step_height:g} m with the edge "
            f"margin that a {settings.step_height:g} m stair starts from failed: "
            f"{result.message}")
    seed = planner.stored_plans(scene, lower)[-1]
    ng = int(planner.build(scene, settings, ()).g.shape[0])
    origin = (f"the plan on stairs of {lower.step_height:g} m with the edge margin "
              f"({result.settings['initial_guess']}; {result.stats.iterations} iterations); "
              f"continued to {settings.step_height:g} m with the segment rows (warm)")
    return Start(seed.x, seed.lam_x, np.zeros(ng), seed.qref, origin), result


def continuation(planner: Planner, scene: Scene, settings: GaitSettings, base: GaitSettings,
                 start: Start, guess: str, clock: Clock) -> Reached | None:
    """A cold plan of request `settings` that failed from its own guess, continued from
    `base` (`continuation_base`: the scene's step length, on level ground if `settings`
    asks for a ramp): plan `base` cold from `start`'s x with its own guess's reference
    configurations, then re-plan `settings` warm from that optimum (the continuation is one
    jump; the same problem, other parameters).
    walker3d on a 10 deg ramp, 2026-11-28: from its own guess the inertia-free attempt
    stopped at the iteration cap and the inertia test reached the 600 s limit (877
    iterations); from the level plan 470 warm iterations, 9.6 s, J 21.7118 (the plan the
    ground's constants had reached cold in 123). walker3d
    at 1.1 m (scene: 0.6338 m): its inertia-free attempt stops at the iteration cap,
    the continuation then converges (746 iterations in all, 22 s; 2026-11-24; 1.0 m
    needed it too before the contact rows were elements, and now converges from its
    own guess in 231).
    At 0.9 m, before the cap was raised to 400: from its own guess no convergence
    within 120 s, this way 64 + 146 iterations (in five steps of 0.05 m 64 + 127).
    Returns what the warm attempt reached, or None if an attempt failed. The plan of
    `base` is kept for warm starts."""
    tr = planner.build(scene, settings, ())
    qref = GUESSES[guess](tr, base.step_length, ground_of(scene, base))[: tr.N - 1]
    cold = planner.attempt(scene, base, COLD_ATTEMPTS[0], dataclasses.replace(start, qref=qref),
                           clock)
    if not cold.success or clock.expired():
        return None
    kept = stored(base, cold)
    planner.keep(scene, base, kept)
    warm = planner.attempt(scene, settings, WARM_ATTEMPTS[0], Start.of(kept, ""), clock)
    return warm if warm.success else None


def plan_once(planner: Planner, scene: Scene, settings: GaitSettings, *,
              warm_start: bool = True, guess: str = "kinematic",
              refine_from: GaitSettings | None = None, seed: StoredPlan | None = None
              ) -> PlanResult:
    """Solve one half cycle; a numerical failure is a result with a reason.

    A cold start begins at `guess`, a key of `ocp.guess.GUESSES`: the kinematic
    stepping motion, or (for robustness tests) the standing pose or a perturbed guess.
    warm_start: start from the nearest optimum the planner keeps of this problem on the
    request's ground at its speed (`StoredPlan.on`), or from `seed` (a gait library's
    interpolated start, `gaitlib.serve.library_start`, which checks its sizes), whichever
    is nearer in step length and friction coefficient; from the seed with the barrier
    fixed (`SEEDED_ATTEMPTS`).
    refine_from: settings whose grid `settings` refines (`ocp.refine`); without a
    stored plan of its own to warm-start from, the plan then starts from the planner's
    plan of the same request on that coarser grid (ValueError if there is none), and a
    failed inertia-free attempt is not restarted with the inertia test (`REFINE_ATTEMPTS`).

    The time limit (settings.solve.max_solve_time, `Clock`) covers the guess, the stairs-down
    start and the solve; building a problem the planner has not seen before comes on top
    (stats.build_time).
    """
    planner.stage("building")
    if guess not in GUESSES:
        raise ValueError(f"unknown guess {guess!r}; known: {', '.join(GUESSES)}")
    try:
        planner.build(scene, settings, (), refinement=refine_from is not None)
        candidates = [r for r in planner.stored_plans(scene, settings) if r.on(settings)]
        candidates += [] if seed is None else [seed]
        path = (parameter_path.nearest(planner, scene, settings)
                if warm_start and seed is None and refine_from is None else None)
        if path is not None and path[2] <= 1.0 and path[0].on(settings):
            path = None  # near enough to re-plan warm
        elif path is not None:
            candidates = []  # continued along the path; planned as below if that fails
        warm_start = warm_start and bool(candidates)
        stairs_first = (not warm_start and refine_from is None
                        and settings.step_height < 0 and settings.stair_segment_rows)
        nearest = (min(candidates, key=lambda r: abs(r.step - settings.step_length)
                       + abs(r.mu - settings.friction_coefficient)) if warm_start else None)
        attempts = (SEEDED_ATTEMPTS if warm_start and nearest is seed
                    else WARM_ATTEMPTS if warm_start or stairs_first
                    else REFINE_ATTEMPTS if refine_from is not None else COLD_ATTEMPTS)
        # every solver the plan may use, its fallbacks' and a continuation's (warm)
        # included, before the clock starts
        planner.build(scene, settings, variants(
            attempts + WARM_ATTEMPTS + (COLD_ATTEMPTS if attempts is SEEDED_ATTEMPTS else ())
            + (([("continued", False, False)],) if path is not None else ())),
            refinement=refine_from is not None)
    except (ValueError, RuntimeError) as err:
        return failed_result(scene, settings, f"could not build the problem: {err}")
    if planner.stopped():
        return failed_result(scene, settings, STOPPED, PlanStatus.STOPPED)
    clock = Clock.begin(settings.solve.max_solve_time)
    before = ""
    if path is not None:
        planner.stage("continuing along a parameter path")
        plan, point, _ = path
        reached, steps = parameter_path.follow(planner, scene, settings, plan, point, clock)
        before = (f"continued from the plan for {described_plan(plan)} ({plan.source}) in "
                  f"{steps} steps along a parameter path")
        if reached is not None:
            return planner.result(scene, settings, reached, clock, before)
        if planner.stopped():
            return failed_result(scene, settings, STOPPED, PlanStatus.STOPPED)
        # planned as if there had been no plan to start from, in the time left (none left:
        # IPOPT stops at its first iteration, and the result says why with its words)
        before += f" (failed after {clock.iterations} iterations); then "
    if not warm_start and refine_from is not None:
        start = refined_from(planner, scene, refine_from, settings)
    elif stairs_first:
        start, lower = stair_start(planner, scene, settings, guess, clock)
        if start is None:
            return (failed_result(scene, settings, STOPPED, PlanStatus.STOPPED)
                    if planner.stopped() else lower)
        clock.iterations += lower.stats.iterations
        clock.evaluation_time += lower.stats.evaluation_time
        start = dataclasses.replace(start, origin=before + start.origin)
    elif warm_start:
        start = Start.of(nearest, f"warm start from the plan for step length "
                                  f"{nearest.step:.4f} m, mu {nearest.mu:.3g} ({nearest.source})")
    else:
        planner.stage("initial guess")
        start = guess_start(planner, scene, settings, guess, f"{before}{guess} guess; sigma "
                            "fixed at its upper bound and limits relaxed, then free")
    reached, origin = _attempts(planner, scene, settings, attempts, start, guess, clock)
    if attempts is SEEDED_ATTEMPTS and not (reached.success or planner.stopped()
                                            or clock.expired()):
        planner.stage("initial guess")
        cold = guess_start(planner, scene, settings, guess, f"; then cold from the {guess} "
                           "guess, sigma fixed at its upper bound and limits relaxed, then free")
        reached, more = _attempts(planner, scene, settings, COLD_ATTEMPTS, cold, guess, clock)
        origin += more
    if planner.stopped():
        return failed_result(scene, settings, STOPPED, PlanStatus.STOPPED)
    return planner.result(scene, settings, reached, clock, origin)


def _attempts(planner: Planner, scene: Scene, settings: GaitSettings, attempts, start: Start,
              guess: str, clock: Clock) -> tuple[Reached, str]:
    """`attempts` in turn from `start` until one succeeds, the request's time is up or the
    plan is stopped; after a failed inertia-free attempt of a cold plan the `continuation`
    is tried before the restart with the inertia test. Returns what was reached last and
    the start's origin with what happened, in words. A seeded or refined plan's first
    attempt is retried by the next (`_RETRIED`) without a continuation."""
    origin = start.origin
    retried = _RETRIED.get(attempts[0][0][0])
    for number, attempt in enumerate(attempts):
        reached = planner.attempt(scene, settings, attempt, start, clock,
                                  inertia_test=number > 0 and retried is None)
        if reached.success or planner.stopped() or clock.expired() \
                or number + 1 == len(attempts):
            break
        origin += (f"; the {retried[0] if retried else 'inertia-free'} attempt stopped "
                   f"({STATUS_WORDS.get(reached.status, reached.status)}) after "
                   f"{clock.iterations} iterations")
        if retried:
            origin += f", {retried[1]}"
            continue
        base = continuation_base(scene, settings)
        if number == 0 and base is not None:
            found = continuation(planner, scene, settings, base, start, guess, clock)
            if found is not None:
                return found, (f"{origin}; continued from {described(base)} (cold) to "
                               f"{described(settings)} (warm)")
            if planner.stopped() or clock.expired():
                break
            origin += f"; the continuation from {described(base)} failed"
        origin += ", restarted with IPOPT's inertia test"
    return reached, origin


def plan_certified(planner: Planner, scene: Scene, settings: GaitSettings, *,
                   warm_start: bool = True, guess: str = "kinematic",
                   seed: StoredPlan | None = None):
    """`plan_once`, then, while the latest converged plan has defects of its grid (it
    misses the continuous-dynamics certificate, or its efforts zigzag: `grid_defects`) and
    `settings.refinements` allow and the machine has the memory to build it
    (`_no_room_for`), the same request on a grid twice as fine from that plan
    (`ocp.refine`). Of the converged plans the one with the fewest defects (then the
    smallest torque error) is returned: a refinement may cure the certificate and still
    zigzag (walker3d on 3 intervals per phase: on 6 the certificate is 0.221 % and the
    knee's effort zigzags, on 12 every check passes). All plans share
    settings.solve.max_solve_time. Returns (result, certificate; None if the plan failed); after
    a refinement the result's stats count every plan's iterations and time, and its
    settings["refinement"] says what was refined and why."""
    from gait_planner.verify.certify import certified, grid_defects  # Pinocchio: on first use

    start = time.perf_counter()
    result = plan_once(planner, scene, settings, warm_start=warm_start, guess=guess, seed=seed)
    if not result.success:
        return result, None
    result, cert = certified(result)
    best = latest = (result, cert, grid_defects(result, cert))
    coarse, notes, runs = settings, [], [result.stats]
    for _ in range(settings.refinements):
        defects = latest[2]
        if not defects:
            break
        left = settings.solve.max_solve_time - (time.perf_counter() - start)
        fine = refined_settings(coarse).with_solve(max_solve_time=max(left, 1e-3))
        why = (f"the plan on {sum(coarse.intervals)} intervals "
               f"({latest[0].settings['initial_guess']}): {'; '.join(defects)}")
        if left <= 0:
            notes.append(f"{why}; no time left to refine")
            break
        room = _no_room_for(planner, scene, coarse, fine)
        if room:
            notes.append(f"{why}; not refined to {sum(fine.intervals)}: {room}")
            break
        planner.stage(f"refining the grid to {sum(fine.intervals)} intervals")
        refined = plan_once(planner, scene, fine, warm_start=warm_start, refine_from=coarse)
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


def _no_room_for(planner: Planner, scene: Scene, coarse: GaitSettings,
                 fine: GaitSettings) -> str:
    """Why the refined grid `fine` of `coarse` is not built: its build would take more
    memory than the machine has available (`ocp.refine.refined_memory`; G1 refined a
    second time needed about 17 GB), so that the process is not killed for it, even after
    the planner forgot the other problems it keeps (`Planner.room_for`: only if that
    would make the room); "" if it fits, is built already, or either amount is unknown."""
    kept = planner.memory_kept(scene, coarse)
    if kept is None or planner.memory_kept(scene, fine) is not None:
        return ""
    need = refined_memory(kept)
    free = planner.room_for(need)
    if free is None or need <= free:
        return ""
    return (f"its problem would take about {gigabytes(need)} to build and "
            f"{gigabytes(free)} is available")


def plan_free_step(planner: Planner, scene: Scene, settings: GaitSettings, *,
                   warm_start: bool = True, seed: StoredPlan | None = None):
    """The plan at settings.speed whose step length, within `ocp.settings.free_step_range`,
    has the least cost per metre walked (J / step length): people choose the step of
    least cost at a speed, and J over one half cycle alone would favour the shortest
    steps. Golden-section search over the step length to `STEP_TOLERANCE` (each trial a
    plan of the same built problem, warm-started from the last: the step length is a
    parameter; `seed` a start every trial may take), then `plan_certified` at the best
    step. Returns (result, certificate) as `plan_certified`, its stats counting every
    trial's iterations and solve time; its settings["step_length_search"] says what was
    tried."""
    low, high = free_step_range(settings)
    tried: dict[float, float] = {}
    spent = [0, 0.0]  # the trials' iterations and solve time
    start = time.perf_counter()

    def cost_per_metre(step: float) -> float:
        trial = plan_once(planner, scene, dataclasses.replace(settings, step_length=step),
                          warm_start=warm_start or bool(tried), seed=seed)
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
                                  warm_start=True, seed=seed)
    result = dataclasses.replace(result, stats=dataclasses.replace(
        result.stats, iterations=result.stats.iterations + spent[0],
        solve_time=result.stats.solve_time + spent[1]))
    search = (f"step length free at {settings.speed:g} m/s within [{low:.4f}, {high:.4f}] m: "
              f"{len(tried)} plans in {time.perf_counter() - start:.1f} s, least J per metre "
              f"at {best:.4f} m; J/m tried: "
              + ", ".join(f"{s:.4f} m: {j:.4f}" for s, j in sorted(tried.items())))
    return dataclasses.replace(result, settings={**result.settings,
                                                 "step_length_search": search}), cert
