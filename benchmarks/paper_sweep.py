"""Sweep the settings the paper does not give (nodes per phase, base time step) for its
gait: walker3d, step length 0.6338 m, minimal kinetic energy. Prints one row per setting.

Usage: .venv/bin/python benchmarks/paper_sweep.py [--intervals 6 8 10] [--dt 0.01 0.0125]
Each row is a cold solve (build + solve, about 1.5-3 min for walker3d on 2 cores).
"""

from __future__ import annotations

import argparse
import dataclasses
import time

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--intervals", type=int, nargs="+", default=[6, 8, 10])
    parser.add_argument("--dt", type=float, nargs="+", default=[0.01])
    args = parser.parse_args()
    scene = load_scene("walker3d")
    print(f"# walker3d sweep, {time.strftime('%Y-%m-%d %H:%M')}; paper: J = 41.2256 J s, "
          "T = 0.5988 s, sigma = 1.5, 1.5, 1.4889, 1.4724")
    print("| intervals/phase | base dt s | success | J (J s) | 2 J | T (s) | sigma | iterations |")
    print("|---|---|---|---|---|---|---|---|")
    for n in args.intervals:
        for dt in args.dt:
            s = dataclasses.replace(settings_for(scene, intervals_per_phase=n), base_time_step=dt)
            r = Planner().plan(scene, s)
            sigma = ", ".join(f"{x:.4f}" for x in r.phase_scaling)
            print(f"| {n} | {dt} | {r.success} | {r.cost_value:.4f} | {2 * r.cost_value:.4f} | "
                  f"{r.duration:.4f} | {sigma} | {r.stats.iterations} |", flush=True)


if __name__ == "__main__":
    main()
