"""Sweep the settings the paper does not give (nodes per phase, base time step) for its
gait: walker3d, step length 0.6338 m, minimal kinetic energy. Prints one row per setting.

Usage:
  .venv/bin/python benchmarks/paper_sweep.py [--intervals 6 8 10] [--dt 0.01 0.0125]
  .venv/bin/python benchmarks/paper_sweep.py --intervals 4 6 8 12 16 --half-cycle 0.39
  .venv/bin/python benchmarks/paper_sweep.py --intervals 8 --set torque_regularisation=1e-5

--set NAME=VALUE (repeatable; VALUE is JSON, e.g. joint_limits={} or torso_lean_max=0)
overrides a gait option of the scene for every row.

With --half-cycle T the base time step is T / (5 * intervals - 1): the half cycle spans
nodes 0..N-1 (paper eqs. 7-9), so at sigma = 1 it lasts T for every row, and each row
discretises the same problem more finely: speed against discretisation error. The
error column is |J - J_finest| / J_finest against the row with the most intervals, and the
observed order is log(e_i / e_j) / log(h_i / h_j) between neighbouring rows.
Each row is a cold solve in a new Planner (build + solve; 1-3 min for walker3d on 2 cores).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="walker3d")
    parser.add_argument("--intervals", type=int, nargs="+", default=[6, 8, 10])
    parser.add_argument("--dt", type=float, nargs="+", default=[0.01])
    parser.add_argument("--compile", action=argparse.BooleanOptionalAction, default=True,
                        help="compiled derivatives (default; --no-compile: CasADi's)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="override a gait option (VALUE in JSON)")
    parser.add_argument("--half-cycle", type=float,
                        help="s at sigma = 1; base time step = this / (intervals in all phases - 1)")
    parser.add_argument("--json", metavar="NAME",
                        help="also write the rows to benchmarks/results/NAME.json")
    args = parser.parse_args()
    overrides = {}
    for item in args.set:
        name, _, value = item.partition("=")
        overrides[name] = json.loads(value)
    scene = load_scene(args.scene)
    print(f"# {args.scene} sweep, {time.strftime('%Y-%m-%d %H:%M')}; paper (walker3d): "
          "J = 41.2256 J s, T = 0.5988 s, sigma = 1.5, 1.5, 1.4889, 1.4724")
    rows = []
    for n in args.intervals:
        phases = len(scene.gait.phases)
        for dt in ([args.half_cycle / (phases * n - 1)] if args.half_cycle else args.dt):
            s = dataclasses.replace(
                settings_for(scene, intervals_per_phase=n, compiled=args.compile, **overrides),
                base_time_step=dt)
            r = plan_once(Planner(), scene, s)
            rows.append((n, dt, r))
            print(f"# done: {n} intervals, dt {dt:.5g}: {r.message}", flush=True)
    finest = max(rows, key=lambda row: row[0])[2].cost_value
    print("| intervals/phase | base dt s | success | J (J s) | 2 J | T (s) | sigma | iterations "
          "| build s | solve s | rel. error of J | order |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    previous = None
    for n, dt, r in rows:
        sigma = ", ".join(f"{x:.4f}" for x in r.phase_scaling)
        error = abs(r.cost_value - finest) / abs(finest)
        order = ""
        if args.half_cycle and previous and error > 0 and previous[1] > 0:
            order = f"{math.log(previous[1] / error) / math.log(previous[0] / dt):.2f}"
        previous = (dt, error)
        print(f"| {n} | {dt:.5g} | {r.success} | {r.cost_value:.4f} | {2 * r.cost_value:.4f} | "
              f"{r.duration:.4f} | {sigma} | {r.stats.iterations} | {r.stats.build_time:.1f} | "
              f"{r.stats.solve_time:.1f} | {error:.2e} | {order} |", flush=True)
    if args.json:
        from results_io import write_results

        print(write_results(args.json, [
            {"intervals": n, "base_time_step": dt, "success": r.success, "cost": r.cost_value,
             "duration": r.duration, "phase_scaling": list(r.phase_scaling),
             "iterations": r.stats.iterations} for n, dt, r in rows],
            {"scene": args.scene, "overrides": overrides, "compiled": args.compile}))


if __name__ == "__main__":
    main()
