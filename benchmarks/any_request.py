"""Requests across a scene's ranges answered by one fresh process after `make setup` (issue
#39): 30 requests drawn at random (fixed seed) — a ramp within +-10 deg or stairs within
+-0.15 m (or level ground), a speed within 0.8-1.6 m/s or free durations, a friction
coefficient within 0.4-1.2, a step length within 0.4-0.9 m — each planned as the node plans
it, from (a copy of) the warm-start store `make setup` leaves (the default plan and its anchors: each
request continued from the nearest plan kept along a path of parameters,
`gait_planner.parameter_path`), and certified as the node certifies it
(`strategies.plan_certified`: refinement after a failed certificate included).

    .venv/bin/python benchmarks/any_request.py                  # walker3d, 30 requests
    .venv/bin/python benchmarks/any_request.py --cold           # each planned cold
    .venv/bin/python benchmarks/any_request.py --scene walker2d --requests 10
    .venv/bin/python benchmarks/any_request.py --library FOLDER  # the same, from a library

With --library (a gait library of the scene, `gait-planner library build`): a request inside
the library's grid starts from its neighbours' interpolation (`gaitlib.serve.library_start`,
as the node's parameter gait_library does; the time includes reading the library), every
other one is planned cold as with --cold. Rows to results/any_request_library.json, with
where each answer started.

Reports per request the time from the call to the certified answer, IPOPT iterations,
success, the certificate's verdict and whether anything was compiled (the planner's
"building: compiling" stage), and the median, p95 and max answer time. A request the
scene refuses before planning (`settings_for`: a speed its step cannot reach within the
durations, a stair beyond reach) is counted as refused, with its reason. Rows to
benchmarks/results/any_request.json (any_request_cold.json with --cold).
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from gait_planner.model.loader import load_scene  # first: it pins numpy's BLAS kernels
from gait_planner.gaitlib.index import read_manifest
from gait_planner.gaitlib.serve import library_start
from gait_planner.ocp.settings import SettingsError, settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.warm_starts import WarmStartStore
from gait_planner.problem import Problem
from gait_planner.request import plan_request
from gait_planner.strategies import plan_certified
from results_io import write_results

SEED = 39
TIME_LIMIT = 60.0  # s per request, as the node's default max_solve_time


def draw(rng: np.random.Generator) -> dict:
    """One request's options: ground (a third each level, ramp, stairs), speed (half of
    them), friction coefficient and step length."""
    ground = rng.integers(3)
    options = {"friction_coefficient": round(float(rng.uniform(0.4, 1.2)), 3),
               "step_length": round(float(rng.uniform(0.4, 0.9)), 3)}
    if ground == 1:
        options["slope"] = round(float(rng.uniform(-10.0, 10.0)), 2)
    elif ground == 2:
        options["step_height"] = round(float(rng.uniform(-0.15, 0.15)), 3)
    if rng.random() < 0.5:
        options["speed"] = round(float(rng.uniform(0.8, 1.6)), 3)
    return options


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="walker3d")
    parser.add_argument("--requests", type=int, default=30)
    parser.add_argument("--library", help="a gait library of the scene to answer from")
    parser.add_argument("--cold", action="store_true",
                        help="plan each request cold: no warm-start store, no path")
    args = parser.parse_args()
    scene = load_scene(args.scene)
    compiled: list[str] = []

    def stage(text: str) -> None:
        if text.startswith("building: compiling"):
            compiled.append(text)

    store = not (args.cold or args.library)
    # a copy of the store `make setup` left, so that this run's plans do not start the next
    library = None
    if store:
        copy = Path(tempfile.mkdtemp(prefix="any_request_"))
        if WarmStartStore().folder.is_dir():
            shutil.copytree(WarmStartStore().folder, copy / "plans")
        library = WarmStartStore(copy)
    planner = Planner(stage=stage, library=library)
    rng = np.random.default_rng(SEED)
    rows = []
    for i in range(args.requests):
        options = draw(rng)
        row = {"request": options}
        try:
            settings = settings_for(scene, compiled=True, max_solve_time=TIME_LIMIT, **options)
        except SettingsError as error:
            row.update(refused=str(error))
            rows.append(row)
            print(f"{i:2d} {options}: refused ({error})", flush=True)
            continue
        before = len(compiled)
        start = time.perf_counter()
        seed = None
        if args.library:
            problem = Problem(plan_request(scene=args.scene, **options), scene, settings)
            seed, row["library"] = library_start(planner, args.library, problem)
        result, cert = plan_certified(planner, scene, settings,
                                      warm_start=store or seed is not None, seed=seed)
        row.update(answer_s=time.perf_counter() - start, success=result.success,
                   start=result.settings.get("initial_guess", ""),
                   refinement=result.settings.get("refinement", ""),
                   iterations=result.stats.iterations, build_s=result.stats.build_time,
                   certified=bool(cert is not None and not cert.failures),
                   compiled=len(compiled) > before)
        rows.append(row)
        print(f"{i:2d} {options}: {'converged' if result.success else 'failed'}, "
              f"{row['iterations']} it, {row['answer_s']:.2f} s, certified {row['certified']}, "
              f"compiled {row['compiled']}", flush=True)
    answered = [r for r in rows if "answer_s" in r]
    times = np.array([r["answer_s"] for r in answered])
    totals = {"requests": len(rows), "refused": len(rows) - len(answered),
              "compilations": sum(r["compiled"] for r in answered),
              "converged": sum(r["success"] for r in answered),
              "certified": sum(r["certified"] for r in answered),
              "median_s": float(np.median(times)), "p95_s": float(np.percentile(times, 95)),
              "max_s": float(times.max()),
              "median_iterations": float(np.median([r["iterations"] for r in answered]))}
    if args.library:
        served = [r for r in answered if r["library"].startswith("started from")]
        totals.update(from_library=len(served), library_median_s=float(np.median(
            [r["answer_s"] for r in served])) if served else None)
    print(totals)
    name = ("any_request_library" if args.library else
            "any_request_cold" if args.cold else "any_request")
    print(write_results(name, rows,
                        {"scene": args.scene, "seed": SEED, "time_limit_s": TIME_LIMIT,
                         "start": "warm-start store" if store else "cold",
                         "totals": totals, "library": args.library,
                         "library_grid": read_manifest(Path(args.library)).grid
                         if args.library else None}))


if __name__ == "__main__":
    main()
