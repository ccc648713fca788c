"""Run the benchmarks and rewrite benchmarks/REPORT.md (`make bench`, `make bench-quick`).

    .venv/bin/python benchmarks/bench.py            # everything (over an hour on 2 cores)
    .venv/bin/python benchmarks/bench.py --quick    # smoke run (~5 min): small cases only,
                                                    # results and report in build/bench-quick/

Each script runs in a fresh process (as a user meets it) and writes its rows to
benchmarks/results/<name>.json; then `report.py` writes REPORT.md from those files.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

FULL = [
    ["model_size.py", "--compiled"],
    ["cold_solve.py"],
    ["node_latency.py"],
    ["request_sweep.py"],
    ["any_request.py"],
    ["work_precision.py"],
    ["hard_cases.py", "--time-limit", "45"],
    ["integrators.py", "--long-steps", "30000"],
    ["walk.py"],
    ["model_error.py"],
    ["smoothness.py"],
    ["gait_trends.py"],
    ["gait_library.py"],
    ["robots.py"],
]
QUICK = [
    ["model_size.py", "--quick", "--compiled"],
    ["cold_solve.py", "--scenes", "walker2d", "--runs", "2"],
    ["work_precision.py", "--quick"],
    ["hard_cases.py", "--quick", "--time-limit", "20"],
    ["integrators.py", "--quick"],
    ["walk.py", "--quick"],
    ["model_error.py", "--quick"],
    ["smoothness.py", "--quick"],
    ["gait_trends.py", "--quick"],
    ["gait_library.py", "--quick"],
    ["robots.py", "--quick"],
    ["any_request.py", "--scene", "walker2d", "--requests", "5"],
]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    failed, env = [], dict(os.environ)
    if args.quick:  # a smoke run: its results and report go to build/, not over the report's
        env["GAIT_PLANNER_BENCH_RESULTS"] = str(HERE.parent / "build" / "bench-quick")
    for script, *options in QUICK if args.quick else FULL:
        start = time.perf_counter()
        print(f"== {script} {' '.join(options)}", flush=True)
        code = subprocess.run([sys.executable, str(HERE / script), *options], cwd=HERE.parent,
                              env=env).returncode
        print(f"== {script}: exit {code} after {time.perf_counter() - start:.0f} s", flush=True)
        if code:
            failed.append(script)
    subprocess.run([sys.executable, str(HERE / "report.py")], check=True, env=env)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
