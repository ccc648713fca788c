"""Plans walked on a walker that is not the plan's model (issue #40 item 2): the default
plans of walker2d and walker3d (made as `walk.py` makes them: `gait-planner plan --json`)
walked 10 half cycles in MuJoCo by the reference controller, with MuJoCo's model changed as
a real robot differs from its URDF (`gait_planner.walk.model_error.ModelError`):

* masses: every body's mass and inertia times a factor from U[0.9, 1.1], 20 seeds;
* friction 0.5 at the feet (the plans assume their scene's coefficient);
* contact time constants of 2 and 10 ms (the controller's model: 5 ms);
* a 50 ms delay of the controller's commands (feed-forward, torso feedback, joint targets;
  each joint's own PD acting on its present state), which the controller predicts through
  (config/walk.yaml `delay.predict`);
* all of them at once, 20 seeds: masses as above, friction 0.5, a time constant from
  U[2, 10] ms, the 50 ms delay.

    .venv/bin/python benchmarks/model_error.py            # both plans (~10 min on 2 cores)
    .venv/bin/python benchmarks/model_error.py --quick    # walker2d, 3 seeds

Rows to benchmarks/results/model_error.json: per plan and perturbation the walks, how
many completed every half cycle, the half cycles walked (min, median), the feedback share
(RMS feedback / RMS plan torque; median, max) and what stopped each walk that stopped.
The walks run in a process pool (`--workers`, default 2): success is measured, not time.
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from walk import Row, plan

SEEDS = 20


def perturbations(seeds: int) -> list[tuple[str, list]]:
    """(label, [ModelError, ...]) in the order of the module docstring."""
    from gait_planner.walk.model_error import ModelError

    taus = np.random.default_rng(12345).uniform(0.002, 0.010, seeds)
    return [
        ("none", [ModelError()]),
        (f"masses x U[0.9, 1.1], {seeds} seeds",
         [ModelError(seed=s, mass_spread=0.1) for s in range(seeds)]),
        ("friction 0.5", [ModelError(friction=0.5)]),
        ("contact time constant 2 ms", [ModelError(contact_time_constant=0.002)]),
        ("contact time constant 10 ms", [ModelError(contact_time_constant=0.010)]),
        ("torque delay 50 ms", [ModelError(torque_delay=0.05)]),
        (f"all at once, {seeds} seeds",
         [ModelError(seed=s, mass_spread=0.1, friction=0.5,
                     contact_time_constant=float(round(t, 4)), torque_delay=0.05)
          for s, t in zip(range(seeds), taus)]),
    ]


def one_walk(job: tuple[str, int, object]) -> dict:
    """The walk of a recording with one ModelError, as JSON-ready numbers."""
    from gait_planner.walk.walk_plan import walk

    recording, steps, error = job
    r = walk(recording, steps, model_error=error)
    return {"differences": error.describe(), "half_cycles_walked": r["half_cycles_walked"],
            "stopped": r["stopped"], "feedback_share": round(r["feedback_share"], 3),
            "joint_rms_deg": round(r["joint_rms_deg"], 2)}


def summarised(label: str, walks: list[dict], steps: int) -> dict:
    """One table row of a perturbation's walks."""
    done = [w["half_cycles_walked"] for w in walks]
    shares = [w["feedback_share"] for w in walks]
    return {"perturbation": label, "walks": len(walks),
            "completed": sum(d == steps for d in done), "half_cycles_min": min(done),
            "half_cycles_median": statistics.median(done),
            "feedback_share_median": statistics.median(shares),
            "feedback_share_max": max(shares),
            "stopped": sorted({re.split(r" [-+]?\d", w["stopped"])[0] for w in walks
                               if w["stopped"] != "completed"}),
            "each": walks}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10, help="half cycles to walk")
    parser.add_argument("--quick", action="store_true", help="walker2d, 3 seeds")
    parser.add_argument("--workers", type=int, default=2, help="walks at a time")
    args = parser.parse_args()
    from results_io import write_results

    scenes, seeds = (("walker2d",), 3) if args.quick else (("walker2d", "walker3d"), SEEDS)
    rows = []
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(args.workers) as pool:
        for scene in scenes:
            recording, planned = plan(Row(scene, "default"), Path(tmp) / scene, 120.0)
            if recording is None:
                print(f"{scene}: not planned: {planned['message']}", flush=True)
                continue
            for label, errors in perturbations(seeds):
                walks = list(pool.map(one_walk, [(str(recording), args.steps, e)
                                                 for e in errors]))
                row = {"scene": scene, "cost_value": planned.get("cost_value"),
                       **summarised(label, walks, args.steps)}
                rows.append(row)
                print(f"{scene:9s} {label:36s} {row['completed']:2d}/{row['walks']:2d} complete, "
                      f"half cycles min {row['half_cycles_min']}, feedback median "
                      f"{100 * row['feedback_share_median']:.0f} % max "
                      f"{100 * row['feedback_share_max']:.0f} %; {row['stopped'][:2]}",
                      flush=True)
    perturbed = [w for r in rows if r["perturbation"] != "none" for w in r["each"]]
    share = (sum(w["half_cycles_walked"] == args.steps for w in perturbed) / len(perturbed)
             if perturbed else float("nan"))
    print(f"perturbed walks that completed {args.steps} half cycles: {100 * share:.0f} %")
    from gait_planner.walk.walk_plan import load_config

    print(write_results("model_error", rows, {
        "steps": args.steps, "seeds": seeds, "completed_share": share, "quick": args.quick,
        "delay_predict": load_config()["delay"]["predict"]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
