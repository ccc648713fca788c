"""Warm re-plans from a stored plan against cold starts, for requests far from it.

Usage: .venv/bin/python benchmarks/replan.py [--scene walker2d] [--no-compile]

One Planner plans the scene's default gait (cold), then each request (a step length or a
friction coefficient) twice: warm, from that stored plan only (the planner's store is
reset to it first), and cold, from the kinematic guess. Prints success, iterations, solve
time, cost and how the solve started (the result's initial_guess metadata says when the
inertia-free attempt of a cold start failed and IPOPT's inertia test took over).
"""

from __future__ import annotations

import argparse
import platform
import time

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once

REQUESTS = [("step_length", 0.45), ("step_length", 0.85), ("friction_coefficient", 0.5),
            ("friction_coefficient", 1.2)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="walker2d")
    parser.add_argument("--compile", action=argparse.BooleanOptionalAction, default=True,
                        help="compiled derivatives (default; --no-compile: CasADi's)")
    parser.add_argument("--json", metavar="NAME",
                        help="also write the rows to benchmarks/results/NAME.json")
    args = parser.parse_args()
    print(f"# {platform.node()} {platform.processor() or platform.machine()} "
          f"{time.strftime('%Y-%m-%d %H:%M')}, {args.scene}")
    scene = load_scene(args.scene)
    planner = Planner()
    base = plan_once(planner, scene, settings_for(scene, compiled=args.compile))
    print(f"default plan: success {base.success}, {base.stats.iterations} iterations, "
          f"J {base.cost_value:.4f}")
    built = next(iter(planner._built.values()))
    stored = list(built.stored)
    rows = []
    print("| request | start | success | iterations | solve s | J | how |")
    print("|---|---|---|---|---|---|---|")
    for name, value in REQUESTS:
        s = settings_for(scene, compiled=args.compile, **{name: value})
        for warm in (True, False):
            built.stored[:] = stored
            r = plan_once(planner, scene, s, warm_start=warm)
            print(f"| {name} {value} | {'warm' if warm else 'cold'} | {r.success} | "
                  f"{r.stats.iterations} | {r.stats.solve_time:.2f} | {r.cost_value:.4f} | "
                  f"{r.settings.get('initial_guess', r.message)} |", flush=True)
            rows.append({"field": name, "value": value, "start": "warm" if warm else "cold",
                         "success": r.success, "iterations": r.stats.iterations,
                         "solve_s": r.stats.solve_time, "cost": r.cost_value})
    if args.json:
        from results_io import write_results

        print(write_results(args.json, rows, {
            "scene": args.scene, "compiled": args.compile, "default_cost": base.cost_value,
            "default_iterations": base.stats.iterations}))


if __name__ == "__main__":
    main()
