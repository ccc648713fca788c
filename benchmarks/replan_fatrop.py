"""walker3d's warm re-plan solved by fatrop, a Riccati-based interior point, against the
planner's IPOPT (issue #62 item 5: a re-plan within 0.3 s; IPOPT with MUMPS takes about 1 s).

Usage: .venv/bin/python benchmarks/replan_fatrop.py [--max-iter 200] [--mu-init 1e-6]
       [--convexify eigen-reflect] [--print-level 5] [--json NAME]

The re-plan is the one `transitions.py` times: walker3d's default gait planned cold, then
transitions of two half cycles from three seeded starts (2 cm and 0.1 rad/s off the gait's
first node, `turned_start`), each from the last; the last one's IPOPT call is captured
(its NLP, bounds, parameters, start point and multipliers) and solved again by the planner's
own IPOPT instance, then by fatrop.

Fatrop takes an optimal control problem stage by stage: variables x_0, u_0, x_1, u_1, ...,
the rows of stage k (first x_{k+1} - F(x_k, u_k), then its own rows) touching only x_k, u_k
(CasADi's `fatrop` nlpsol, structure given: N, nx, nu, ng). DMOCC's rows each touch at most
three consecutive nodes, so the NLP is lifted into that form here, exactly: stage k's
controls are node k's torques and contact multipliers and node k+1's reparametrisation u;
its state carries copies of the unknowns of earlier nodes (and the phase scalings) that its
rows and cost terms use; every row and cost term is the planner's own expression with the
copies substituted, and X_{k+1} - (X_k, U_k) selected is the identity gap row fatrop wants.
The captured optimum, lifted, satisfies the lifted rows to the same round-off. fatrop has no
multiplier warm start (1.1.8, as CasADi 3.8.2 ships it); it starts from the lifted point.
Threads: one. The machine and its load are printed.
"""

from __future__ import annotations

import argparse
import time

import casadi as ca
import numpy as np

from gait_planner.ocp import ipopt
from gait_planner.ocp.transition import start_of_plan, turned_start
from gait_planner.transitions import plan_transition
from transitions import planned_gait


def captured_replan() -> tuple[dict, dict, np.ndarray]:
    """(the last re-plan's IPOPT call: solver, x0, duals, p, bounds; the transition's NLP
    {x, p, f, g}; node (nx,) of each unknown, -1 for the phase scalings). The solver's
    iteration callback is left without a deadline, so it can be called again."""
    scene, settings, planner, gait = planned_gait("walker3d")
    rng = np.random.default_rng(0)
    calls, solve_stage = [], ipopt.solve_stage

    def spy(solver, x0, duals, p, lbx, ubx, lbg, ubg):
        calls.append(dict(solver=solver, x0=x0, duals=duals, p=p, lbx=lbx, ubx=ubx,
                          lbg=lbg, ubg=ubg))
        return solve_stage(solver, x0, duals, p, lbx, ubx, lbg, ubg)

    ipopt.solve_stage = spy
    try:
        for number in range(3):
            start = turned_start(scene, start_of_plan(gait), rng.uniform(-0.02, 0.02),
                                 rng.uniform(-0.1, 0.1))
            plan_transition(planner, scene, settings, start, steps=2, halves=2,
                            from_last=number > 0)
    finally:
        ipopt.solve_stage = solve_stage
    built = [b for b in planner._built.values() if b.tr.transition][-1]
    built.callback.deadline, built.callback.report, built.callback.stop = np.inf, None, None
    layout = built.tr.layout
    node = np.full(int(built.tr.x.shape[0]), -1)
    for n in range(layout.N + 1):
        node[layout.u_index(n)] = max(n - 1, 0)  # u_{n} is a control of stage n - 1
        if n < layout.N:
            node[layout.tau_index(n)] = n
            node[layout.lam_index(n)] = n
    return calls[-1], built.nlp, node


def cost_terms(f: ca.SX, x: ca.SX) -> list[ca.SX]:
    """The additive terms of f, products with factors free of x distributed."""
    terms, stack = [], [(f, 1)]
    while stack:
        e, c = stack.pop()
        free = [not ca.depends_on(e.dep(i), x) for i in range(e.n_dep())]
        if e.is_op(ca.OP_ADD) or e.is_op(ca.OP_SUB):
            stack += [(e.dep(0), c), (e.dep(1), c if e.is_op(ca.OP_ADD) else -c)]
        elif e.is_op(ca.OP_NEG):
            stack.append((e.dep(0), -c))
        elif e.is_op(ca.OP_MUL) and any(free):
            k = free.index(True)
            stack.append((e.dep(1 - k), c * e.dep(k)))
        elif e.is_op(ca.OP_DIV) and free[1]:
            stack.append((e.dep(0), c / e.dep(1)))
        else:
            terms.append(c * e)
    return terms


def lifted(nlp: dict, node: np.ndarray):
    """(the stage-wise NLP, fatrop's structure {N, nx, nu, ng}, lift: a function from the
    NLP's (x, lbx, ubx, lam_x, lbg, ubg, lam_g) to the stage form's)."""
    x, g = nlp["x"], nlp["g"]
    terms = cost_terms(nlp["f"], x)

    def used(e) -> np.ndarray:
        return np.array(ca.jacobian(e, x).sparsity().get_col(), dtype=int)

    jac = ca.jacobian(g, x).sparsity().T
    rows = [np.array(jac.row()[jac.colind()[r]:jac.colind()[r + 1]], dtype=int)
            for r in range(g.shape[0])]
    row_stage = np.array([max(int(node[v].max()), 0) if v.size else 0 for v in rows])
    term_used = [used(t) for t in terms]
    term_stage = np.array([max(int(node[v].max()), 0) if v.size else 0 for v in term_used])
    last = node.copy()
    for v, k in list(zip(rows, row_stage)) + list(zip(term_used, term_stage)):
        last[v] = np.maximum(last[v], k)
    N = int(node.max())
    states = [np.where((node < k) & (last >= k))[0] for k in range(N + 1)]
    controls = [np.where(node == k)[0] for k in range(N + 1)]
    X = [ca.SX.sym(f"X{k}", s.size) for k, s in enumerate(states)]
    U = [ca.SX.sym(f"U{k}", c.size) for k, c in enumerate(controls)]
    w, gs, f, blocks = [], [], 0, []
    for k in range(N + 1):
        copy = {**dict(zip(states[k], ca.vertsplit(X[k]))),
                **dict(zip(controls[k], ca.vertsplit(U[k])))}
        keys = sorted(copy)
        old, new = ca.vertcat(*[x[j] for j in keys]), ca.vertcat(*[copy[j] for j in keys])
        w += [X[k], U[k]]
        if k < N:
            gs.append(X[k + 1] - ca.vertcat(*[copy[j] for j in states[k + 1]]))
        own = np.where(row_stage == k)[0]
        blocks.append(own)
        if own.size:
            gs.append(ca.substitute(g[own.tolist()], old, new))
        mine = [terms[i] for i in np.where(term_stage == k)[0]]
        if mine:
            f = f + ca.substitute(ca.sum1(ca.vertcat(*mine)), old, new)
    structure = {"N": N, "nx": [s.size for s in states], "nu": [c.size for c in controls],
                 "ng": [b.size for b in blocks]}

    def lift(xv, lbx, ubx, lam_x, lbg, ubg, lam_g) -> dict:
        out = {k: [] for k in ("x0", "lbx", "ubx", "lam_x0", "lbg", "ubg", "lam_g0")}
        for k in range(N + 1):
            s, c = states[k], controls[k]
            bounded = (node[s] < 0) & (k == 0)  # the phase scalings' bounds, once
            out["x0"] += [xv[s], xv[c]]
            out["lbx"] += [np.where(bounded, lbx[s], -np.inf), lbx[c]]
            out["ubx"] += [np.where(bounded, ubx[s], np.inf), ubx[c]]
            out["lam_x0"] += [np.where(bounded, lam_x[s], 0.0), lam_x[c]]
            if k < N:
                zero = np.zeros(states[k + 1].size)
                out["lbg"].append(zero), out["ubg"].append(zero), out["lam_g0"].append(zero)
            out["lbg"].append(lbg[blocks[k]]), out["ubg"].append(ubg[blocks[k]])
            out["lam_g0"].append(lam_g[blocks[k]])
        return {k: np.concatenate(v) for k, v in out.items()}

    return {"x": ca.vertcat(*w), "p": nlp["p"], "f": f, "g": ca.vertcat(*gs)}, structure, lift


def timed(name: str, solver: ca.Function, **arguments) -> dict:
    """One call of `solver`, timed: its status, iterations, wall and evaluation seconds, the
    rest an iteration, and fatrop's own count and search-direction time where it has them."""
    began = time.perf_counter()
    solution = solver(**arguments)
    wall = time.perf_counter() - began
    stats = solver.stats()
    own = stats.get("fatrop", {})
    evaluations = sum(v for k, v in stats.items() if k.startswith("t_wall_nlp_"))
    iterations = int(own.get("iterations_count", stats.get("iter_count", 0)))
    row = {"solver": name, "status": str(stats.get("return_status")),
           "iterations": iterations, "wall_s": wall, "evaluations_s": evaluations,
           "rest_ms_per_iteration": 1e3 * (wall - evaluations) / max(iterations, 1),
           "search_direction_s": own.get("compute_sd_time"), "cost": float(solution["f"])}
    direction = "-" if own.get("compute_sd_time") is None else f"{own['compute_sd_time']:.2f}"
    print(f"| {name} | {row['status']} | {iterations} | {wall:.2f} | {evaluations:.2f} | "
          f"{row['rest_ms_per_iteration']:.0f} | {direction} | {row['cost']:.5f} |", flush=True)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-iter", type=int, default=200)
    parser.add_argument("--mu-init", type=float, default=1e-6)
    parser.add_argument("--convexify", default=None,
                        help="CasADi's convexify_strategy for fatrop's Hessian blocks")
    parser.add_argument("--print-level", type=int, default=0)
    parser.add_argument("--json", metavar="NAME")
    args = parser.parse_args()
    call, nlp, node = captured_replan()
    began = time.perf_counter()
    stages, structure, lift = lifted(nlp, node)
    print(f"lifted in {time.perf_counter() - began:.1f} s: {structure['N'] + 1} stages, "
          f"states {min(structure['nx'])}-{max(structure['nx'])}, controls "
          f"{min(structure['nu'])}-{max(structure['nu'])}; {stages['x'].shape[0]} unknowns, "
          f"{stages['g'].shape[0]} rows (the planner's NLP: {nlp['x'].shape[0]}, "
          f"{nlp['g'].shape[0]})")
    at = lift(call["x0"], call["lbx"], call["ubx"], call["duals"]["lam_x0"], call["lbg"],
              call["ubg"], call["duals"]["lam_g0"])
    options = {"structure_detection": "manual", **structure, "expand": True,
               "print_time": False,
               "fatrop": {"print_level": args.print_level, "tol": 1e-8,
                          "max_iter": args.max_iter, "mu_init": args.mu_init,
                          "bound_push": 1e-9, "bound_frac": 1e-9}}
    if args.convexify:
        options.update(convexify_strategy=args.convexify, convexify_margin=1e-7)
    began = time.perf_counter()
    fatrop = ca.nlpsol("replan_fatrop", "fatrop", stages, options)
    print(f"fatrop's instance built in {time.perf_counter() - began:.1f} s")
    print("| solver | status | iterations | wall s | evaluations s | rest ms an iteration "
          "| search directions s | J |\n|---|---|---|---|---|---|---|---|")
    rows = [timed("IPOPT (the planner's instance)", call["solver"], x0=call["x0"],
                  p=call["p"], lbx=call["lbx"], ubx=call["ubx"], lbg=call["lbg"],
                  ubg=call["ubg"], **call["duals"]),
            timed("fatrop, lifted", fatrop, p=call["p"], **at)]
    if args.json:
        from results_io import write_results

        print(write_results(args.json, rows, {"structure": structure,
                                              "convexify": args.convexify,
                                              "mu_init": args.mu_init}))


if __name__ == "__main__":
    main()
