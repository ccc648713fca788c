"""Cold and warm solves as a user meets them: each run a fresh Python process that builds the
scene's default problem (compiled derivative elements from the cache), plans it cold from
the kinematic guess, then re-plans warm with the step length +2 %.

    .venv/bin/python benchmarks/cold_solve.py                      # walker3d and walker2d, 5 runs
    .venv/bin/python benchmarks/cold_solve.py --scenes walker2d --runs 3

Per run: process start to planner ready (imports and build), the cold plan's time (guess and
IPOPT), its iterations, and the warm re-plan; medians over the runs. Then one more process
per scene with IPOPT's timers on (`print_timing_statistics`, to a file; they cost the plan
0-5 %, so the timed runs go without): the cold plan's time per iteration split into
function and derivative evaluation, the primal-dual system (MUMPS's factorisations and
solves with IPOPT's residuals around them) and the rest of IPOPT (line search, barrier
update, vector operations, the progress callback), and the time outside IPOPT (the guess,
the result), summed over the plan's IPOPT calls. Rows to benchmarks/results/cold_solve.json.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

import numpy as np

CHILD = """
import dataclasses, json, os, re, tempfile, time
start = time.perf_counter()
from gait_planner.model.loader import load_scene
from gait_planner.ocp import solve
from gait_planner.ocp.settings import settings_for
from gait_planner.strategies import plan_once
timers = os.path.join(tempfile.mkdtemp(), "ipopt.out")
for options in solve.VARIANTS.values() if {timers} else ():  # IPOPT's summary and timers
    options.update({{"ipopt.output_file": timers, "ipopt.file_print_level": 3,
                    "ipopt.file_append": "yes", "ipopt.print_timing_statistics": "yes"}})
scene = load_scene({scene!r})
settings = settings_for(scene, compiled=True)
planner = solve.Planner()
planner.prepare(scene, settings)
ready = time.perf_counter() - start
cold = plan_once(planner, scene, settings, warm_start=False)
text = open(timers).read() if {timers} else ""
split = {{key: sum(float(v) for v in re.findall(name + r"\\.*:.*?wall:\\s*([0-9.]+)\\)", text))
         for key, name in (("ipopt", "OverallAlgorithm"), ("kkt", "PDSystemSolverTotal"),
                           ("evaluation", "Function Evaluations"))}}
warm = plan_once(planner, scene,
                 dataclasses.replace(settings, step_length=1.02 * settings.step_length))
print(json.dumps({{"ready_s": ready,
    "cold_s": cold.stats.solve_time, "cold_iterations": cold.stats.iterations,
    "cold_evaluation_s": cold.stats.evaluation_time, "cold_success": cold.success,
    **({{"cold_ipopt_s": split["ipopt"], "cold_kkt_s": split["kkt"],
        "cold_ipopt_evaluation_s": split["evaluation"]}} if {timers} else {{}}),
    "cost": cold.cost_value, "warm_s": warm.stats.solve_time,
    "warm_iterations": warm.stats.iterations, "warm_success": warm.success}}))
"""


def one_run(scene: str, timers: bool = False) -> dict:
    """A fresh process; with `timers`, IPOPT's timers split the cold plan's time."""
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", CHILD.format(scene=scene, timers=timers)],
                         capture_output=True, text=True, check=True)
    row = json.loads(out.stdout.strip().splitlines()[-1])
    row["process_s"] = time.perf_counter() - start
    row["cold_per_iteration_ms"] = 1e3 * row["cold_s"] / max(row["cold_iterations"], 1)
    row["cold_evaluation_share"] = row["cold_evaluation_s"] / row["cold_s"]
    row["timers"] = timers
    if timers:
        per_iteration = 1e3 / max(row["cold_iterations"], 1)
        row["cold_evaluation_ms"] = per_iteration * row["cold_ipopt_evaluation_s"]
        row["cold_kkt_ms"] = per_iteration * row["cold_kkt_s"]
        row["cold_other_ipopt_ms"] = per_iteration * (row["cold_ipopt_s"] - row["cold_kkt_s"]
                                                      - row["cold_ipopt_evaluation_s"])
        row["cold_outside_ipopt_s"] = row["cold_s"] - row["cold_ipopt_s"]
    return row


def run(scenes=("walker3d", "walker2d"), runs: int = 5) -> list[dict]:
    rows = []
    for scene in scenes:
        for i in range(runs):
            rows.append({"scene": scene, "run": i, **one_run(scene)})
            r = rows[-1]
            print(f"{scene} run {i}: ready {r['ready_s']:.2f} s, cold {r['cold_s']:.2f} s "
                  f"({r['cold_iterations']} it, {r['cold_per_iteration_ms']:.1f} ms/it, "
                  f"evaluation {100 * r['cold_evaluation_share']:.0f} %), warm {r['warm_s']:.3f} s "
                  f"({r['warm_iterations']} it), J {r['cost']:.6f}", flush=True)
        rows.append({"scene": scene, "run": runs, **one_run(scene, timers=True)})
        r = rows[-1]
        print(f"{scene} with IPOPT's timers: cold {r['cold_s']:.2f} s, per iteration evaluation "
              f"{r['cold_evaluation_ms']:.1f} ms, KKT {r['cold_kkt_ms']:.1f} ms, rest of IPOPT "
              f"{r['cold_other_ipopt_ms']:.1f} ms; outside IPOPT {r['cold_outside_ipopt_s']:.3f} s",
              flush=True)
    return rows


def medians(rows: list[dict]) -> dict[str, dict]:
    out = {}
    for scene in dict.fromkeys(r["scene"] for r in rows):
        mine = [r for r in rows if r["scene"] == scene and not r.get("timers")]
        split = [r for r in rows if r["scene"] == scene and r.get("timers")]
        out[scene] = {k: float(np.median([r[k] for r in mine])) for k in
                      ("ready_s", "cold_s", "cold_iterations", "cold_per_iteration_ms",
                       "cold_evaluation_share", "warm_s", "warm_iterations")}
        out[scene].update({k: float(np.median([r[k] for r in split])) for k in
                           ("cold_evaluation_ms", "cold_kkt_ms", "cold_other_ipopt_ms",
                            "cold_outside_ipopt_s") if split})
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", nargs="+", default=["walker3d", "walker2d"])
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    from results_io import write_results
    rows = run(args.scenes, args.runs)
    summary = medians(rows)
    for scene, m in summary.items():
        print(f"{scene} medians: " + ", ".join(f"{k} {v:.3g}" for k, v in m.items()))
    print(write_results("cold_solve", rows, {"medians": summary}))


if __name__ == "__main__":
    main()
