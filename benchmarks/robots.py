"""Robots planned from their URDF (issue #37, item 6): per robot of the example-robot-data
wheel (`robot_plan.ROBOTS`: Bolt, Unitree G1, Talos, iCub, Alexander, Romeo), the scene drafted
and planned as a user plans it, in fresh processes; G1's plan beside walker3d scaled to G1
and walker3d itself.

    .venv/bin/python benchmarks/robots.py                  # every robot, compiled and not
    .venv/bin/python benchmarks/robots.py --quick          # Bolt only, compiled
    .venv/bin/python benchmarks/robots.py --robots bolt --modes compiled casadi --no-counterpart

Per robot and derivative mode, one row from fresh processes (`robot_plan.py`):

* compiled: a process with $GAIT_PLANNER_CACHE an empty folder (the first build: the
  per-node derivative elements compiled with the C compiler), then a second process with
  that folder filled (the cached build); the second process's plan is the row's plan;
* casadi: one process, CasADi's derivatives of the whole SX graph (`--no-compile`).

Each process drafts the URDF, builds the problem (`Planner.prepare`: `build_s`; the
process's start to then: `ready_s`, imports included), plans it cold
(`pipeline.plan_and_record`: refined while the certificate asks; `plan_s` the request's
wall time, `solve_s` IPOPT's over every grid) and records it. The row: joints planned and
locked, the NLP's variables and constraints (the first grid), iterations, J, positive joint
work W+ and the cost of transport W+ / (m g s) (`robot_plan.measures`), the peak effort
and its largest share of the URDF's effort limit, the certificate, and the half cycles
walked by `gait-planner walk RUN.mcap --steps 10 --json` (its JSON, or its error line).

The counterpart table (`--counterpart ROBOT`, default g1 when it is benchmarked): the
robot's compiled plan, walker3d scaled to its leg length and mass (`scaled_walker.py`)
and walker3d, each compiled (cache: ~/.cache/gait_planner), with J, W+/(m g s), peak
torque, iterations, duration and speed.

The picture `robots.png`: each robot at the mid-step node of its plan, its own meshes
placed by the recording's /tf, as rerun draws it (`robot_picture.py`; needs Chromium).
Rows to benchmarks/results/robots.json.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from robot_picture import mid_step_picture
from robot_plan import ROBOTS, robots_folder

HERE = Path(__file__).resolve().parent
STEPS = 10  # half cycles walked


def child(name: str, out: Path, *, compiled: bool, cache: Path | None, time_limit: float,
          scaled_to: str | None = None) -> dict:
    """`robot_plan.py` in a fresh process: its JSON row, with process_s (the process's wall
    time) or, if it failed, error (its last line on stderr)."""
    env = dict(os.environ)
    if cache is not None:
        env["GAIT_PLANNER_CACHE"] = str(cache)
    command = [sys.executable, str(HERE / "robot_plan.py"), name, "--out", str(out),
               "--time-limit", str(time_limit)] + (["--compiled"] if compiled else []) + (
               ["--scaled-to", scaled_to] if scaled_to else [])
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=HERE.parent)
    wall = time.perf_counter() - start
    try:
        row = json.loads(done.stdout.strip().splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        lines = done.stderr.strip().splitlines()
        return {"name": name, "success": False, "process_s": wall,
                "error": lines[-1] if lines else f"exit {done.returncode}"}
    return {**row, "process_s": wall}


def walked(mcap: str) -> dict:
    """`gait-planner walk MCAP --steps 10 --json`: half cycles walked and why it stopped,
    or the command's error line."""
    if not mcap:
        return {"half_cycles_walked": None, "walk": "not planned"}
    exe = Path(sys.executable).with_name("gait-planner")
    done = subprocess.run([str(exe), "walk", mcap, "--steps", str(STEPS), "--json"],
                          capture_output=True, text=True)
    try:
        data = json.loads(done.stdout)
    except json.JSONDecodeError:
        lines = done.stderr.strip().replace(mcap, Path(mcap).name).splitlines()
        return {"half_cycles_walked": None,
                "walk": lines[-1] if lines else f"exit {done.returncode}"}
    return {"half_cycles_walked": data.get("half_cycles_walked"),
            "walk": data.get("stopped", ""),
            "walk_feedback_share": data.get("feedback_share")}


def robot_rows(name: str, modes: list[str], folder: Path, time_limit: float) -> list[dict]:
    rows = []
    for mode in modes:
        out = folder / f"{name}_{mode}"
        if mode == "compiled":
            cache = folder / f"cache_{name}"
            cache.mkdir()
            first = child(name, out / "first", compiled=True, cache=cache, time_limit=time_limit)
            row = child(name, out, compiled=True, cache=cache, time_limit=time_limit)
            row.update(first_build_s=first.get("build_s"), first_ready_s=first.get("ready_s"),
                       first_plan_s=first.get("plan_s"), first_process_s=first["process_s"],
                       first_compiling=first.get("compiling"), first_error=first.get("error"),
                       first_iterations=first.get("iterations"))
        else:
            row = child(name, out, compiled=False, cache=None, time_limit=time_limit)
        row.update(kind="robot", robot=name, mode=mode, **walked(row.get("mcap", "")))
        rows.append(row)
        print(progress_line(row), flush=True)
    return rows


def counterpart_rows(robot_row: dict, robot: str, folder: Path, time_limit: float) -> list[dict]:
    """The robot's compiled plan, walker3d scaled to it, and walker3d (module docstring)."""
    rows = [dict(robot_row, kind="counterpart", label=f"{robot} (its URDF)")]
    for label, scaled in ((f"walker3d scaled to {robot}", robot), ("walker3d", None)):
        out = folder / ("walker3d_" + (scaled or "plain"))
        row = child("walker3d", out, compiled=True, cache=None, time_limit=time_limit,
                    scaled_to=scaled)
        row.update(kind="counterpart", label=label, robot="walker3d", mode="compiled",
                   **walked(row.get("mcap", "")))
        rows.append(row)
        print(progress_line(row), flush=True)
    return rows


def progress_line(r: dict) -> str:
    head = f"{r.get('label') or r['name']:24s} {r.get('mode', ''):8s}"
    if not r.get("success"):
        return f"{head} failed: {r.get('error') or r.get('message')}"
    first = (f"first build {r['first_build_s']:.1f} s, " if r.get("first_build_s") is not None
             else "")
    share = r.get("peak_torque_share")
    return (f"{head} {first}build {r['build_s']:.1f} s, ready {r['ready_s']:.1f} s, plan "
            f"{r['plan_s']:.1f} s ({r['iterations']} it, solve {r['solve_s']:.1f} s), "
            f"{r['variables']} variables, J {r['cost']:.5g}, CoT {r['cost_of_transport']:.3f}, "
            f"peak {r['peak_torque_Nm']:.3g} N m"
            + (f" ({100 * share:.1f} % of {r['peak_share_joint']}'s limit)" if share else "")
            + f"; walked {r.get('half_cycles_walked')}: {r.get('walk')}")


def recordings(rows: list[dict]) -> dict[str, str]:
    """robot -> the first recording of it that planned (for the picture)."""
    shown: dict[str, str] = {}
    for r in rows:
        if r["kind"] == "robot" and r.get("mcap") and r["robot"] not in shown:
            shown[r["robot"]] = r["mcap"]
    return shown


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--modes", nargs="+", default=["compiled", "casadi"],
                        choices=["compiled", "casadi"])
    parser.add_argument("--counterpart", default="g1", help="robot set beside walker3d "
                        "scaled to it (only if it is benchmarked compiled)")
    parser.add_argument("--no-counterpart", dest="counterpart", action="store_const",
                        const=None)
    parser.add_argument("--time-limit", type=float, default=900.0, help="s per plan")
    parser.add_argument("--quick", action="store_true", help="Bolt only, compiled")
    args = parser.parse_args()
    if args.quick:
        args.robots, args.modes, args.counterpart = ["bolt"], ["compiled"], None
    from results_io import figure_path, write_results

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for robot in args.robots:
            rows += robot_rows(robot, args.modes, folder, args.time_limit)
        match = [r for r in rows if r["robot"] == args.counterpart and r["mode"] == "compiled"]
        if match:
            rows += counterpart_rows(match[0], args.counterpart, folder, args.time_limit)
        try:  # a picture that fails must not lose the measurements
            figure = mid_step_picture(recordings(rows), figure_path("robots.png"),
                                      robots_folder().parents[1])
        except Exception as error:  # noqa: BLE001 - reported in the results' header
            figure = None
            print(f"robots.png not drawn: {error!r}", flush=True)
        for r in rows:  # the temporary folder is gone after this
            r["mcap"] = Path(r["mcap"]).name if r.get("mcap") else ""
    print(write_results("robots", rows, {
        "steps": STEPS, "time_limit_s": args.time_limit, "quick": args.quick,
        "modes": args.modes, "figure": figure.name if figure else None,
        "cost_of_transport": "W+ / (m g s): W+ the positive joint work over the half cycle "
                             "(published efforts conjugate to the joint angles times their "
                             "rates, trapezoidal rule), m the total mass, s the step length"}))
    return 0 if all(r.get("success") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
