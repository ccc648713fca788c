"""The node as a user meets it: fresh `gait-planner node` processes, each asked for the
paper's walker3d gait (the default request) as soon as its service is offered.

    .venv/bin/python benchmarks/node_latency.py              # 5 fresh processes
    .venv/bin/python benchmarks/node_latency.py --runs 3 --scene walker2d

Per process: seconds from the start of the process until the service is offered (Python,
rclpy, the problem built by prepare_on_start), the first request's wall time (request sent
to answer received: guess, cold solve, verification certificate, MCAP and .rrd written,
topics published) and a second, warm request (step length +2 %). Median over the runs.
Needs the compiled derivatives of the scene in the cache (`make setup` compiles them).
"""

from __future__ import annotations

import argparse
import os
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


def one_run(scene: str, node, step_factor: float = 1.02) -> dict:
    with tempfile.TemporaryDirectory(prefix="node_latency_") as folder:
        start = time.perf_counter()
        process = subprocess.Popen(
            [str(GAIT_PLANNER), "node", "--ros-args", "-p", f"default_scene:={scene}",
             "-p", f"output_dir:={folder}", "-p", f"allowed_output_dirs:=['{folder}']"],
            cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            client = node.create_client(PlanGait, SERVICE)
            while not client.wait_for_service(timeout_sec=0.01):
                if process.poll() is not None or time.perf_counter() - start > 300:
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
        for i in range(runs):
            rows.append({"scene": scene, "run": i, **one_run(scene, node)})
            r = rows[-1]
            print(f"run {i}: service offered after {r['service_ready_s']:.2f} s, first answer "
                  f"{r['first_answer_s']:.2f} s ({r['first_iterations']} it, solve "
                  f"{r['first_solve_time_s']:.2f} s), warm answer {r['warm_answer_s']:.2f} s "
                  f"({r['warm_iterations']} it)", flush=True)
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
    for key in ("service_ready_s", "first_answer_s", "warm_answer_s"):
        print(f"median {key}: {np.median([r[key] for r in rows]):.2f}")
    print(write_results(f"node_latency_{args.scene}", rows))


if __name__ == "__main__":
    main()
