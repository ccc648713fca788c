"""Solving the collocation NLP with the product's IPOPT set-up.

Same options as `gait_planner.ocp.solve.Planner` (`gait_planner.ocp.ipopt.ipopt_options`:
MUMPS, tol and constr_viol_tol of the settings, adaptive mu, warm_start_init_point), the
same solver variants and cold-start stages (`VARIANTS`, `COLD_ATTEMPTS`: sigma fixed at its
upper bound with the swing clearance and joint speed limits relaxed, then everything free;
the inertia-free curvature test first, IPOPT's inertia correction as the fallback), the
same progress callback and time limit.

Everything a plan may use is built before the clock starts (stats.build_time): the NLP,
its derivatives and the IPOPT instance of every variant in `ATTEMPTS` (until 2026-11-27
"cold_full" was created inside the timed solve, when the first attempt failed: CasADi then
differentiated the whole graph on the clock, walker3d at 4 intervals per phase 10.7 of
74.1 s, issue #27).

The NLP is built with recursive Newton-Euler dynamics (`collocation.rnea.SpatialModel`, the
same values as `MinimalModel` to round-off); IPOPT evaluates f and g as one expanded SX
graph. Its derivatives (`collocation_nlp`), as settings.solve.compiled says:
* compiled (the baseline of benchmarks/work_precision.py): the rows and cost terms that are
  one formula per collocation point, knot or interval are elements (`collocation.elements`)
  whose Jacobians and Lagrangian Hessians `ocp.derivatives.nlp_derivatives` maps over the
  mesh and compiles to C (`ocp.compile`, vector passes of 4 points, cached per machine),
  as the product's; CasADi differentiates the rest (touch-down rows, the pinned start, the
  speed row, the torque and share terms of the cost), compiled too. The compiled and
  interpreted derivatives agree to round-off (test_collocation_compiled), so the iterates
  part only by round-off. Compiling the whole expanded graph instead is not viable
  (issue #27: walker3d's Hessian 266 MB of C, gcc out of memory on walker2d at 12 per
  phase);
* interpreted: CasADi's derivatives of the one expanded graph in its virtual machine,
  formed once and shared by the solver variants.
Measured by benchmarks/work_precision.py on the 2-core machine shared with other jobs
(load 2-7, 2026-11-27; times inflated), per iteration, compiled against interpreted:
evaluation 10-22 against 27-77 ms on walker2d (4-16 intervals per phase), 20-36 against
141-349 ms on walker3d (4-12); the rest is IPOPT's own (MUMPS's factorisations and solves
above all), alike in both forms and now most of a compiled iteration: walker2d 44-192 ms,
walker3d 156-315 ms (DMOCC's: 8-35 ms on 3-4 times fewer unknowns). The element libraries
are the same for every grid: built once per machine (walker3d's in 690 s, walker2d's in
74 s of gcc on the loaded machine), after which a compiled build takes 1-86 s (the rest's
derivatives, the libraries of groups of a size not met before, IPOPT's instances), an
interpreted one 6-70 s.

Earlier derivative forms (2-core machine, walker2d on the DMOCC nodes):
`MinimalModel` (derivatives of q(theta) composed with the director mass matrix) as MX calls
of per-point SX Functions cost 200 ms of derivative evaluation per iteration against
13.6 ms (build 2 s against 7 s) and, with a 0.04 s swing clearance ramp (`ocp.clearance`)
and joint-rate bounds at the impacts (a variant not kept), did not converge within 600 s
(414 iterations) where this form converged in 231 iterations, 6.5 s (2026-11-23);
`MinimalModel` expanded built walker2d in 19 s and did not finish walker3d (over 6 GB).

Cold attempts (`ATTEMPTS`): the product's inertia-free attempt from the "linear" guess
(`collocation.guess`), then an inertia-free attempt from the "spline" guess with the whole
iteration budget, then the product's inertia-correction attempt from the "linear" guess.
From "linear" walker3d's relaxed stage had not converged after 1000 iterations, and with
the inertia correction (from "spline" with inverse-dynamics torques, a variant not kept)
the regularisation rose to 1e5 and the infeasibility stayed at 990 N for 100 iterations;
from "spline" the relaxed stage and the free one took 245 + 114 iterations at 4 intervals
per phase and 338 + 27 at 8, more than the 150 per stage of the first attempt
(`COLLOCATION_VARIANTS`), hence the whole budget (2026-11-23).
Measured 2026-11-27 (benchmarks/work_precision.py: 60 s per walker2d solve, 300 s per
walker3d solve, loaded machine), compiled form: walker2d converges at 8 and 12 intervals per
phase in the first attempt (153 and 154 iterations, 22 and 34 s); at 4, 6 and 16 it stops at
the time limit in the second (1077, 557 and 532 iterations); given 600 s at 4 the second
attempt ran to its 3000 iterations and the third (the inertia test) was slower than 1 s an
iteration. walker3d converges at 4 (486 iterations, 86 s; all but the first 150 in the
second attempt) and at 12 (163 iterations, 52 s, in the first), and stops in the second at
6 and 8 (849 and 1079 iterations in 300 s). The interpreted form, its derivatives equal to
round-off, takes other iterates (walker2d at 12: 93 iterations to the same J) at 2-7 times
the evaluation time; it converged at walker2d 8 and 12 and on no walker3d grid
within 300 s (400-1048 iterations).

Why walker3d needs that many: its optimum is stiff and nearly singular where a foot stands
on one point (right_forefoot, double_heel). The foot's roll about that point (inertia
0.0035 kg m^2; walker2d's foot has only its pitch, 0.0196 kg m^2 about the forefoot)
reaches 2500-5000 rad/s^2 in the converged plan, the vertical forces alternate from knot
to knot (32-823 N), and the reduced Hessian there has eigenvalues from -3.6e-5 to 1.7e-7
along the ankle accelerations of these phases; IPOPT's full steps of 20-50 (scaled) in
these directions raise the infeasibility to 100-200 N and back. Started from the DMOCC
plan mapped to the collocation (4 per phase) it still needed 163 + 178 iterations.
"""

from __future__ import annotations

import dataclasses
import time

import casadi as ca
import numpy as np

from benchmarks.collocation.guess import initial_guess
from benchmarks.collocation.mesh import mesh_of
from benchmarks.collocation.result import build_result
from benchmarks.collocation.rnea import SpatialModel
from benchmarks.collocation.transcription import CollocationTranscription
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.compile import CompileError, compile_sources
from gait_planner.ocp.derivatives import expand_nlp, nlp_derivatives
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solution import STATUS_WORDS, failed_result
from gait_planner.ocp.ipopt import IterationCallback, Progress, ipopt_options, run_attempt
from gait_planner.ocp.solve import INERTIA_FREE, VARIANTS
from gait_planner.strategies import COLD_ATTEMPTS
from gait_planner.result import PlanResult

# Solver variants: the product's, except that the first attempt keeps 150 iterations per
# stage (the product's cap is 400 since 2026-11-23; from the "linear" guess walker3d's
# relaxed stage had not converged after 1000, so a longer first attempt only delays the
# "spline" one, at 0.2-0.4 s an iteration), and the inertia-free test with the settings'
# whole iteration budget (module docstring; measured with these caps)
COLLOCATION_VARIANTS = {**VARIANTS, "cold": {**INERTIA_FREE, "ipopt.max_iter": 150},
                        "cold_full": INERTIA_FREE}
# Cold attempts (guess mapping, stages as `COLD_ATTEMPTS`), in order (module docstring)
ATTEMPTS = (("linear", COLD_ATTEMPTS[0]),
            ("spline", [("cold_full", True, True), ("cold_full", False, False)]),
            ("linear", COLD_ATTEMPTS[1]))


def problem_size(jac_g: ca.Function, hess_lag: ca.Function, nx: int, ng: int) -> dict[str, int]:
    """variables, constraints, nonzeros of the constraint Jacobian and of the Hessian of
    the Lagrangian (lower triangle, what IPOPT stores) of the NLP whose derivatives are
    jac_g ((x, p) -> (g, jac_g_x)) and hess_lag (-> its upper or full Hessian)."""
    rows, cols = hess_lag.sparsity_out(0).get_triplet()
    return {"variables": nx, "constraints": ng,
            "jacobian_nonzeros": int(jac_g.sparsity_out(1).nnz()),
            "hessian_nonzeros": int(np.sum(np.array(rows) <= np.array(cols)))}


def collocation_nlp(tr: CollocationTranscription, compiled: bool
                    ) -> tuple[dict, dict[str, ca.Function], str]:
    """(nlp {"x", "p", "f", "g"} as SX, derivative Functions for nlpsol's options grad_f,
    jac_g, hess_lag, how they are evaluated in words). compiled: the elements' derivatives
    (`collocation.elements`) mapped and compiled to C (`ocp.derivatives.nlp_derivatives`,
    `ocp.compile`); otherwise, or if that is not possible, CasADi's derivatives of the one
    expanded SX graph, formed once for all the solver variants (as `ocp.solve`'s)."""
    used = "CasADi, whole SX graph"
    if compiled:
        if tr.layout is None:
            used += " (not compiled: the mirror image of knot 0 is not a signed permutation)"
        else:
            expanded = expand_nlp(tr)
            nlp = {"x": expanded.x, "p": expanded.p, "f": expanded.f, "g": expanded.g}
            try:
                return nlp, nlp_derivatives(tr, compile_sources, expanded), \
                    "per-point elements compiled to C"
            except CompileError as err:
                used += f" (not compiled: {err})"
    graph = ca.Function("collocation_nlp", [tr.x, tr.p], [tr.cost, tr.g]).expand()
    xs, ps = ca.SX.sym("x", int(tr.x.shape[0])), ca.SX.sym("p", int(tr.p.shape[0]))
    f, g = graph(xs, ps)
    nlp = {"x": xs, "p": ps, "f": f, "g": g}
    reference = ca.nlpsol("collocation_derivatives", "ipopt", nlp, {"print_time": False})
    return nlp, {name: reference.get_function(f"nlp_{function}") for name, function in
                 (("grad_f", "grad_f"), ("jac_g", "jac_g"), ("hess_lag", "hess_l"))}, used


def plan_collocation(scene: Scene, settings: GaitSettings, *, intervals_per_phase: int | None = None,
                     progress: Progress | None = None) -> PlanResult:
    """Plan the half cycle of (scene, settings) by Hermite-Simpson collocation in minimal
    coordinates (`benchmarks.collocation.transcription`); intervals_per_phase sets the
    collocation mesh (None: the DMOCC nodes), the problem itself is that of `settings`
    (`collocation.mesh`); settings.solve.compiled: derivatives compiled from the elements
    (`collocation_nlp`). Returns a `PlanResult` as the product's (`collocation.result`),
    with the NLP's size in result.settings (variables, constraints, jacobian_nonzeros,
    hessian_nonzeros) and how its derivatives were evaluated ("derivatives"). Everything
    built (the NLP, its derivatives, every IPOPT instance the attempts may use) is in
    stats.build_time, not in the solve time."""
    start = time.perf_counter()
    try:
        tr = CollocationTranscription(SpatialModel(Multibody(scene)), settings,
                                      mesh_of(scene, settings, intervals_per_phase))
    except (ValueError, RuntimeError) as err:
        return failed_result(scene, settings, f"could not build the problem: {err}")
    nx, ng = int(tr.x.shape[0]), int(tr.g.shape[0])
    nlp, derivatives, used = collocation_nlp(tr, settings.solve.compiled)
    lbx, ubx, lbg, ubg = tr.bounds()
    callback = IterationCallback(nx, ng, lbg, ubg)
    solvers: dict[str, ca.Function] = {}
    for variant in dict.fromkeys(v for _, attempt in ATTEMPTS for v, _, _ in attempt):
        opts = ipopt_options(callback, settings)
        opts.update(COLLOCATION_VARIANTS[variant])
        opts["ipopt.max_iter"] = min(opts["ipopt.max_iter"], settings.solve.max_iterations)
        opts.update(derivatives)
        solvers[variant] = ca.nlpsol(f"collocation_{variant}", "ipopt", nlp, opts)
    size = problem_size(derivatives["jac_g"], derivatives["hess_lag"], nx, ng)
    build_time = time.perf_counter() - start
    start = time.perf_counter()
    p = np.array([settings.step_length, settings.friction_coefficient])
    sig = tr.variables.index("sigma")
    callback.deadline = start + settings.solve.max_solve_time
    callback.started, callback.iteration, callback.report = start, 0, progress
    origin = ("kinematic guess (ocp.guess) in minimal coordinates, linear; sigma fixed at its "
              "upper bound and limits relaxed, then free")
    totals = [0, 0.0]  # iterations, evaluation s
    x_starts: dict[str, np.ndarray] = {}
    for number, (kinematics, attempt) in enumerate(ATTEMPTS):
        if kinematics not in x_starts:
            x_starts[kinematics] = initial_guess(tr, settings.step_length, kinematics)
        zero_duals = {"lam_x0": np.zeros(nx), "lam_g0": np.zeros(ng)}
        x, g, _, status, success = run_attempt(solvers.__getitem__, attempt,
                                               x_starts[kinematics], zero_duals, p,
                                               (lbx, ubx, lbg, ubg), sig,
                                               tr.relaxed_lower_bounds, totals)
        if success or time.perf_counter() > callback.deadline or number + 1 == len(ATTEMPTS):
            break
        following = ATTEMPTS[number + 1]
        test = "IPOPT's inertia test" if following[1][0][0] == "cold_inertia" \
            else "the inertia-free test and no iteration cap"
        origin += (f"; attempt {number + 1} stopped ({STATUS_WORDS.get(status, status)}) after "
                   f"{totals[0]} iterations, restarted from the {following[0]} guess with {test}")
    iterations, evaluation = totals
    result = build_result(tr, x, p, g, status=status, iterations=iterations,
                          solve_time=time.perf_counter() - start, build_time=build_time,
                          evaluation_time=evaluation, origin=origin, sizes=size)
    return dataclasses.replace(result, settings={**result.settings, "derivatives": used})
