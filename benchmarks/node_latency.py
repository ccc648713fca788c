"""The node as a user meets it: fresh `gait-planner node` processes, each asked for the
paper's walker3d gait (the default request) as soon as its service is offered.

    .venv/bin/python benchmarks/node_latency.py              # 5 fresh processes of each kind
    .venv/bin/python benchmarks/node_latency.py --runs 3 --scene walker2d

Two kinds of process: without the warm-start store (`-p warm_start_store:=false`: the first request
is a cold solve from the kinematic guess) and with it as `make setup` leaves it (the
scene's default plan only: every such run gets a cache folder of its own whose compiled
libraries are links to the real cache's and whose plans/ holds what `gait-planner prepare`
wrote into an empty one, so no run re-plans from an earlier run's plans). Per process:
seconds from the start of the process until the service is offered (Python, rclpy, the
problem built by prepare_on_start), the first request's wall time (request sent to answer
received: guess, solve, verification certificate, MCAP and .rrd written, topics published)
and a second, warm request (step length +2 %), and the first answer from the start of the
process (what a user waits who starts the node and asks at once). Median over the runs of
each kind. The service is looked for every 5 ms (`wait_until`).
Needs the compiled derivatives of the scene in the cache (`make setup` compiles them).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import rclpy

from gait_planner.ros.node import SERVICE
from gait_planner_msgs.srv import PlanGait

REPO = Path(__file__).resolve().parent.parent
GAIT_PLANNER = Path(sys.executable).parent / "gait-planner"


POLL = 0.005  # s between checks for the node's service


def wait_until(ready, timeout: float) -> bool:
    """Check `ready` every POLL s until it returns True (True) or `timeout` s have passed
    (False). rclpy's wait_for_service sleeps 0.25 s between checks, which rounded every
    "service offered" before 2026-11-25 up to a multiple of 0.25 s (1.75 s). Here the client
    is an old participant, which a new node's discovery finds before the node creates its
    service. `gait-planner call` keeps rclpy's waits: with this check a fresh client would
    send within 5 ms of seeing the server, possibly before the server has matched its reply
    reader (the lost answers of test_lost_answers.py; benchmarks/HISTORY.md)."""
    deadline = time.monotonic() + timeout
    while not ready():
        if time.monotonic() >= deadline:
            return False
        time.sleep(POLL)
    return True


def cache_with_plans(folder: Path, plans: Path | None) -> Path:
    """A cache folder under `folder` whose entries link to the real cache's
    (`gait_planner.ocp.compile.cache_folder`), except plans/, a copy of `plans` (or empty)."""
    from gait_planner.ocp.compile import cache_folder

    cache = folder / "cache"
    cache.mkdir()
    for entry in cache_folder().iterdir():
        if entry.name != "plans":
            (cache / entry.name).symlink_to(entry)
    if plans is not None:
        shutil.copytree(plans, cache / "plans")
    return cache


def seeded_plans(scene: str, folder: Path) -> Path:
    """plans/ as `gait-planner prepare` (make setup) writes it into an empty library."""
    cache = cache_with_plans(folder, None)
    subprocess.run([str(GAIT_PLANNER), "prepare", scene], cwd=REPO, check=True,
                   env={**os.environ, "GAIT_PLANNER_CACHE": str(cache)},
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return cache / "plans"


def one_run(scene: str, node, plans: Path | None, step_factor: float = 1.02) -> dict:
    """One fresh node; plans None: without the warm-start store, else with a copy of it."""
    with tempfile.TemporaryDirectory(prefix="node_latency_") as folder:
        env = dict(os.environ)
        if plans is not None:
            env["GAIT_PLANNER_CACHE"] = str(cache_with_plans(Path(folder), plans))
        start = time.perf_counter()
        process = subprocess.Popen(
            [str(GAIT_PLANNER), "node", "--ros-args", "-p", f"default_scene:={scene}",
             "-p", f"output_dir:={folder}", "-p", f"allowed_output_dirs:=['{folder}']",
             "-p", f"warm_start_store:={'true' if plans is not None else 'false'}"],
            cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            client = node.create_client(PlanGait, SERVICE)
            if not wait_until(lambda: client.service_is_ready() or process.poll() is not None,
                              300) or process.poll() is not None:
                raise RuntimeError("the node did not offer its service")
            ready = time.perf_counter() - start
            out = {"service_ready_s": ready}
            for key, request in (("first", PlanGait.Request()), ("warm", PlanGait.Request())):
                if key == "warm":
                    request.step_length = step_factor * out["step_length"]
                sent = time.perf_counter()
                future = client.call_async(request)
                rclpy.spin_until_future_complete(node, future, timeout_sec=300)
                answer = future.result()
                if answer is None or not answer.success:
                    raise RuntimeError(f"{key} request failed: {answer and answer.message}")
                out[f"{key}_answer_s"] = time.perf_counter() - sent
                out[f"{key}_iterations"] = answer.iterations
                out[f"{key}_solve_time_s"] = answer.solve_time
                out.setdefault("step_length", answer.step_length)
            out["first_answer_from_start_s"] = ready + out["first_answer_s"]
            node.destroy_client(client)
            return out
        finally:
            process.terminate()
            process.wait(30)


def run(runs: int = 5, scene: str = "walker3d") -> list[dict]:
    os.environ.setdefault("ROS_DOMAIN_ID", str(40 + os.getpid() % 50))
    rclpy.init()
    node = rclpy.create_node("node_latency_client")
    try:
        rows = []
        with tempfile.TemporaryDirectory(prefix="node_latency_seed_") as seed:
            plans = seeded_plans(scene, Path(seed))
            for i, library in [(i, library) for library in (False, True) for i in range(runs)]:
                rows.append({"scene": scene, "run": i, "library": library,
                             **one_run(scene, node, plans if library else None)})
                r = rows[-1]
                print(f"run {i}{' (warm-start store)' if library else ''}: service offered after "
                      f"{r['service_ready_s']:.2f} s, first answer "
                      f"{r['first_answer_s']:.2f} s ({r['first_iterations']} it, solve "
                      f"{r['first_solve_time_s']:.2f} s), warm answer {r['warm_answer_s']:.2f} s "
                      f"({r['warm_iterations']} it); first answer "
                      f"{r['first_answer_from_start_s']:.2f} s after the process started",
                      flush=True)
        return rows
    finally:
        node.destroy_node()
        rclpy.shutdown()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--scene", default="walker3d")
    args = parser.parse_args()
    from results_io import write_results
    rows = run(args.runs, args.scene)
    for library in (False, True):
        for key in ("service_ready_s", "first_answer_s", "first_answer_from_start_s",
                    "warm_answer_s"):
            values = [r[key] for r in rows if r["library"] == library]
            print(f"median {key}{' (warm-start store)' if library else ''}: {np.median(values):.2f}")
    print(write_results(f"node_latency_{args.scene}", rows))


if __name__ == "__main__":
    main()
