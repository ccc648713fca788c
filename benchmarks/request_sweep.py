"""Cold plans over a spread of requests: one process per scene plans the scene cold from the
kinematic guess at 5 step lengths times 2 friction coefficients (compiled derivatives,
no warm starts) and reports each plan's iterations, solve time and J, and their totals.

    .venv/bin/python benchmarks/request_sweep.py                  # walker3d
    .venv/bin/python benchmarks/request_sweep.py --scenes walker2d walker3d

Why: a cold solve's iteration count changes with round-off (a change that leaves the NLP's
mathematics alone but adds the same numbers in another order took walker3d's default
request from 64 to 67 iterations, the 0.8 m step from 101 to 234 and the 0.45 m step at
mu 0.6 from 178 to 56), so one request cannot tell a faster formulation from a luckier
one; the total over these ten can (benchmarks/HISTORY.md). Rows to
benchmarks/results/request_sweep.json.
"""

from __future__ import annotations

import argparse
import time

from gait_planner.model.loader import load_scene  # first: it pins numpy's BLAS kernels
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from results_io import write_results

STEPS = (0.45, 0.55, 0.6, 0.7, 0.8)  # m; walker3d's scene step is 0.6338 m
FRICTION = (0.3, 0.6)
TIME_LIMIT = 60.0  # s per plan


def sweep(name: str) -> list[dict]:
    scene = load_scene(name)
    planner = Planner()
    planner.prepare(scene, settings_for(scene, compiled=True))
    rows = []
    for step in STEPS:
        for mu in FRICTION:
            s = settings_for(scene, step_length=step, friction_coefficient=mu,
                             max_solve_time=TIME_LIMIT, compiled=True)
            start = time.perf_counter()
            result = plan_once(planner, scene, s, warm_start=False)
            rows.append({"scene": name, "step_length": step, "friction_coefficient": mu,
                         "success": result.success, "iterations": result.stats.iterations,
                         "solve_s": time.perf_counter() - start,
                         "cost": result.cost_value if result.success else None})
            print(f"{name} step {step} m, mu {mu}: {'converged' if result.success else 'failed'}"
                  f", {result.stats.iterations} iterations, {rows[-1]['solve_s']:.2f} s",
                  flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", nargs="+", default=["walker3d"])
    args = parser.parse_args()
    rows = [row for name in args.scenes for row in sweep(name)]
    totals = {}
    for name in args.scenes:
        mine = [r for r in rows if r["scene"] == name]
        totals[name] = {"converged": sum(r["success"] for r in mine), "requests": len(mine),
                        "iterations": sum(r["iterations"] for r in mine),
                        "solve_s": sum(r["solve_s"] for r in mine)}
        print(f"{name}: {totals[name]}")
    print(write_results("request_sweep", rows, {"totals": totals, "time_limit_s": TIME_LIMIT}))


if __name__ == "__main__":
    main()
