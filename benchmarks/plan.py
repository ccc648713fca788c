"""Cold and warm solve times of the gait optimisation, per scene.

Usage: .venv/bin/python benchmarks/plan.py [--scenes compass walker2d walker3d]

Cold: a new Planner builds the problem (CasADi SX expansion + exact Hessian: `build_s`) and
solves from the kinematic guess (`solve_s`, `iterations`; IPOPT's own split of the solve
time into function and derivative evaluations and the rest, i.e. mostly MUMPS, is
reported as `eval_share`). Warm: the same
Planner re-plans with the step length changed by +2 % from the stored plan. Ratios are
against the cold solve of the same scene in the same process.
"""

from __future__ import annotations

import argparse
import platform
import time

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner


def bench(name: str) -> dict:
    scene = load_scene(name)
    settings = settings_for(scene)
    planner = Planner()
    start = time.perf_counter()
    cold = planner.plan(scene, settings)
    wall_cold = time.perf_counter() - start
    warm_settings = settings_for(scene, step_length=settings.step_length * 1.02)
    warm = planner.plan(scene, warm_settings)
    return {
        "scene": name, "cold_ok": cold.success, "build_s": cold.stats.build_time,
        "cold_solve_s": cold.stats.solve_time, "cold_iterations": cold.stats.iterations,
        "cold_eval_share": cold.stats.evaluation_time / cold.stats.solve_time,
        "cold_wall_s": wall_cold, "warm_ok": warm.success, "warm_solve_s": warm.stats.solve_time,
        "warm_iterations": warm.stats.iterations,
        "warm_eval_share": warm.stats.evaluation_time / warm.stats.solve_time,
        "warm_over_cold": warm.stats.solve_time / cold.stats.solve_time,
        "cost": cold.cost_value, "duration": cold.duration,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["compass", "walker2d", "walker3d"])
    args = parser.parse_args()
    print(f"# {platform.node()} {platform.processor() or platform.machine()} "
          f"{time.strftime('%Y-%m-%d %H:%M')}")
    rows = [bench(name) for name in args.scenes]
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for row in rows:
        print("| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v)
                                for v in row.values()) + " |")


if __name__ == "__main__":
    main()
