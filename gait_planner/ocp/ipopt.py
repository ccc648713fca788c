"""IPOPT calls shared by the DMOCC planner (`ocp.solve`) and the collocation baseline
(`benchmarks.collocation`): the per-iteration callback (progress, deadline, stop), the
common options, one IPOPT call and an attempt's stages."""

from __future__ import annotations

import dataclasses
import time
from typing import Callable

import casadi as ca
import numpy as np

from gait_planner.ocp.settings import GaitSettings

Progress = Callable[[int, float, float, float], None]  # iteration, cost, violation, seconds
Stop = Callable[[], bool]  # polled every iteration: True stops the plan (nothing is kept)


class IterationCallback(ca.Callback):
    """Called by IPOPT every iteration: reports progress, stops at the deadline or when
    `stop` says so (IPOPT then ends with User_Requested_Stop after this iteration)."""

    def __init__(self, nx: int, ng: int, lbg: np.ndarray, ubg: np.ndarray):
        ca.Callback.__init__(self)
        self.nx, self.ng, self.lbg, self.ubg = nx, ng, lbg, ubg
        self.deadline = np.inf
        self.started = time.perf_counter()
        self.iteration = 0
        self.report: Progress | None = None
        self.stop: Stop | None = None
        self.construct("iteration_callback", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.nx)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.ng)
        return ca.Sparsity(0, 0)

    def eval(self, arg):
        g = np.array(arg[ca.nlpsol_out().index("g")]).ravel()
        viol = float(np.max(np.concatenate([[0.0], self.lbg - g, g - self.ubg])))
        if self.report is not None:
            cost = float(arg[ca.nlpsol_out().index("f")])
            self.report(self.iteration, cost, viol, time.perf_counter() - self.started)
        self.iteration += 1
        stopped = self.stop is not None and self.stop()
        return [1 if stopped or time.perf_counter() > self.deadline else 0]


def ipopt_options(callback: IterationCallback, s: GaitSettings) -> dict:
    """The IPOPT options every solver variant shares (the planner's and the collocation
    baseline's): MUMPS, the settings' tolerances and iteration limit, adaptive mu,
    warm_start_init_point, progress and stopping through `callback`."""
    return {
        "print_time": False,
        # No gradient of the Lagrangian in CasADi (it would only give lam_p, which no one
        # reads): building it differentiated the whole SX graph again for every IPOPT
        # instance (walker3d: 0.7 of 0.75 s each; 2026-11-25) and evaluated it after every solve
        "calc_lam_p": False,
        "no_nlp_grad": True,
        "iteration_callback": callback,
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        "ipopt.linear_solver": "mumps",
        "ipopt.tol": s.solve.tolerance,
        "ipopt.constr_viol_tol": s.solve.constraint_tolerance,
        # IPOPT's "acceptable" stop keeps the tight constraint tolerance: only the
        # optimality error is relaxed (to 1e-6, IPOPT's default acceptable_tol)
        "ipopt.acceptable_constr_viol_tol": s.solve.constraint_tolerance,
        "ipopt.max_iter": s.solve.max_iterations,
        "ipopt.mu_strategy": "adaptive",
        "ipopt.warm_start_init_point": "yes",
    }


@dataclasses.dataclass(frozen=True)
class StageStats:
    """What one IPOPT call reports: iterations, seconds spent evaluating functions and
    derivatives, return status, success."""

    iterations: int
    evaluation_time: float
    status: str
    success: bool


def solve_stage(solver: ca.Function, x0: np.ndarray, duals: dict, p: np.ndarray,
                lbx: np.ndarray, ubx: np.ndarray, lbg: np.ndarray, ubg: np.ndarray):
    """One IPOPT call from (x0, duals {"lam_x0", "lam_g0"}): (x, g, duals to continue
    from, StageStats)."""
    sol = solver(x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, **duals)
    stats = solver.stats()
    return (np.array(sol["x"]).ravel(), np.array(sol["g"]).ravel(),
            {"lam_x0": np.array(sol["lam_x"]).ravel(), "lam_g0": np.array(sol["lam_g"]).ravel()},
            StageStats(int(stats.get("iter_count", 0)),
                       sum(v for k, v in stats.items() if k.startswith("t_wall_nlp_")),
                       str(stats.get("return_status", "unknown")),
                       bool(stats.get("success", False))))


def run_attempt(solver_of: Callable[[str], ca.Function], attempt, x0: np.ndarray,
                duals: dict, p: np.ndarray, bounds: tuple, sigma, relaxed_lower_bounds,
                totals: list, enter: Callable[[int, str], None] = lambda k, variant: None):
    """The stages of one attempt, a list of (variant, sigma fixed, limits relaxed), from
    (x0, duals {"lam_x0", "lam_g0"}) with parameters p: each stage is one IPOPT call of
    `solver_of(variant)` within bounds (lbx, ubx, lbg, ubg), with x[sigma] fixed at its
    current value if asked and lbg replaced by `relaxed_lower_bounds(lbg)` if relaxed;
    `enter(k, variant)` is called before stage k. Adds iterations and evaluation seconds to
    totals [iterations, seconds] and stops at the first stage that fails. Returns (x, g,
    duals, status, success) of the last stage run (the DMOCC planner's and the collocation
    baseline's attempts alike)."""
    lbx, ubx, lbg, ubg = bounds
    g, status, success = None, "not started", False
    for k, (variant, fix_sigma, relaxed) in enumerate(attempt):
        enter(k, variant)
        lb, ub = lbx.copy(), ubx.copy()
        if fix_sigma:
            lb[sigma] = ub[sigma] = x0[sigma]
        lower = relaxed_lower_bounds(lbg) if relaxed else lbg
        x0, g, duals, stage = solve_stage(solver_of(variant), x0, duals, p, lb, ub, lower, ubg)
        totals[0] += stage.iterations
        totals[1] += stage.evaluation_time
        status, success = stage.status, stage.success
        if not success:
            break
    return x0, g, duals, status, success
