"""Solving the collocation NLP with the product's IPOPT set-up.

Same options as `gait_planner.ocp.solve.Planner` (`gait_planner.ocp.ipopt.ipopt_options`:
MUMPS, tol and constr_viol_tol of the settings, adaptive mu, warm_start_init_point), the
same solver variants and cold-start stages (`VARIANTS`, `COLD_ATTEMPTS`: sigma fixed at its
upper bound with the swing clearance and joint speed limits relaxed, then everything free;
the inertia-free curvature test first, IPOPT's inertia correction as the fallback), the
same progress callback and time limit.

The NLP is built with recursive Newton-Euler dynamics (`collocation.rnea.SpatialModel`, the
same values as `MinimalModel` to round-off) and expanded to one SX graph before IPOPT
(Hessian and Jacobian by SX AD; nothing compiled). Measured alternatives (2-core machine,
walker2d on the DMOCC nodes): `MinimalModel` (derivatives of q(theta) composed with the
director mass matrix) as MX calls of per-point SX Functions cost 200 ms of derivative
evaluation per iteration against 13.6 ms (build 2 s against 7 s) and, with a 0.04 s swing
clearance ramp (`ocp.clearance`) and joint-rate bounds at the impacts (a variant not kept),
did not converge within 600 s (414 iterations) where this form converged in 231
iterations, 6.5 s (2026-11-23; today's problem: 70 iterations, 1.9 s in
benchmarks/REPORT.md); `MinimalModel` expanded built
walker2d in 19 s and did not finish walker3d (over 6 GB). walker3d at 4 intervals per phase
builds in 41 s (2.4 GB).

Cold attempts (`ATTEMPTS`): the product's inertia-free attempt from the "linear" guess
(`collocation.guess`), then an inertia-free attempt from the "spline" guess with the whole
iteration budget, then the product's inertia-correction attempt from the "linear" guess.
Measured 2026-11-23 with benchmarks/work_precision.py's settings (60 s for walker2d):
walker2d at 8 intervals per phase converges in the first (94 iterations, 2.8 s), at 12 and
16 now in the second (691 and 279 iterations, 32 s and 22 s); before, the inertia attempt
took them over (benchmarks/results: converged, 167 iterations each; re-run on the loaded
machine: time limit after 171 and 169 iterations). walker3d at 4, 6, 8 and 12 intervals
per phase converges in the second (509, 1101, 515, 793 iterations; 68, 195, 134, 291 s)
and converged in none of the product's: from "linear" the relaxed stage had not converged
after 1000 iterations; with the inertia correction (from "spline" with inverse-dynamics
torques, a variant not kept) the regularisation rose to 1e5 and the infeasibility stayed
at 990 N for 100 iterations. From "spline" the relaxed stage and the free one take 245 +
114 iterations at 4 intervals per phase and 338 + 27 at 8, more than the 150 per stage of
the first attempt (`COLLOCATION_VARIANTS`), hence the whole budget.

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

import time

import casadi as ca
import numpy as np

from gait_planner.collocation.guess import initial_guess
from gait_planner.collocation.mesh import mesh_of
from gait_planner.collocation.result import build_result
from gait_planner.collocation.rnea import SpatialModel
from gait_planner.collocation.transcription import CollocationTranscription
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solution import STATUS_WORDS, failed_result
from gait_planner.ocp.ipopt import IterationCallback, Progress, ipopt_options, run_attempt
from gait_planner.ocp.solve import COLD_ATTEMPTS, INERTIA_FREE, VARIANTS
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


def problem_size(solver: ca.Function, nx: int, ng: int) -> dict[str, int]:
    """variables, constraints, nonzeros of the constraint Jacobian and of the Hessian of
    the Lagrangian (lower triangle, what IPOPT stores) of an nlpsol instance."""
    rows, cols = solver.get_function("nlp_hess_l").sparsity_out(0).get_triplet()  # triu
    return {"variables": nx, "constraints": ng,
            "jacobian_nonzeros": int(solver.get_function("nlp_jac_g").sparsity_out(1).nnz()),
            "hessian_nonzeros": int(np.sum(np.array(rows) <= np.array(cols)))}


def plan_collocation(scene: Scene, settings: GaitSettings, *, intervals_per_phase: int | None = None,
                     progress: Progress | None = None) -> PlanResult:
    """Plan the half cycle of (scene, settings) by Hermite-Simpson collocation in minimal
    coordinates (`gait_planner.collocation.transcription`); intervals_per_phase sets the
    collocation mesh (None: the DMOCC nodes), the problem itself is that of `settings`
    (`collocation.mesh`). Returns a `PlanResult` as the product's (`collocation.result`),
    with the NLP's size in result.settings (variables, constraints, jacobian_nonzeros,
    hessian_nonzeros)."""
    start = time.perf_counter()
    try:
        tr = CollocationTranscription(SpatialModel(Multibody(scene)), settings,
                                      mesh_of(scene, settings, intervals_per_phase))
    except (ValueError, RuntimeError) as err:
        return failed_result(scene, settings, f"could not build the problem: {err}")
    nx, ng = int(tr.x.shape[0]), int(tr.g.shape[0])
    graph = ca.Function("collocation_nlp", [tr.x, tr.p], [tr.cost, tr.g]).expand()
    xs, ps = ca.SX.sym("x", nx), ca.SX.sym("p", int(tr.p.shape[0]))
    f, g_expr = graph(xs, ps)
    nlp = {"x": xs, "p": ps, "f": f, "g": g_expr}
    lbx, ubx, lbg, ubg = tr.bounds()
    callback = IterationCallback(nx, ng, lbg, ubg)
    solvers: dict[str, ca.Function] = {}

    def solver(variant: str) -> ca.Function:
        if variant not in solvers:
            opts = ipopt_options(callback, settings)
            opts.update(COLLOCATION_VARIANTS[variant])
            opts["ipopt.max_iter"] = min(opts["ipopt.max_iter"], settings.max_iterations)
            solvers[variant] = ca.nlpsol(f"collocation_{variant}", "ipopt", nlp, opts)
        return solvers[variant]

    size = problem_size(solver(ATTEMPTS[0][1][0][0]), nx, ng)
    build_time = time.perf_counter() - start
    start = time.perf_counter()
    p = np.array([settings.step_length, settings.friction_coefficient])
    sig = tr.variables.index("sigma")
    callback.deadline = start + settings.max_solve_time
    callback.started, callback.iteration, callback.report = start, 0, progress
    origin = ("kinematic guess (ocp.guess) in minimal coordinates, linear; sigma fixed at its "
              "upper bound and limits relaxed, then free")
    totals = [0, 0.0]  # iterations, evaluation s
    x_starts: dict[str, np.ndarray] = {}
    for number, (kinematics, attempt) in enumerate(ATTEMPTS):
        if kinematics not in x_starts:
            x_starts[kinematics] = initial_guess(tr, settings.step_length, kinematics)
        zero_duals = {"lam_x0": np.zeros(nx), "lam_g0": np.zeros(ng)}
        x, g, _, status, success = run_attempt(solver, attempt, x_starts[kinematics], zero_duals,
                                               p, (lbx, ubx, lbg, ubg), sig,
                                               tr.relaxed_lower_bounds, totals)
        if success or time.perf_counter() > callback.deadline or number + 1 == len(ATTEMPTS):
            break
        following = ATTEMPTS[number + 1]
        test = "IPOPT's inertia test" if following[1][0][0] == "cold_inertia" \
            else "the inertia-free test and no iteration cap"
        origin += (f"; attempt {number + 1} stopped ({STATUS_WORDS.get(status, status)}) after "
                   f"{totals[0]} iterations, restarted from the {following[0]} guess with {test}")
    iterations, evaluation = totals
    return build_result(tr, x, p, g, status=status, iterations=iterations,
                        solve_time=time.perf_counter() - start, build_time=build_time,
                        evaluation_time=evaluation, origin=origin, sizes=size)
