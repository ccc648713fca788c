"""Gait libraries on Ray (`gait_planner.gaitlib`): plans per minute against workers,
continuation against independent cold plans, a simulated cluster, and the in-hull answer.

    .venv/bin/python benchmarks/gait_library.py            # ~10 min on 2 cores
    .venv/bin/python benchmarks/gait_library.py --quick    # a 3 x 2 walker2d grid, ~2 min

Rows of results/gait_library.json:
* "build": the walker2d grid `GRID` (27 plans: step length and slope; friction does not
  bind on level walks, so J would not change along it) built into a fresh folder with 1 and 2 local
  workers by continuation, and with 2 workers as independent cold plans: wall time (Ray's
  start apart), plans per minute, IPOPT iterations, failures, points whose recording
  fails the verifier.
* "cluster": the same grid on `ray.cluster_utils.Cluster` with 4 nodes of one CPU each,
  all on this machine: the build runs unchanged through an address, as on a real
  cluster; the 4 nodes share 2 cores, so this shows the scheduling and its overhead, not
  a speed-up, which needs more cores.
* "serve": walker3d's libraries `SERVE_GRIDS` (step length 5, 2.5 and 1.25 cm apart) built, then
  requests at the centres of their cells answered in one process as the node answers them
  (problem built, as after the node's first request): from the library
  (`gaitlib.serve.library_start`, then a warm plan), from the nearest single stored plan
  (the node without a library), and cold. Iterations and wall time (library_start
  included; library_start_s alone).
Figure gait_library.png: J over the walker2d grid, IPOPT iterations per point by
continuation and independently, and the serve times.
"""

from __future__ import annotations

import argparse
import itertools
import tempfile
import time
from pathlib import Path

import numpy as np

from gait_planner.gaitlib.build import build_library
from gait_planner.gaitlib.grid import parse_grid
from gait_planner.gaitlib.index import PLANS, LibraryIndex, Manifest
from gait_planner.gaitlib.serve import library_start
from gait_planner.model.loader import find_scene
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.problem import resolve
from gait_planner.request import plan_request
from gait_planner.verify import verify_recording
from results_io import figure_path, write_results

GRID = "step_length=0.40:0.80:0.05,slope=-5/0/5"
QUICK_GRID = "step_length=0.5/0.6/0.7,friction_coefficient=0.6/1.0"
SERVE_GRIDS = ("step_length=0.55:0.70:0.05,friction_coefficient=0.8/1.0",
               "step_length=0.55:0.70:0.025,friction_coefficient=0.8/1.0",
               "step_length=0.55:0.65:0.0125,friction_coefficient=0.8/1.0")


def _rows(folder: Path):
    index = LibraryIndex(folder)
    try:
        return index.rows()
    finally:
        index.close()


def build_row(kind: str, scene: str, grid: str, folder: Path, **options) -> dict:
    summary = build_library(folder, Manifest(scene, "", grid, {}), progress=lambda line: None,
                            **options)
    rows = _rows(folder)
    failing = [r.name for r in rows if r.status == "ok"
               and not verify_recording(folder / PLANS / r.mcap).ok]
    planning = summary.wall_time - summary.ray_start
    out = {"kind": kind, "scene": scene, "grid": grid, "points": summary.total,
           "workers": options.get("workers"), "continuation": options.get("continuation", True),
           "ray_start_s": summary.ray_start, "planning_s": planning,
           "plans_per_min": summary.planned / planning * 60.0,
           "iterations": summary.iterations, "failed": summary.failed,
           "cold_points": sum(r.start == "cold" for r in rows),
           "verifier_failures": failing}
    print(f"{kind:8s} {scene} workers {out['workers']} continuation {out['continuation']}: "
          f"{summary.planned} plans in {planning:.1f} s (+{summary.ray_start:.1f} s Ray), "
          f"{out['plans_per_min']:.1f}/min, {summary.iterations} iterations, "
          f"{summary.failed} failed, {len(failing)} fail the verifier", flush=True)
    return out


def cluster_row(grid: str, folder: Path) -> dict:
    from ray.cluster_utils import Cluster

    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    for _ in range(3):
        cluster.add_node(num_cpus=1)
    try:
        return build_row("cluster", "walker2d", grid, folder, address=cluster.address)
    finally:
        cluster.shutdown()


def serve_rows(folder: Path, grid_text: str) -> list[dict]:
    """Requests at the centres of the library's cells, three ways (module docstring)."""
    grid = parse_grid(grid_text)
    centres = [{f: 0.5 * (axis[i] + axis[i + 1]) for (f, axis), i in zip(grid.axes, index)}
               for index in itertools.product(*(range(n - 1) for n in grid.shape))]
    planner = Planner()
    first = resolve(plan_request(scene="walker3d", compiled=True,
                                 **grid.values(grid.indices()[0])), find_scene)
    scene, s = first.scene, first.settings
    planner.prepare(scene, s)  # every solver variant built, as the node does when it starts
    plan_once(planner, scene, s, warm_start=False)  # one plan stored: as the node after a request
    base = planner.stored_plans(scene, s)
    out = []
    for values in centres:
        problem = resolve(plan_request(scene="walker3d", compiled=True, **values), find_scene)
        scene, s = problem.scene, problem.settings
        row = {"kind": "serve", "scene": "walker3d", "serve_grid": grid_text, **values}
        for how in ("library", "nearest", "cold"):
            planner._build(scene, s).stored[:] = list(base)  # as the node after one request
            start = time.perf_counter()
            seed, note = (library_start(planner, folder, problem) if how == "library"
                          else (None, ""))
            started = time.perf_counter()
            result = plan_once(planner, scene, s, warm_start=how != "cold", seed=seed)
            row[f"{how}_s"] = time.perf_counter() - start
            if how == "library":
                row["library_start_s"] = started - start
            row[f"{how}_iterations"] = result.stats.iterations
            row[f"{how}_success"] = bool(result.success)
            row[f"{how}_cost"] = result.cost_value if result.success else None
            if how == "library":
                row["note"] = note
        print(f"serve {values}: library {row['library_iterations']} it {row['library_s']:.3f} s, "
              f"nearest {row['nearest_iterations']} it {row['nearest_s']:.3f} s, cold "
              f"{row['cold_iterations']} it {row['cold_s']:.2f} s", flush=True)
        out.append(row)
    return out


def figure(folders: dict[str, Path], serve: list[dict]) -> None:
    """J over step length per value of the grid's second axis (the continuation build),
    iterations per point of each build, and the in-hull answer times."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 3.9))
    rows = [r for r in _rows(folders["continuation"]) if r.status == "ok"]
    other = [k for k in rows[0].request if k != "step_length"][0] if rows else ""
    for value in sorted({r.request[other] for r in rows}):
        sel = sorted((r for r in rows if r.request[other] == value),
                     key=lambda r: r.request["step_length"])
        axes[0].plot([r.request["step_length"] for r in sel], [r.cost for r in sel], "o-",
                     label=f"{other} {value:g}")
    axes[0].set(xlabel="step length (m)", ylabel="J (J s)", title="walker2d library: cost")
    axes[0].legend(fontsize=8)
    for label, folder in folders.items():
        its = [r.iterations for r in _rows(folder)]
        axes[1].plot(range(len(its)), its, "o-" if label == "continuation" else "s--",
                     label=f"{label}: {sum(its)} in all")
    axes[1].set(xlabel="grid point", ylabel="IPOPT iterations",
                title="iterations per point (2 workers)")
    axes[1].legend(fontsize=8)
    if serve:
        x = np.arange(len(serve))
        for k, how in enumerate(("library", "nearest", "cold")):
            axes[2].bar(x + 0.27 * (k - 1), [r[f"{how}_s"] for r in serve], 0.27, label=how)
        axes[2].set_xticks(x, [f"{r['step_length']:.4g}\n{r['friction_coefficient']:g}"
                               for r in serve], fontsize=6)
        axes[2].set_xlabel("request: step length (m), mu; left the 5 cm grid, right 2.5 cm")
        axes[2].set_yscale("log")
        axes[2].set(ylabel="answer (s)", title="walker3d: in-hull answers")
        axes[2].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(figure_path("gait_library.png"), dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    grid = QUICK_GRID if args.quick else GRID
    rows: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="gait_library_") as tmp:
        root = Path(tmp)
        for workers in ((2,) if args.quick else (1, 2)):
            rows.append(build_row("build", "walker2d", grid, root / f"w{workers}",
                                  workers=workers))
        rows.append(build_row("build", "walker2d", grid, root / "independent", workers=2,
                              continuation=False))
        serve = []
        if not args.quick:
            rows.append(cluster_row(grid, root / "cluster"))
            for k, serve_grid in enumerate(SERVE_GRIDS):
                folder = root / f"walker3d-{k}"
                rows.append(build_row("build", "walker3d", serve_grid, folder, workers=2))
                serve += serve_rows(folder, serve_grid)
            rows += serve
        figure({"continuation": root / "w2", "independent": root / "independent"}, serve)
    write_results("gait_library", rows, {"grid": grid, "serve_grids": list(SERVE_GRIDS)})


if __name__ == "__main__":
    main()
