"""Starts from standing and stops to standing (issue #62): iterations, time, J and the
verifier's verdict, one and two half cycles.

Usage: .venv/bin/python benchmarks/start_stop.py [--scene walker3d] [--halves 1 2]
       [--json NAME]

One process, one Planner (derivatives compiled, no warm-start store): the scene's default
gait is planned cold and certified (`transitions.planned_gait`), then for each K a start from the scene's standing pose
(`standing_start`: its start phases, then K half cycles onto the gait, then one of the
gait's) and a stop from the gait's first node (K half cycles, then the scene's stop phases,
at rest), each from its guess (`transitions.transition_start`; nothing re-planned).
"solve s" is IPOPT's time; "answer s" the whole call as a user meets it (the gait found
in the planner, the transition built on its first use, solved, joined, certified).
Threads: one (OPENBLAS_NUM_THREADS=1, the package's default). The machine and its load
are printed.
"""

from __future__ import annotations

import argparse
import time

from gait_planner.ocp.transition import StartError, standing_start
from gait_planner.transitions import plan_transition
from transitions import planned_gait, verdict


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="walker3d")
    parser.add_argument("--halves", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--json", metavar="NAME",
                        help="also write the rows to benchmarks/results/NAME.json")
    args = parser.parse_args()
    scene, settings, planner, gait = planned_gait(args.scene)
    print(f"gait: {gait.stats.iterations} iterations, J {gait.cost_value:.5f}, "
          f"half cycle {gait.duration:.3f} s")
    rows = []
    print("| motion | K | converged | iterations | solve s | answer s | J (J s) | duration s "
          "| checks |")
    print("|---|---|---|---|---|---|---|---|---|")
    for halves in args.halves:
        for motion in ("from standing", "stop"):
            began = time.perf_counter()
            try:
                r = plan_transition(planner, scene, settings,
                                    standing_start(scene) if motion == "from standing"
                                    else None, steps=1, halves=halves,
                                    stop=motion == "stop", from_last=False)
            except StartError as err:
                print(f"| {motion} | {halves} | refused: {err} |")
                continue
            answer = time.perf_counter() - began
            row = {"motion": motion, "halves": halves, "success": r.success,
                   "iterations": r.stats.iterations, "solve_s": r.stats.solve_time,
                   "answer_s": answer, "cost": r.cost_value, "duration_s": r.duration,
                   "checks": verdict(r)}
            rows.append(row)
            print(f"| {motion} | {halves} | {r.success} | {r.stats.iterations} | "
                  f"{r.stats.solve_time:.2f} | {answer:.1f} | {r.cost_value:.4f} | "
                  f"{r.duration:.3f} | {row['checks']} |", flush=True)
    if args.json:
        from results_io import write_results

        print(write_results(args.json, rows, {
            "scene": args.scene, "gait_cost": gait.cost_value,
            "gait_iterations": gait.stats.iterations}))


if __name__ == "__main__":
    main()
