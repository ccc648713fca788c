"""Solving the gait NLP with IPOPT from an explicit start, with progress, a time limit and
a store of optima.

`Planner` caches one built transcription + IPOPT instances per (scene, shape of the
settings: `ocp.transcription.shape_of`, the time limit aside) and the optima it found: a
request of another step length, friction coefficient, slope, stair height or speed is a new
value of the problem's parameters, never a new build or compilation. With a
`WarmStartStore` it also reads the optima of earlier processes and adds its own
(`ocp.warm_starts`). It decides nothing: `Planner.attempt` runs one attempt (a list of
IPOPT stages) from the `Start` it is given, within the request's `Clock`, and
`Planner.result` makes the plan of what the attempt reached. Which start, which attempts,
and what to do when one fails (the continuation, the stairs-down start, the restart with
IPOPT's inertia test, the grid refinement, the free-step search, a gait library's seed) is
`gait_planner.strategies`.
"""

from __future__ import annotations

import dataclasses
import gc
import time
from typing import Callable

import casadi as ca
import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.memory import (PEAK_PER_KEPT, available_bytes, release_free_heap,
                                  resident_bytes)
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.compile import CompileError, compile_sources
from gait_planner.ocp.derivatives import expand_nlp, nlp_derivatives
from gait_planner.ocp.guess import GUESSES, guess_x
from gait_planner.ocp.ipopt import IterationCallback, Progress, Stop, ipopt_options, run_attempt
from gait_planner.ocp.warm_starts import WarmStartStore, StoredPlan
from gait_planner.ocp.settings import GaitSettings, ground_of
from gait_planner.ocp.solution import build_result
from gait_planner.ocp.transcription import Transcription, shape_of
from gait_planner.result import PlanResult

Stage = Callable[[str], None]  # the phase a plan enters ("building", "cold stage 1", ...)
STOPPED = "stopped on request"  # the message of a plan ended by `Planner.stop`
Attempt = list[tuple[str, bool, bool]]  # IPOPT stages: (variant, sigma fixed, limits relaxed)

# Inertia-free curvature test (Chiang & Zavala 2016; IPOPT recommends 1e-12 to 1e-11): a
# step is accepted when it has positive curvature, instead of regularising the Hessian
# until MUMPS reports the right inertia. Far from the optimum walker3d's reduced Hessian is
# strongly indefinite: with the inertia test it needed regularisations up to 1e6 and
# 200-330 cold iterations, with this 70-105 (benchmarks/HISTORY.md). walker2d cold solves
# with it took from 31 to over 1000 iterations, hence the fallback below.
INERTIA_FREE = {"ipopt.neg_curv_test_tol": 1e-12}
# Iterations the inertia-free attempt of a cold plan gets (per stage) before the plan
# restarts from the guess with IPOPT's inertia correction (walker3d's default: 57-87 in
# stage 1). With 150 the torque-squared cost (126 + 224 needed) and the 0.9 m step (302) fell
# back and took 942 iterations, 90 s (J 1106.6 instead of 1021.3), or did not converge in
# 120 s; with 400 they converge in 13 s each (2026-11-23).
FIRST_ATTEMPT_ITERATIONS = 400

# A warm re-plan's MUMPS runs without its scalings (IPOPT's defaults let MUMPS choose a
# permutation and scaling at every factorisation): the same iterations on nine re-plans of
# walker3d and of walker2d but for one far request (1.3 x step: 126 -> 134), 11-27 % less
# time (walker3d +2 %: 0.208 -> 0.152 s). Not for cold plans: in the first stage 18-20
# instead of 21-23 ms an iteration, but the ten requests of request_sweep.py took 1054
# iterations instead of 824, the same time in all; in the second stage only (which starts
# near an optimum, as a warm re-plan does) 6 % less time and the same iterations on 20 of
# 22 sweep requests (measured after a loosely solved first stage), but walker3d's
# torque-squared plan then missed the continuous-dynamics certificate after both
# refinements (0.278 %; 2026-11-25, benchmarks/HISTORY.md).
NEAR_OPTIMUM = {f"ipopt.mumps_{option}": 0 for option in ("permuting_scaling", "scaling")}
# A gait library's seed (`gaitlib.serve.library_start`: its neighbours' optima mixed) is
# near the request's optimum, so the barrier starts where it ends: fixed (monotone) at
# 1e-9 instead of IPOPT's adaptive choice, whose probing costs solves of the primal-dual
# system every iteration. walker3d in-library answers (libraries 5 cm apart, the cells'
# centres; 2026-11-29): 5 / 7 / 12 iterations in 152 / 204 / 301 ms adaptive, 5 / 7 / 8 in
# 117 / 164 / 216 ms with the barrier fixed, the same J to 1e-8 (benchmarks/HISTORY.md).
# Not for other warm starts, which may start far from the optimum. Capped at
# SEEDED_ITERATIONS: a seed that needs more is not near its optimum (walker3d on a 9.52 deg
# ramp from a library 2.5 deg and 5 cm apart: 996 iterations, then locally infeasible).
FIXED_BARRIER = {"ipopt.mu_strategy": "monotone", "ipopt.mu_init": 1e-9}
SEEDED_ITERATIONS = 100
# A step of a parameter path (`gait_planner.parameter_path`: the request's ground, pace,
# step and friction moved from a kept optimum towards the request's): the barrier fixed
# (monotone) from 1e-4, so that the optimum's active set can change (contact forces leave
# their cones' faces, clearances and sigma their bounds) where at 1e-9 a step that changes
# it stalled. walker3d, 2026-11-29 (benchmarks/HISTORY.md), 11 requests continued from the
# default plan in steps of 2.5 deg, 2.5 cm of stair, 5 cm of step, 0.1 m/s: from 1e-9
# (the seeded variant) 7 of 11 steps into a stair or a speed stopped at its cap of 100;
# from 1e-4 they took 20-90 iterations; 1e-4 with a loose tolerance in the steps before the
# last: fewer iterations on the way, more in the last step, 3 of 5 requests slower.
CONTINUED_BARRIER = {"ipopt.mu_strategy": "monotone", "ipopt.mu_init": 1e-4}
CONTINUED_ITERATIONS = 150
WARM = {**INERTIA_FREE, **{f"ipopt.warm_start_{push}": 1e-9
                           for push in ("bound_push", "mult_bound_push", "slack_bound_push")},
        **NEAR_OPTIMUM}
# IPOPT options of the solver variants beyond the common ones (`ipopt_options`)
VARIANTS = {
    "cold": {**INERTIA_FREE, "ipopt.max_iter": FIRST_ATTEMPT_ITERATIONS},
    "cold_inertia": {},
    "warm": WARM,
    "seeded": {**WARM, **FIXED_BARRIER, "ipopt.max_iter": SEEDED_ITERATIONS},
    "continued": {**WARM, **CONTINUED_BARRIER, "ipopt.max_iter": CONTINUED_ITERATIONS},
}
COLD_VARIANTS = ("cold", "cold_inertia")  # the rest start near an optimum


@dataclasses.dataclass(frozen=True)
class Start:
    """Where an attempt begins: the NLP's x (nx,) and its multipliers lam_x (nx,), lam_g
    (ng,), the reference configurations qref (N-1, k) of the reparametrisation (the
    problem's parameters take them: `Transcription.parameters`), and where it came from, in
    words (the result's settings["initial_guess"])."""

    x: np.ndarray
    lam_x: np.ndarray
    lam_g: np.ndarray
    qref: np.ndarray
    origin: str

    @classmethod
    def of(cls, plan: StoredPlan, origin: str) -> "Start":
        """The start at a stored optimum."""
        return cls(plan.x, plan.lam_x, plan.lam_g, plan.qref, origin)

    @property
    def duals(self) -> dict:
        """The multipliers as IPOPT's nlpsol takes them."""
        return {"lam_x0": self.lam_x, "lam_g0": self.lam_g}


@dataclasses.dataclass
class Clock:
    """One request's time limit and counts, shared by every attempt it makes: started and
    deadline (time.perf_counter s), IPOPT iterations and seconds spent evaluating, and the
    iteration the progress reports count from."""

    started: float
    deadline: float
    iterations: int = 0
    evaluation_time: float = 0.0
    reported: int = 0

    @classmethod
    def begin(cls, limit: float) -> "Clock":
        """A clock started now with `limit` seconds."""
        now = time.perf_counter()
        return cls(now, now + limit)

    def expired(self) -> bool:
        return time.perf_counter() > self.deadline


@dataclasses.dataclass(frozen=True)
class Reached:
    """What one attempt reached: x (nx,), g (ng,), multipliers {"lam_x0", "lam_g0"} to
    continue from, IPOPT's return status, success, and the parameters p and qref it was
    solved with."""

    x: np.ndarray
    g: np.ndarray
    duals: dict
    status: str
    success: bool
    p: np.ndarray
    qref: np.ndarray


@dataclasses.dataclass
class _Built:
    tr: Transcription
    nlp: dict
    bounds: tuple
    callback: IterationCallback
    derivatives: dict  # nlpsol options grad_f, jac_g, hess_lag (ocp.derivatives)
    derivatives_used: str  # how, in words (result.settings["derivatives"])
    build_time: float
    kept: int | None = None  # bytes its build and first IPOPT instances kept (`memory`)
    solvers: dict = dataclasses.field(default_factory=dict)  # variant -> IPOPT instance
    stored: list[StoredPlan] = dataclasses.field(default_factory=list)
    library_key: str | None = None  # its file in the warm-start store, if the planner has one
    first_p: np.ndarray | None = None  # the parameters of its instances' first calls


def _first_call(built: _Built, solver: ca.Function, s: GaitSettings) -> None:
    """Call a new IPOPT instance once, stopped at iteration 0 (its callback's deadline
    passed) from the kinematic guess of `s`, so that no plan pays its first call: an
    in-library answer of walker3d (5 iterations) took 206 ms as the instance's first call
    and 101-124 ms after, 106-109 ms as the first call after this one (which took 74 ms;
    2026-11-29). The instance keeps no state between calls: the plans after it are the
    same, bit for bit. The callback's deadline, listener, stop and count are restored after
    it: a variant first used within an attempt keeps the attempt's. The guess is solved
    once per problem (walker3d's start from standing: 0.4 s for each of its 3 instances)."""
    tr, (lbx, ubx, lbg, ubg) = built.tr, built.bounds
    if built.first_p is None:
        qref = GUESSES["kinematic"](tr, s.step_length, ground_of(tr.mb.scene, s))
        built.first_p = tr.parameters(qref[: tr.layout.free], s)
    cb = built.callback
    kept = cb.deadline, cb.report, cb.stop, cb.iteration  # an attempt may be under way
    cb.deadline, cb.report, cb.stop = -np.inf, None, None
    try:
        solver(x0=np.clip(guess_x(tr, s.scaling_bounds[1]), lbx, ubx),
               p=built.first_p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    finally:
        cb.deadline, cb.report, cb.stop, cb.iteration = kept


def _key(scene: Scene, s: GaitSettings):
    return scene.name, scene.source, shape_of(s).with_solve(max_solve_time=1.0)


def stored(settings: GaitSettings, reached: Reached) -> StoredPlan:
    """The optimum `reached` (with its multipliers) of the request `settings`, to keep."""
    return StoredPlan(settings.step_length, settings.friction_coefficient, reached.x,
                      reached.duals["lam_x0"], reached.duals["lam_g0"], reached.qref,
                      slope=settings.slope, step_height=settings.step_height,
                      speed=settings.speed, momentum=np.array(settings.start_momentum, float))


class Planner:
    """Builds gait problems, solves them from the starts it is given, and keeps their
    optima for warm starts.

    progress: called every IPOPT iteration; stage: called when a plan enters a phase;
    stop: polled every iteration and between phases: once it returns True the attempt ends
    within one iteration (the strategies then return a failed result of status
    `PlanStatus.STOPPED`, message `STOPPED`; a problem being built is finished first and
    kept for later plans); library: the plans of earlier processes (`ocp.warm_starts`),
    read when a problem is built and written after every optimum kept (None: this
    process's plans only); pin: the optima it keeps are pinned in the library (`gait-planner
    prepare`'s default plans and warm-start anchors, `StoredPlan.pinned`). gaits: the
    certified periodic gaits that transitions join, by request (`transitions.gait_to_join`)."""

    def __init__(self, *, progress: Progress | None = None, stage: Stage | None = None,
                 stop: Stop | None = None, library: WarmStartStore | None = None,
                 pin: bool = False):
        self.progress, self.stage, self.stop = progress, stage or (lambda name: None), stop
        self.library, self.pin = library, pin
        self._built: dict = {}
        self.gaits: dict = {}

    def stopped(self) -> bool:
        """Whether `stop` asks the plan to end."""
        return self.stop is not None and self.stop()

    def prepare(self, scene: Scene, settings: GaitSettings) -> str:
        """Build the problem of (scene, settings) now, compiling its derivative elements if
        the settings ask for it (cached on disk for later processes), and every IPOPT
        variant (a cold start, its fallback with the inertia test and a warm re-plan;
        walker3d: 0.7 s each), so that no plan spends time on them. Returns how the
        derivatives are evaluated, in words."""
        return self._built_with(scene, settings, tuple(VARIANTS)).derivatives_used

    def build(self, scene: Scene, settings: GaitSettings, variants=tuple(VARIANTS), *,
              refinement: bool = False) -> Transcription:
        """The transcription of (scene, settings), built on first use with the IPOPT
        instances of `variants` (keys of `VARIANTS`), so that no attempt's clock pays for
        them; refinement: it is a refined grid (`ocp.refine`), whose rest of the NLP is not
        compiled (`nlp_derivatives`): no request compiles what `gait-planner prepare` left
        out. ValueError or RuntimeError if it cannot be built."""
        return self._built_with(scene, settings, variants, refinement).tr

    def _built_with(self, scene: Scene, settings: GaitSettings, variants,
                    refinement: bool = False) -> _Built:
        new = _key(scene, settings) not in self._built
        if new:
            self._make_room()
        before = resident_bytes() if new else None
        built = self._build(scene, settings, refinement)
        for variant in variants:
            self._solver(built, settings, variant)
        after = resident_bytes() if before is not None else None
        if after is not None:
            built.kept = max(after - before, 0)
        return built

    def _make_room(self) -> None:
        """Before a new problem is built: `make_room` for the largest build this planner
        measured taken again (`memory.PEAK_PER_KEPT` times what it kept), so that a node
        serving one robot after another is not killed for memory (G1's problems held
        10.6 GB after its plan, 2026-12-07)."""
        kept = [built.kept for built in self._built.values() if built.kept]
        if kept:
            self.make_room(int(max(kept) * PEAK_PER_KEPT))

    def make_room(self, need: int) -> int | None:
        """Forget the problems used least recently (never the last one used, which a
        refinement starts from; the optima of a planner with a library stay in it) while
        the memory available is below `need` bytes. Returns the bytes available then (None:
        not known here)."""
        free = available_bytes()
        while free is not None and free < need and len(self._built) > 1:
            del self._built[next(iter(self._built))]
            gc.collect()
            release_free_heap()
            free = available_bytes()
        return free

    def room_for(self, need: int) -> int | None:
        """The bytes available for a build of `need` bytes (None: not known here), after
        `make_room` if forgetting the problems it may forget (what they kept when built;
        those not measured count nothing) would make the room; if it would not, none is
        forgotten."""
        free = available_bytes()
        spare = sum(built.kept or 0 for built in list(self._built.values())[:-1])
        if free is not None and free < need <= free + spare:
            free = self.make_room(need)
        return free

    def memory_kept(self, scene: Scene, settings: GaitSettings) -> int | None:
        """Bytes the problem of (scene, settings) kept when this planner built it with its
        IPOPT instances (None: not built here by `build`/`prepare`, or not measurable)."""
        built = self._built.get(_key(scene, settings))
        return None if built is None else built.kept

    def problem_size(self, scene: Scene, settings: GaitSettings) -> dict[str, int]:
        """Size of the NLP of (scene, settings), built if needed: intervals, variables,
        constraints, nonzeros of the constraint Jacobian and of the upper triangle of the
        Lagrangian's Hessian (the patterns IPOPT is given)."""
        built = self._build(scene, settings)
        rows, cols = built.derivatives["hess_lag"].sparsity_out(0).get_triplet()
        return {"intervals": int(built.tr.N), "variables": int(built.nlp["x"].numel()),
                "constraints": int(built.nlp["g"].numel()),
                "jacobian_nonzeros": int(built.derivatives["jac_g"].sparsity_out(1).nnz()),
                "hessian_nonzeros": int(np.sum(np.asarray(rows) <= np.asarray(cols)))}

    def _build(self, scene: Scene, s: GaitSettings, refinement: bool = False) -> _Built:
        """The problem of (scene, s), built on first use (`build`)."""
        key = _key(scene, s)
        if key not in self._built:
            start = time.perf_counter()
            tr = Transcription(DiscreteMechanics(Multibody(scene)), s)
            bounds = tr.bounds()
            # IPOPT's f and g are one SX graph; their derivatives come from `nlp_derivatives`.
            expanded = expand_nlp(tr)
            nlp = {"x": expanded.x, "p": expanded.p, "f": expanded.f, "g": expanded.g}
            derivatives, used = None, "CasADi, whole SX graph"
            if s.solve.compiled:  # a cache miss is announced, still as the building stage:
                # "building: compiling ... (how long)"
                def announce(text: str) -> None:
                    self.stage(f"building: {text}")

                try:
                    derivatives = nlp_derivatives(
                        tr, lambda sources: compile_sources(sources, notify=announce), expanded,
                        compile_rest=not refinement)
                    used = "per-node elements compiled to C"
                except CompileError as err:
                    used += f" (not compiled: {err})"
                    self.stage(f"building with CasADi's derivatives (not compiled: {err})")
            if derivatives is None:
                # CasADi differentiates the whole SX graph: in its virtual machine this beats
                # per-node elements (walker3d Hessian 26 ms against 49 ms), as each node's
                # reparametrisation is shared by all the rows that use it.
                reference = ca.nlpsol("gait_derivatives", "ipopt", nlp, {"print_time": False})
                derivatives = {name: reference.get_function(f"nlp_{name}")
                               for name in ("grad_f", "jac_g")}
                derivatives["hess_lag"] = reference.get_function("nlp_hess_l")
            nx, ng = int(tr.x.shape[0]), int(tr.g.shape[0])
            cb = IterationCallback(nx, ng, bounds[2], bounds[3])
            built = _Built(tr, nlp, bounds, cb, derivatives, used, time.perf_counter() - start)
            if self.library is not None:
                built.library_key = self.library.key(scene.source, key[2], nx, ng)
                built.stored = self.library.load(built.library_key, nx, ng)
            self._built[key] = built
        self._built[key] = self._built.pop(key)  # the last used last (`_make_room`)
        return self._built[key]

    def stored_plans(self, scene: Scene, settings: GaitSettings) -> list[StoredPlan]:
        """The optima kept for warm starts of the problem of (scene, settings), oldest
        first (building it if the planner has not yet)."""
        return list(self._build(scene, settings).stored)

    def all_plans(self, scene: Scene, settings: GaitSettings) -> list[StoredPlan]:
        """The optima kept of every problem of `scene` built so far on the grid of
        `settings` (so their x mean what its x means), whatever their ground or speed,
        oldest first per problem: the starts of `gait_planner.parameter_path`."""
        own = self._build(scene, settings).tr
        grid = (own.N, own.x.shape[0])
        return [plan for (name, source, _), built in self._built.items()
                if (name, source) == (scene.name, scene.source)
                and (built.tr.N, built.tr.x.shape[0]) == grid for plan in built.stored]

    def fits(self, scene: Scene, settings: GaitSettings, plan: StoredPlan) -> None:
        """ValueError unless `plan`'s sizes are those of the problem of (scene, settings)."""
        built = self._build(scene, settings)
        nx, ng = int(built.tr.x.shape[0]), int(built.tr.g.shape[0])
        if plan.x.shape != (nx,) or plan.lam_x.shape != (nx,) or plan.lam_g.shape != (ng,) \
                or plan.qref.shape != (built.tr.layout.free, built.tr.mb.k):
            raise ValueError(f"a plan of {plan.x.size} variables and {plan.lam_g.size} "
                             f"constraints cannot start a problem of {nx} and {ng}")

    def keep(self, scene: Scene, settings: GaitSettings, plan: StoredPlan) -> None:
        """Keep an optimum of (scene, settings) for warm starts, in the library too if the
        planner has one (a transition's only if the planner pins its plans: `gait-planner
        prepare`'s start from standing and stop, which later processes repeat; the others
        serve this process's next re-plans, its measured starts never repeat); the pinned
        plans another process added to the library's file since this one read it (a
        node's background preparation) are taken in first, so that saving does not drop
        them."""
        built = self._build(scene, settings)
        saved = (self.library is not None and built.library_key is not None
                 and (self.pin or not built.tr.transition))
        if saved:
            known = {p.request for p in built.stored}
            built.stored[:0] = [p for p in self.library.load(
                built.library_key, int(built.tr.x.shape[0]), int(built.tr.g.shape[0]))
                if p.pinned and p.request not in known]
        built.stored.append(dataclasses.replace(plan, pinned=True) if self.pin else plan)
        if saved:
            self.library.save(built.library_key, built.stored)

    def _solver(self, built: _Built, s: GaitSettings, variant: str = "cold") -> ca.Function:
        """The IPOPT instance `variant` of a problem, built on first use (under a second:
        the derivative Functions are built with the problem). All start from the
        multipliers they are given (zero for a cold start, the stored plan's for a warm
        start), warm_start_init_point; the adaptive mu strategy chooses the barrier
        (mu_init 0.01 for a cold plan, 1e-8 for a warm one: not one iteration changed,
        2026-11-23).
        * "warm" pushes the start 1e-9 (instead of 1e-3) inside the bounds, which keeps a
          previous optimum's active set: walker2d re-plans in 4 instead of 9 iterations (a
          cold start with it needs 126 instead of 77; measured with IPOPT's inertia test,
          before the inertia-free variants).
        * "seeded" is "warm" with the barrier fixed at 1e-9 (`FIXED_BARRIER`), for a gait
          library's seed.
        (A loose first stage, tol 1e-4 with σ fixed, was tried with the inertia test:
        walker3d then needed 249 iterations in all instead of 168.)
        """
        if variant not in built.solvers:
            start = time.perf_counter()
            opts = ipopt_options(built.callback, s)
            opts.update(VARIANTS[variant])
            opts["ipopt.max_iter"] = min(opts["ipopt.max_iter"], s.solve.max_iterations)
            opts.update(built.derivatives)
            solver = ca.nlpsol(f"gait_{variant}", "ipopt", built.nlp, opts)
            _first_call(built, solver, s)
            built.solvers[variant] = solver
            built.build_time += time.perf_counter() - start
        return built.solvers[variant]

    def attempt(self, scene: Scene, settings: GaitSettings, attempt: Attempt, start: Start,
                clock: Clock, *, inertia_test: bool = False) -> Reached:
        """One attempt (`ocp.ipopt.run_attempt`: its stages in turn, each from where the
        last ended) of the built problem of (scene, settings) from `start`, its parameters
        those of `settings` and start.qref, within `clock` (deadline; iterations and
        evaluation seconds added to it); each stage is reported (`Planner.stage`: "warm",
        or "cold stage k", with " (inertia test)" if inertia_test)."""
        built = self._build(scene, settings)
        cb = built.callback
        cb.started, cb.deadline, cb.iteration = clock.started, clock.deadline, clock.reported
        cb.report, cb.stop = self.progress, self.stopped

        def enter(k: int, variant: str) -> None:
            self.stage("warm" if variant not in COLD_VARIANTS else
                       f"cold stage {k + 1}" + (" (inertia test)" if inertia_test else ""))

        totals = [clock.iterations, clock.evaluation_time]
        p = built.tr.parameters(start.qref, settings)
        x, g, duals, status, success = run_attempt(
            lambda variant: self._solver(built, settings, variant), attempt, start.x,
            start.duals, p, built.bounds, slice(-int(built.tr.S.shape[0]), None),
            built.tr.relaxed_lower_bounds, totals, enter)
        clock.iterations, clock.evaluation_time = totals
        clock.reported = cb.iteration
        return Reached(x, g, duals, status, success, p, start.qref)

    def result(self, scene: Scene, settings: GaitSettings, reached: Reached, clock: Clock,
               origin: str) -> PlanResult:
        """The plan of request `settings` at what an attempt reached (`build_result`: its
        stats the clock's iterations, evaluation seconds and time since it started, the
        problem's build time); a converged one is kept for warm starts (`keep`)."""
        built = self._build(scene, settings)
        result = build_result(built.tr, settings, reached.x, reached.p, reached.g,
                              status=reached.status, iterations=clock.iterations,
                              solve_time=time.perf_counter() - clock.started,
                              build_time=built.build_time,
                              evaluation_time=clock.evaluation_time, origin=origin)
        result = dataclasses.replace(result, settings={
            **result.settings, "derivatives": built.derivatives_used})
        if result.success:
            self.keep(scene, settings, stored(settings, reached))
        return result
