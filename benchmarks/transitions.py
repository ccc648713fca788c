"""Transitions from given states onto the periodic gait (issue #62): iterations, time, J
and the verifier's verdict, one and two half cycles, from the gait's own first node and
from seeded starts off it.

Usage: .venv/bin/python benchmarks/transitions.py [--scene walker3d] [--starts 6]
       [--seed 0] [--json NAME]

One process, one Planner (derivatives compiled, no warm-start store): the scene's default
gait is planned cold and certified, then each start is planned twice per transition length
K: from the gait ("gait": the guess of `transitions.transition_start`) and re-planned from
the previous start's transition ("last": `transitions.last_transition`, as a re-planning
loop would; the first start has no previous one). The starts: the gait's own first node
(`start_of_plan`), then `--starts` states drawn with the seed, each the first node moved
sideways by U(-2, 2) cm (3D) and turned about its stance heel at U(-0.1, 0.1) rad/s (roll
in 3D, pitch in the plane; the contacts stay on the ground). "solve s" is IPOPT's time of
the transition; "answer s" the whole call as a user meets it (the gait found in the
planner, the transition built on its first use, solved, joined, certified). Threads: one
(OPENBLAS_NUM_THREADS=1, the package's default). The machine and its load are printed.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.transition import start_of_plan, turned_start
from gait_planner.strategies import plan_certified
from gait_planner.transitions import plan_transition
from gait_planner.verify import verify_result


def planned_gait(name: str):
    """(scene, settings, planner, gait): the scene's default gait planned cold and
    certified in a new Planner (derivatives compiled, no warm-start store), after a line
    with the machine, the date, the load and the threads."""
    print(f"# {platform.node()} {platform.processor() or platform.machine()} "
          f"{time.strftime('%Y-%m-%d %H:%M')}, load {os.getloadavg()[0]:.2f}, {name}, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")
    scene = load_scene(name)
    settings = settings_for(scene, compiled=True)
    planner = Planner()
    gait, _ = plan_certified(planner, scene, settings, warm_start=False)
    return scene, settings, planner, gait


def verdict(result) -> str:
    """"passed", or the verifier's failures (a plan that converged) or the solver's
    message, cut to 120 characters."""
    if not result.success:
        return result.message[:120]
    report = verify_result(result)
    return "passed" if report.ok else "; ".join(report.failures)[:120]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="walker3d")
    parser.add_argument("--starts", type=int, default=6)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--halves", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--json", metavar="NAME",
                        help="also write the rows to benchmarks/results/NAME.json")
    args = parser.parse_args()
    scene, settings, planner, gait = planned_gait(args.scene)
    print(f"gait: {gait.stats.iterations} iterations, J {gait.cost_value:.5f}")
    rng = np.random.default_rng(args.seed)
    starts = [start_of_plan(gait)] + [
        turned_start(scene, start_of_plan(gait), rng.uniform(-0.02, 0.02),
                     rng.uniform(-0.1, 0.1))
        for _ in range(args.starts)]
    rows = []
    print("| K | start | from | converged | iterations | solve s | answer s | J / (K J_gait) "
          "| checks |")
    print("|---|---|---|---|---|---|---|---|---|")
    for halves in args.halves:
        for number, start in enumerate(starts):
            for origin in ("gait", "last") if number else ("gait",):
                if origin == "last":  # the previous start's transition, as a loop has it
                    plan_transition(planner, scene, settings, starts[number - 1], steps=2,
                                    halves=halves, from_last=False)
                began = time.perf_counter()
                r = plan_transition(planner, scene, settings, start, steps=2, halves=halves,
                                    from_last=origin == "last")
                answer = time.perf_counter() - began
                row = {"halves": halves, "start": start.origin, "from": origin,
                       "success": r.success, "iterations": r.stats.iterations,
                       "solve_s": r.stats.solve_time, "answer_s": answer,
                       "cost_ratio": r.cost_value / (halves * gait.cost_value),
                       "checks": verdict(r)}
                rows.append(row)
                print(f"| {halves} | {start.origin} | {origin} | {r.success} | "
                      f"{r.stats.iterations} | {r.stats.solve_time:.3f} | {answer:.2f} | "
                      f"{row['cost_ratio']:.4f} | {row['checks']} |", flush=True)
    for halves in args.halves:
        for origin in ("gait", "last"):
            chosen = [r for r in rows if r["halves"] == halves and r["from"] == origin
                      and r["success"]]
            if chosen:
                def median(key):
                    return statistics.median(r[key] for r in chosen)

                print(f"K={halves} from {origin}: median {median('iterations'):.0f} "
                      f"iterations, solve {median('solve_s'):.3f} s, "
                      f"answer {median('answer_s'):.2f} s "
                      f"({len(chosen)} converged)")
    if args.json:
        from results_io import write_results

        print(write_results(args.json, rows, {
            "scene": args.scene, "gait_cost": gait.cost_value,
            "gait_iterations": gait.stats.iterations, "seed": args.seed}))


if __name__ == "__main__":
    main()
