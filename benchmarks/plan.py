"""Cold and warm solve times of the gait optimisation, per scene and derivative mode.

Usage: .venv/bin/python benchmarks/plan.py [--scenes compass walker2d walker3d]
                                           [--modes casadi compiled] [--spread 0.9 0.95 1 1.05 1.1]

For each scene and mode one Planner builds the problem (`build_s`: CasADi SX expansion and
derivatives; in "compiled" mode also the C compilation of the derivative elements, unless
the libraries are cached already from an earlier run) and then solves cold, from the
kinematic guess, at the scene's step length times each factor of --spread. Cold solve
iteration counts of this non-convex problem change with round-off (another mode, another
step length, another BLAS), so the table gives the median, least and largest solve time
and iterations over that spread, how many converged, and IPOPT's split of the solve time
into function and derivative evaluations (`eval_share`; the rest is mostly MUMPS). The
paper's case (factor 1) is also given on its own. Warm: the same Planner re-plans with
the step length changed by +2 % from its plan for factor 1.

Modes: "casadi" (CasADi's derivatives of the whole SX graph, in its virtual machine) and
"compiled" (per-node elements compiled to C, `gait_planner.ocp.derivatives`). Ratios are
against the "casadi" mode of the same scene in the same process.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once


def bench(name: str, mode: str, spread: list[float]) -> dict:
    scene = load_scene(name)
    nominal = settings_for(scene, compiled=mode == "compiled")
    planner = Planner()
    start = time.perf_counter()
    planner.prepare(scene, nominal)
    build = time.perf_counter() - start
    cold = {}
    for factor in spread:
        s = settings_for(scene, step_length=nominal.step_length * factor,
                         compiled=nominal.solve.compiled)
        cold[factor] = plan_once(planner, scene, s, warm_start=False)
    paper = cold.get(1.0) or plan_once(planner, scene, nominal, warm_start=False)
    warm = plan_once(planner, scene, settings_for(scene, step_length=nominal.step_length * 1.02,
                                                  compiled=nominal.solve.compiled))
    times = [r.stats.solve_time for r in cold.values()]
    its = [r.stats.iterations for r in cold.values()]
    return {
        "scene": name, "derivatives": mode, "build_s": build,
        "cold_ok": f"{sum(r.success for r in cold.values())}/{len(cold)}",
        "cold_solve_s_median": statistics.median(times), "cold_solve_s_min": min(times),
        "cold_solve_s_max": max(times), "cold_iterations_median": statistics.median(its),
        "cold_iterations_range": f"{min(its)}-{max(its)}",
        "cold_eval_share": sum(r.stats.evaluation_time for r in cold.values()) / sum(times),
        "paper_case_s": paper.stats.solve_time, "paper_case_iterations": paper.stats.iterations,
        "paper_case_cost": paper.cost_value,
        "warm_ok": warm.success, "warm_solve_s": warm.stats.solve_time,
        "warm_iterations": warm.stats.iterations,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["compass", "walker2d", "walker3d"])
    parser.add_argument("--modes", nargs="+", default=["casadi", "compiled"])
    parser.add_argument("--spread", nargs="+", type=float, default=[0.9, 0.95, 1.0, 1.05, 1.1])
    args = parser.parse_args()
    print(f"# {platform.node()} {platform.processor() or platform.machine()} "
          f"{time.strftime('%Y-%m-%d %H:%M')}")
    rows = []
    for name in args.scenes:
        baseline = None
        for mode in args.modes:
            row = bench(name, mode, args.spread)
            baseline = baseline or row
            row["median_over_casadi"] = row["cold_solve_s_median"] / baseline["cold_solve_s_median"]
            rows.append(row)
            print(row, flush=True)
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for row in rows:
        print("| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v)
                                for v in row.values()) + " |")


if __name__ == "__main__":
    main()
