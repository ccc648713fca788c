"""Solving the gait NLP with IPOPT, with progress, a time limit and warm starts.

`Planner` caches one built transcription + solvers per (scene, shape of the settings:
`ocp.transcription.shape_of`, the time limit aside) and the plans it found: a request of
another step length, friction coefficient, slope, stair height or speed is a new value of
the problem's parameters, never a new build or compilation. A changed step length or
friction coefficient re-plans from the nearest stored plan on the same ground at the same
speed (primal and dual warm start), a new ground or speed cold; with a `WarmStartStore` it also
starts from, and adds to, the plans of earlier processes (`ocp.warm_starts`). A cold plan that
fails from its guess at a step length other than the scene's, or on a ramp, is continued
from the scene's step length on level ground (`Planner._continuation`); a cold plan on
stairs down starts from the plan on stairs at most `STAIR_COLD_MAX` deep
whose segments are kept above the edges by the edge margin instead of the segment rows
(`Planner._stair_start`).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Callable

import casadi as ca
import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.compile import CompileError, compile_sources
from gait_planner.ocp.derivatives import expand_nlp, nlp_derivatives
from gait_planner.ocp.guess import GUESSES, initial_multipliers
from gait_planner.ocp.ipopt import IterationCallback, Progress, Stop, ipopt_options, run_attempt
from gait_planner.ocp.warm_starts import WarmStartStore, StoredPlan
from gait_planner.ocp.refine import refined_start
from gait_planner.ocp.settings import GaitSettings, ground_of
from gait_planner.ocp.solution import STATUS_WORDS, build_result, failed_result
from gait_planner.ocp.transcription import Transcription, shape_of
from gait_planner.result import PlanResult, PlanStatus

Stage = Callable[[str], None]  # the phase a plan enters ("building", "cold stage 1", ...)
STOPPED = "stopped on request"  # the message of a plan ended by `Planner.stop`

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
# IPOPT options of the solver variants beyond the common ones (`ipopt_options`)
VARIANTS = {
    "cold": {**INERTIA_FREE, "ipopt.max_iter": FIRST_ATTEMPT_ITERATIONS},
    "cold_inertia": {},
    "warm": {**INERTIA_FREE, **{f"ipopt.warm_start_{push}": 1e-9
                                for push in ("bound_push", "mult_bound_push", "slack_bound_push")},
             **NEAR_OPTIMUM},
}
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
# A refinement (a plan started from a coarser plan of the same request) gets no restart with
# the inertia test: the coarse plan stands if the refined grid fails. Measured 2026-11-26
# (walker3d, 1.0 m step, 600 s limit): the 40-interval plan missed the certificate (0.27 %),
# its refinement's inertia-free attempt stopped at the cap after 24 s, and the restart with
# the inertia test (regularisation 1e5-1e7, MUMPS reallocating) slowed from 0.1 s to over a
# minute an iteration, so the request ended at 617 s, past its limit, with the coarse plan.
REFINE_ATTEMPTS = COLD_ATTEMPTS[:1]
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


def _variants(attempts) -> list[str]:
    """The solver variants of `attempts` (lists of stages), each once, in order."""
    return list(dict.fromkeys(variant for attempt in attempts for variant, *_ in attempt))


@dataclasses.dataclass
class _Built:
    tr: Transcription
    nlp: dict
    bounds: tuple
    callback: IterationCallback
    derivatives: dict  # nlpsol options grad_f, jac_g, hess_lag (ocp.derivatives)
    derivatives_used: str  # how, in words (result.settings["derivatives"])
    build_time: float
    solvers: dict = dataclasses.field(default_factory=dict)  # variant -> IPOPT instance
    stored: list[StoredPlan] = dataclasses.field(default_factory=list)
    library_key: str | None = None  # its file in the plan library, if the planner has one


def _key(scene: Scene, s: GaitSettings):
    return scene.name, scene.source, dataclasses.replace(shape_of(s), max_solve_time=1.0)


def _continuation_base(scene: Scene, s: GaitSettings) -> GaitSettings | None:
    """The request a failed cold plan of `s` is continued from (`Planner._continuation`):
    `s` at the scene's step length and, on a ramp, on level ground (one problem: the same
    shape); None if that is `s` itself."""
    base = dataclasses.replace(s, step_length=scene.gait.step_length,
                               slope=0.0 if s.step_height == 0 else s.slope)
    return None if base == s else base


def _described(s: GaitSettings) -> str:
    """A request's step length and ground, in words."""
    ground = (f"a {s.slope:g} deg ramp" if s.slope else
              f"{s.step_height:g} m stairs" if s.step_height else "level ground")
    return f"step length {s.step_length:.4f} m on {ground}"


def _stored(settings: GaitSettings, x: np.ndarray, duals: dict, qref: np.ndarray
            ) -> StoredPlan:
    """The optimum x (with its multipliers) of the request `settings`, to keep."""
    return StoredPlan(settings.step_length, settings.friction_coefficient, x, duals["lam_x0"], duals["lam_g0"],
                      qref, slope=settings.slope, step_height=settings.step_height,
                      speed=settings.speed)


class Planner:
    """Plans gaits; keeps built problems and previous plans for warm starts.

    progress: called every IPOPT iteration; stage: called when a plan enters a phase;
    stop: polled every iteration and between phases: once it returns True the plan ends
    within one iteration as a failed result of status `PlanStatus.STOPPED` (message `STOPPED`) (a problem being
    built is finished first and kept for later plans); library: the plans of earlier
    processes (`ocp.warm_starts`), read when a problem is built and written after every
    successful plan (None: this process's plans only)."""

    def __init__(self, *, progress: Progress | None = None, stage: Stage | None = None,
                 stop: Stop | None = None, library: WarmStartStore | None = None):
        self.progress, self.stage, self.stop = progress, stage or (lambda name: None), stop
        self.library = library
        self._built: dict = {}

    def prepare(self, scene: Scene, settings: GaitSettings) -> str:
        """Build the problem of (scene, settings) now, compiling its derivative elements if
        the settings ask for it (cached on disk for later processes), and the IPOPT
        instances of a cold start, its fallback with the inertia test and a warm re-plan
        (walker3d: 0.7 s each), so that no plan spends time on them. Returns how the derivatives are evaluated, in words."""
        built = self._build(scene, settings)
        for variant in _variants(COLD_ATTEMPTS + WARM_ATTEMPTS):
            self._solver(built, settings, variant)
        return built.derivatives_used

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
        """The problem of (scene, s), built on first use; refinement: it is a refined grid
        (`ocp.refine`), whose rest of the NLP is not compiled (`nlp_derivatives`): no
        request compiles what `gait-planner prepare` left out."""
        key = _key(scene, s)
        if key not in self._built:
            start = time.perf_counter()
            tr = Transcription(DiscreteMechanics(Multibody(scene)), s)
            bounds = tr.bounds()
            # IPOPT's f and g are one SX graph; their derivatives come from `nlp_derivatives`.
            expanded = expand_nlp(tr)
            nlp = {"x": expanded.x, "p": expanded.p, "f": expanded.f, "g": expanded.g}
            derivatives, used = None, "CasADi, whole SX graph"
            if s.compiled:  # a cache miss is announced, still as the building stage:
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
        return self._built[key]

    def stored_plans(self, scene: Scene, settings: GaitSettings) -> list[StoredPlan]:
        """The optima kept for warm starts of the problem of (scene, settings), oldest
        first (building it if the planner has not yet)."""
        return list(self._build(scene, settings).stored)

    def remember(self, scene: Scene, settings: GaitSettings, plan: StoredPlan) -> None:
        """Keep `plan` (an optimum of this problem or of a neighbouring one of the same
        size) as the newest start of warm plans of (scene, settings), on their ground and
        at their speed (`StoredPlan.on`); ValueError if its sizes are not this problem's."""
        built = self._build(scene, settings)
        nx, ng = int(built.tr.x.shape[0]), int(built.tr.g.shape[0])
        if plan.x.shape != (nx,) or plan.lam_x.shape != (nx,) or plan.lam_g.shape != (ng,) \
                or plan.qref.shape != (built.tr.N - 1, built.tr.mb.k):
            raise ValueError(f"a plan of {plan.x.size} variables and {plan.lam_g.size} "
                             f"constraints cannot start a problem of {nx} and {ng}")
        built.stored.append(dataclasses.replace(plan, slope=settings.slope,
                                                step_height=settings.step_height,
                                                speed=settings.speed))

    def _store(self, built: _Built, plan: StoredPlan) -> None:
        """Keep an optimum for warm starts, in the library too if the planner has one."""
        built.stored.append(plan)
        if self.library is not None and built.library_key is not None:
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
        (A loose first stage, tol 1e-4 with σ fixed, was tried with the inertia test:
        walker3d then needed 249 iterations in all instead of 168.)
        """
        if variant not in built.solvers:
            start = time.perf_counter()
            opts = ipopt_options(built.callback, s)
            opts.update(VARIANTS[variant])
            opts["ipopt.max_iter"] = min(opts["ipopt.max_iter"], s.max_iterations)
            opts.update(built.derivatives)
            built.solvers[variant] = ca.nlpsol(f"gait_{variant}", "ipopt", built.nlp, opts)
            built.build_time += time.perf_counter() - start
        return built.solvers[variant]

    def _attempt(self, built: _Built, s: GaitSettings, attempt, number: int,
                 x0: np.ndarray, duals: dict, p: np.ndarray, totals: list):
        """`run_attempt` on a built problem, reporting each stage (`Planner.stage`)."""
        def enter(k: int, variant: str) -> None:
            self.stage("warm" if variant == "warm" else
                       f"cold stage {k + 1}" + (" (inertia test)" if number else ""))

        return run_attempt(lambda variant: self._solver(built, s, variant), attempt, x0, duals,
                           p, built.bounds, slice(-int(built.tr.S.shape[0]), None),
                           built.tr.relaxed_lower_bounds, totals, enter)

    def _refined_start(self, scene: Scene, coarse_settings: GaitSettings, built: _Built,
                       step: float, mu: float):
        """(x, qref, origin in words) refined (`ocp.refine.refined_start`) from the stored
        plan of (step, mu) on the coarse grid of `coarse_settings`."""
        coarse = self._built.get(_key(scene, coarse_settings))
        plans = [r for r in (coarse.stored if coarse else [])
                 if (r.step, r.mu) == (step, mu) and r.on(coarse_settings)]
        if not plans:
            raise ValueError(f"no plan of step length {step} m, mu {mu} on the coarse grid "
                             "to refine")
        x, qref = refined_start(coarse.tr, plans[-1], built.tr, coarse_settings)
        return x, qref, (f"refined from the plan on {coarse.tr.N} intervals to {built.tr.N}; "
                         "sigma fixed and limits relaxed, then free")

    def _continuation(self, built: _Built, s: GaitSettings, base: GaitSettings,
                      x_start: np.ndarray, duals_start: dict, qref: np.ndarray, totals: list):
        """A cold plan of request `s` that failed from its own guess, continued from `base`
        (`_continuation_base`: the scene's step length, on level ground if `s` asks for a
        ramp): plan `base` cold from its guess (qref), then re-plan `s` warm from that
        optimum (the continuation is one jump; the same problem, other parameters).
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
        Returns (x, g, duals, status, success, p) of the warm stage, or None if a stage
        failed. The scene's plan is kept for warm starts."""
        p0 = built.tr.parameters(qref, base)
        x0, _, duals, _, success = self._attempt(built, s, COLD_ATTEMPTS[0], 0, x_start,
                                                 duals_start, p0, totals)
        if not success or time.perf_counter() > built.callback.deadline:
            return None
        self._store(built, _stored(base, x0, duals, qref))
        p = built.tr.parameters(qref, s)
        x, g, duals, status, success = self._attempt(built, s, WARM_ATTEMPTS[0], 0, x0, duals,
                                                     p, totals)
        return (x, g, duals, status, success, p) if success else None

    def _stair_start(self, scene: Scene, settings: GaitSettings, guess: str, ng: int
                     ) -> tuple[StoredPlan | None, PlanResult]:
        """The start of a cold plan on stairs down: the same request on stairs at most
        `STAIR_COLD_MAX` deep with the edge margin and midpoint rows instead of the segment
        rows, and the scene's own scaling bounds (not `stairs_down_scaling_bounds`), planned
        warm from a plan of that problem this planner keeps, else cold from `guess` (its
        problem is kept for later plans). Returns (its stored plan, its multipliers of g
        zeroed to the ng rows of `settings`' problem: the segment rows are not its rows;
        its result), or (None, a failed result of `settings` saying so) if it failed."""
        lower = dataclasses.replace(
            settings, step_height=max(settings.step_height, -STAIR_COLD_MAX),
            stair_segment_rows=False, scaling_bounds=tuple(scene.gait.scaling_bounds))
        result = self.plan(scene, lower, warm_start=True, guess=guess)
        if not result.success:
            return None, failed_result(
                scene, settings, f"the plan on stairs of {lower.step_height:g} m with the edge "
                f"margin that a {settings.step_height:g} m stair starts from failed: "
                f"{result.message}")
        seed = self.stored_plans(scene, lower)[-1]
        return dataclasses.replace(seed, lam_g=np.zeros(ng)), result

    def plan(self, scene: Scene, settings: GaitSettings, *, warm_start: bool = True,
             guess: str = "kinematic", refine_from: GaitSettings | None = None) -> PlanResult:
        """Solve one half cycle; a numerical failure is a result with a reason.

        A cold start begins at `guess`, a key of `ocp.guess.GUESSES`: the kinematic
        stepping motion, or (for robustness tests) the standing pose or a perturbed guess.
        refine_from: settings whose grid `settings` refines (`ocp.refine`); without a
        stored plan of its own to warm-start from, the plan then starts from this planner's
        plan of the same request on that coarser grid (ValueError if there is none), and a
        failed inertia-free attempt is not restarted with the inertia test (`REFINE_ATTEMPTS`).

        The time limit (settings.max_solve_time) covers the guess and the solve; building a
        problem the planner has not seen before comes on top (stats.build_time).
        """
        stopped = self.stop or (lambda: False)
        self.stage("building")
        if guess not in GUESSES:
            raise ValueError(f"unknown guess {guess!r}; known: {', '.join(GUESSES)}")
        try:
            built = self._build(scene, settings, refinement=refine_from is not None)
            candidates = [r for r in built.stored if r.on(settings)]
            warm_start = warm_start and bool(candidates)
            stairs_first = (not warm_start and refine_from is None
                            and settings.step_height < 0 and settings.stair_segment_rows)
            attempts = (WARM_ATTEMPTS if warm_start or stairs_first
                        else REFINE_ATTEMPTS if refine_from is not None else COLD_ATTEMPTS)
            # every solver the plan may use, its fallbacks' and a continuation's (warm)
            # included, before the clock starts
            for variant in _variants(attempts + WARM_ATTEMPTS):
                self._solver(built, settings, variant)
        except (ValueError, RuntimeError) as err:
            return failed_result(scene, settings, f"could not build the problem: {err}")
        if stopped():
            return failed_result(scene, settings, STOPPED, PlanStatus.STOPPED)
        start = time.perf_counter()
        tr, step, mu = built.tr, settings.step_length, settings.friction_coefficient
        nsig = int(tr.S.shape[0])
        first = [0, 0.0]  # iterations and evaluation s of a plan this one continues
        if not warm_start and refine_from is not None:
            x_start, qref, origin = self._refined_start(scene, refine_from, built, step, mu)
            duals_start = {"lam_x0": np.zeros(x_start.size),
                           "lam_g0": np.zeros(int(tr.g.shape[0]))}
        elif stairs_first:
            seed, lower = self._stair_start(scene, settings, guess, int(tr.g.shape[0]))
            if seed is None:
                return lower
            x_start, qref = seed.x, seed.qref
            duals_start = {"lam_x0": seed.lam_x, "lam_g0": seed.lam_g}
            first = [lower.stats.iterations, lower.stats.evaluation_time]
            origin = (f"the plan on stairs of {max(settings.step_height, -STAIR_COLD_MAX):g} m "
                      f"with the edge margin ({lower.settings['initial_guess']}; "
                      f"{lower.stats.iterations} iterations); continued to "
                      f"{settings.step_height:g} m with the segment rows (warm)")
        elif warm_start:
            nearest = min(candidates, key=lambda r: abs(r.step - step) + abs(r.mu - mu))
            x_start, qref = nearest.x, nearest.qref
            duals_start = {"lam_x0": nearest.lam_x, "lam_g0": nearest.lam_g}
            origin = (f"warm start from the plan for step length {nearest.step:.4f} m, "
                      f"mu {nearest.mu:.3g} ({nearest.source})")
        else:
            self.stage("initial guess")
            qref = GUESSES[guess](tr, step, ground_of(scene, settings))[: tr.N - 1]
            x_start = np.concatenate([
                np.zeros(tr.U.numel() + tr.T.numel()), initial_multipliers(tr),
                np.full(nsig, settings.scaling_bounds[1])])
            duals_start = {"lam_x0": np.zeros(x_start.size),
                           "lam_g0": np.zeros(int(tr.g.shape[0]))}
            # sigma starts (fixed) at its upper bound, where every measured optimum of the
            # kinetic-energy cost puts it: the free stage then moves little, and the local
            # minimum reached depends less on round-off. walker3d's default request with
            # numpy's Haswell, Zen, SkylakeX, Prescott kernels (compiled) and CasADi
            # derivatives: J 20.7683, 20.7683, 20.7801, 20.7801, 20.7801 (0.06 % apart);
            # from sigma = 1: 20.7801, 20.7801, 20.8470, 20.8936, 20.7644 (0.6 %)
            origin = f"{guess} guess; sigma fixed at its upper bound and limits relaxed, then free"
        p = tr.parameters(qref, settings)
        built.callback.deadline = start + settings.max_solve_time
        built.callback.started, built.callback.iteration = start, 0
        built.callback.report, built.callback.stop = self.progress, stopped
        totals = first  # iterations, evaluation s
        for number, attempt in enumerate(attempts):
            x0, g, duals, status, success = self._attempt(
                built, settings, attempt, number, x_start, duals_start, p, totals)
            if success or stopped() or time.perf_counter() > built.callback.deadline \
                    or number + 1 == len(attempts):
                break
            origin += (f"; the inertia-free attempt stopped ({STATUS_WORDS.get(status, status)})"
                       f" after {totals[0]} iterations")
            base = _continuation_base(scene, settings)
            if number == 0 and base is not None:
                qref_c = GUESSES[guess](tr, base.step_length, ground_of(scene, base))[: tr.N - 1]
                found = self._continuation(built, settings, base, x_start, duals_start, qref_c,
                                           totals)
                if found is not None:
                    x0, g, duals, status, success, p = found
                    qref = qref_c
                    origin += (f"; continued from {_described(base)} (cold) to "
                               f"{_described(settings)} (warm)")
                    break
                if stopped() or time.perf_counter() > built.callback.deadline:
                    break
                origin += f"; the continuation from {_described(base)} failed"
            origin += ", restarted with IPOPT's inertia test"
        iterations, evaluation = totals
        if stopped():
            return failed_result(scene, settings, STOPPED, PlanStatus.STOPPED)
        result = build_result(tr, settings, x0, p, g, status=status, iterations=iterations,
                              solve_time=time.perf_counter() - start,
                              build_time=built.build_time, evaluation_time=evaluation,
                              origin=origin)
        result = dataclasses.replace(result, settings={
            **result.settings, "derivatives": built.derivatives_used})
        if result.success:
            self._store(built, _stored(settings, x0, duals, qref))
        return result
