"""Drake peer (issue #27): problem.json -> plan.npz, the gait problem written as Drake's own
legged trajectory optimisations write it, solved by IPOPT or SNOPT (Drake's wheels ship
both). Run in the drake env from the repository root:

    .venv-peers/drake/bin/python -m benchmarks.peers.drake_peer PROBLEM.json PLAN.npz \
        --intervals 8 [--solver ipopt|snopt] [--time-limit 300] [--free-durations] \
        [--scheme backward_euler|midpoint] [--cost squared_torque|kinetic_energy]

(the solver's log goes to PLAN.log; --time-limit, wall-clock, stops either solver through
an iterate callback, the plan then the last point evaluated, not converged).

The program (its formulation in its docstring) is benchmarks/peers/drake_program.py; this
module solves it and writes the plan.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from importlib.metadata import version
from pathlib import Path

import numpy as np
from pydrake.solvers import IpoptSolver, SnoptSolver, SolverOptions

from benchmarks.peers import exchange
from benchmarks.peers.drake_program import (CONE_SIDES, SCHEMES, STEP_BOUNDS,
                                            GaitProgram)

# Drake's IPOPT has no exact Hessian for generic constraints: it runs limited-memory BFGS.
IPOPT_OPTIONS = {"tol": 1e-6, "constr_viol_tol": 1e-6, "acceptable_tol": 1e-4,
                 "max_iter": 3000, "mu_strategy": "adaptive", "print_level": 0,
                 "file_print_level": 5}
# The littledog gait optimisation's SNOPT settings, feasibility 1e-6, iteration limits raised.
SNOPT_OPTIONS = {"Major feasibility tolerance": 1e-6, "Major optimality tolerance": 1e-4,
                 "Major iterations limit": 3000, "Iterations limit": 1_000_000,
                 "Superbasics limit": 5000, "Linesearch tolerance": 0.9}


class TimeLimit(Exception):
    """The solve's wall-clock limit passed (raised from the iterate callback)."""


def solve(problem: dict, intervals: int, solver: str, time_limit: float,
          free_durations: bool, scheme: str, cost: str, log: Path) -> exchange.Plan:
    """Build and solve the program (the solver's own log written to `log`); the plan in
    the exchange format, meta filled. A callback sees every point the solver evaluates
    and stops the solve after `time_limit` s (SNOPT 7.4, as Drake ships it, has no time
    limit of its own): the plan is then the last point evaluated, not converged."""
    start = time.perf_counter()
    gp = GaitProgram(problem, intervals, free_durations, scheme, cost)
    gp.set_guess()
    build_time = time.perf_counter() - start
    options = SolverOptions()
    log.unlink(missing_ok=True)
    if solver == "ipopt":
        backend = IpoptSolver()
        settings = dict(IPOPT_OPTIONS, output_file=str(log))
    else:
        backend = SnoptSolver()
        settings = dict(SNOPT_OPTIONS)
    for key, value in settings.items():
        options.SetOption(backend.solver_id(), key, value)
    variables = gp.prog.decision_variables()
    last = {"x": gp.prog.GetInitialGuess(variables), "evaluations": 0}
    start = time.perf_counter()

    def iterate(x):
        last["x"], last["evaluations"] = np.array(x), last["evaluations"] + 1
        if time.perf_counter() - start > time_limit:
            raise TimeLimit

    gp.prog.AddVisualizationCallback(iterate, variables)
    try:
        result = backend.Solve(gp.prog, None, options)
        x, converged = result.get_x_val(), bool(result.is_success())
        details = result.get_solver_details()
        status = details.ConvertStatusToString() if solver == "ipopt" else \
            f"SNOPT INFO {details.info}"
    except (TimeLimit, RuntimeError) as error:
        if not isinstance(error, TimeLimit) and "TimeLimit" not in str(error):
            raise
        x, converged, status = last["x"], False, f"time limit {time_limit:g} s"
    solve_time = time.perf_counter() - start
    text = log.read_text(errors="replace") if log.exists() else ""
    # IPOPT's iteration count: its summary line, or the last iteration row when stopped
    found = re.findall(r"Number of Iterations\.+:\s*(\d+)", text) or \
        re.findall(r"^\s*(\d+)r?\s+[-+]?\d\.\d+e[-+]\d+\s", text, re.MULTILINE)
    return _plan(gp, x, {
        "peer": "drake", "version": version("drake"), "solver": solver,
        "start": "kinematic guess",
        "formulation": f"direct transcription, {SCHEMES[scheme]}, AutoDiffXd generic"
                       " constraints, plastic impulses at touch-down, mirror periodicity",
        "grid": intervals, "cost": cost, "build_time": build_time,
        "solve_time": solve_time, "iterations": int(found[-1]) if found else -1,
        "converged": converged,
        "status": f"{status}; {last['evaluations']} function evaluations",
        "objective": float(np.sum(gp.prog.EvalBindings(gp.prog.GetAllCosts(), x))),
        "notes": _notes(gp)})


def _notes(gp: GaitProgram) -> str:
    cone = "exact (planar)" if gp.walker.planar else \
        f"inscribed {CONE_SIDES}-sided pyramid"
    durations = f"free (one step per phase, {STEP_BOUNDS[0]}..{STEP_BOUNDS[1]} of DMOCC's)" \
        if gp.free_durations else "DMOCC's (fixed)"
    return (f"durations {durations}; cones {cone}, hard; periodicity hard (mirror);"
            " joint ranges, joint speed limit, torso lean hard; swing clearance except"
            " next to a release or strike (z >= 0 there); objective includes FORCE_WEIGHT"
            " h |f|^2; not expressed: the strike-speed bound, the clearance ramp, a full"
            " contact's roll moment and foot width (point contacts), the paper's torso"
            " inertia (the URDF's realisable one)")


def _plan(gp: GaitProgram, x: np.ndarray, meta: dict) -> exchange.Plan:
    """The decision vector x as an exchange.Plan: nodes 0..K, torques per interval, each
    interval's forces at the node that ends it (backward Euler evaluates them there); node
    0's forces are the mirror images of node K's partners'."""
    w, K, prog = gp.walker, gp.K, gp.prog

    def value(variables):
        return x[prog.FindDecisionVariableIndices(np.ravel(variables))].reshape(
            np.shape(variables))

    q = value(gp.q)
    steps = np.array([value([gp.step(n)])[0] for n in range(K)])
    forces = {c: np.zeros((K + 1, 3)) for c in w.frames}
    for (n, c), f in gp.forces.items():
        forces[c][n + 1, list(w.dims)] = value(f)
    for c, partner in w.contact_partners(q[:, 0]).items():
        forces[c][0] = forces[partner][K] * np.array([1.0, -1.0, 1.0])
    return exchange.Plan(
        times=np.concatenate([[0.0], np.cumsum(steps)]),
        q=np.array([w.to_pin(column) for column in q.T]),
        phase_of_node=np.minimum(np.arange(K + 1) // gp.m, gp.P - 1), meta=meta,
        tau=value(gp.tau).T, forces=forces)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("problem", type=Path)
    parser.add_argument("plan", type=Path)
    parser.add_argument("--intervals", type=int, default=8, help="intervals per phase")
    parser.add_argument("--solver", choices=("ipopt", "snopt"), default="ipopt")
    parser.add_argument("--time-limit", type=float, default=300.0, help="s")
    parser.add_argument("--free-durations", action="store_true")
    parser.add_argument("--scheme", choices=tuple(SCHEMES), default="backward_euler")
    parser.add_argument("--cost", choices=("squared_torque", "kinetic_energy"),
                        default="squared_torque")
    args = parser.parse_args(argv)
    problem = exchange.read_problem(args.problem)
    plan = solve(problem, args.intervals, args.solver, args.time_limit, args.free_durations,
                 args.scheme, args.cost, args.plan.with_suffix(".log"))
    exchange.write_plan(args.plan, plan)
    print(json.dumps(plan.meta))
    return 0


if __name__ == "__main__":
    sys.exit(main())
