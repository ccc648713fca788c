"""What a smaller model buys: the size of each scene's gait NLP against its build and solve
times.

    .venv/bin/python benchmarks/model_size.py              # compass, walker2d, walker3d
    .venv/bin/python benchmarks/model_size.py --quick      # compass and walker2d
    .venv/bin/python benchmarks/model_size.py --compiled   # compiled derivative elements

Per scene (config/scenes/*.yaml), at the scene's default request (`settings_for(scene)`,
CasADi derivatives unless --compiled), one new `Planner`:

* model: bodies, configuration entries k, degrees of freedom, joint torque components;
* NLP (the built problem's IPOPT inputs): intervals N, variables, constraints, nonzeros of
  the constraint Jacobian and of the upper triangle of the Hessian of the Lagrangian (the
  sparsity patterns of the jac_g and hess_lag Functions the solver is given);
* build_s: building the problem (`Planner.prepare`: transcription, expanded SX graph,
  derivatives; with --compiled also compiling, unless ~/.cache/gait_planner has the
  libraries);
* a cold plan (kinematic guess, then IPOPT): solve_s (guess and solve, `stats.solve_time`),
  IPOPT iterations, solve time per iteration, success, J.

Writes benchmarks/results/model_size.json (with --compiled: model_size_compiled.json) and
prints a table.
"""

from __future__ import annotations

import argparse
import logging
import time


from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from results_io import write_results

SCENES = ("compass", "walker2d", "walker3d")


def measure(name: str, compiled: bool = False) -> dict:
    """One scene's row (see the module docstring)."""
    scene = load_scene(name)
    settings = settings_for(scene, compiled=compiled)
    mb = Multibody(scene)
    planner = Planner()
    start = time.perf_counter()
    used = planner.prepare(scene, settings)
    build = time.perf_counter() - start
    size = planner.problem_size(scene, settings)  # the problem prepare() built
    result = plan_once(planner, scene, settings, warm_start=False)
    return {
        "scene": name, "derivatives": used, "bodies": mb.nb, "k": mb.k, "dof": mb.ndof,
        "torques": mb.nt, **size,
        "build_s": build, "solve_s": result.stats.solve_time,
        "iterations": result.stats.iterations,
        "per_iteration_ms": 1e3 * result.stats.solve_time / max(1, result.stats.iterations),
        "success": result.success,
        "cost": result.cost_value,
    }


def run(quick: bool = False, compiled: bool = False) -> list[dict]:
    """Rows of compass and walker2d (quick) or of every scene in SCENES."""
    return [measure(name, compiled) for name in (SCENES[:2] if quick else SCENES)]


def print_table(rows: list[dict]) -> None:
    print(f"{'scene':>9} {'dof':>4} {'N':>3} {'vars':>6} {'cons':>6} {'jac nnz':>8} "
          f"{'hess nnz':>9} {'build s':>8} {'solve s':>8} {'iter':>5} {'ms/it':>6} {'ok':>3} "
          f"{'J':>9}")
    for r in rows:
        print(f"{r['scene']:>9} {r['dof']:>4} {r['intervals']:>3} {r['variables']:>6} "
              f"{r['constraints']:>6} {r['jacobian_nonzeros']:>8} "
              f"{r['hessian_nonzeros']:>9} {r['build_s']:>8.2f} {r['solve_s']:>8.2f} "
              f"{r['iterations']:>5} {r['per_iteration_ms']:>6.1f} "
              f"{'y' if r['success'] else 'n':>3} {r['cost']:>9.4f}")
    print(f"(derivatives: {rows[0]['derivatives']}; hess nnz: upper triangle of the Hessian "
          "of the Lagrangian; solve s includes the kinematic guess)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="compass and walker2d only")
    parser.add_argument("--compiled", action="store_true",
                        help="compiled derivative elements (SolveOptions.compiled)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)  # the paper's torso inertia warns on load
    rows = run(args.quick, args.compiled)
    print_table(rows)
    path = write_results("model_size_compiled" if args.compiled else "model_size", rows,
                         {"quick": args.quick, "compiled": args.compiled})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
