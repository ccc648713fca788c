"""A terminal swing without a burst (issue #40 items 3 and 5): the default plans of walker2d
and walker3d as shipped, with the swing braked over its swing (the gait option
`strike_deceleration_max`, m/s^2) and with the torques' second differences in the cost (the
gait option `torque_smoothness`, per (N m)^2), each option in a copy of the scene file as a
user sets it, each plan made by `gait-planner plan --json --cold-start` (`walk.plan`),
checked by the verifier and walked 10 half cycles in MuJoCo with the self-test
(`walk.walk_row`).

    .venv/bin/python benchmarks/smoothness.py              # both scenes, every value (~15 min)
    .venv/bin/python benchmarks/smoothness.py --quick      # walker2d only
    .venv/bin/python benchmarks/smoothness.py --deceleration 40 --smoothness

The smoothness figures are the verifier's (`gait_planner.verify.physical`), away from
contact switches: the largest second difference of any joint torque between nodes over the
largest joint peak (target <= 20 %), and over its own joint's peak for the joints whose
peak is at least a fifth of the largest (target <= 25 %), with that joint and node. Rows to
benchmarks/results/smoothness.json, with the plan's J, iterations, nodes and whether every
check passes.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from walk import Row, plan, walk_row

DECELERATION, SMOOTHNESS = "strike_deceleration_max", "torque_smoothness"
TARGET_PEAK, TARGET_OWN = 0.20, 0.25  # issue #40 item 3


def rows(scenes: list[str], options: dict[str, list[float]]) -> list[Row]:
    """Each scene's default plan as shipped, then with each gait option at each value."""
    return [row for scene in scenes for row in
            [Row(scene, "as shipped"), *(Row(scene, f"{name} {v:g}", options={name: float(v)})
                                         for name, values in options.items() for v in values)]]


def measure(row: Row, folder: Path, steps: int, time_limit: float) -> dict:
    """The row's plan, its verifier figures and its walk, as JSON-ready numbers."""
    from gait_planner.verify import verify_recording

    stem = folder / f"{row.scene}_{row.case.replace(' ', '_')}"
    recording, planned = plan(row, stem, time_limit)
    out = {"scene": row.scene, "case": row.case, "options": row.options,
           "plan": {k: planned.get(k) for k in ("success", "wall_s", "cost_value", "nodes",
                                                "iterations", "certified", "message")}}
    if recording is None:
        return {**out, "checks_pass": False, "half_cycles_walked": None}
    report = verify_recording(recording)
    physical = report.physical
    share, joint, node = physical.roughest_joint
    start = time.perf_counter()
    walked = walk_row(recording, steps)
    return {**out, "checks_pass": bool(report.ok), "failures": list(report.failures)[:3],
            "second_difference_of_peak": round(physical.max_torque_second_difference, 4),
            "roughest_own_peak": round(share, 4), "roughest_joint": joint,
            "roughest_node": node, "steps": steps,
            "meets_target": (physical.max_torque_second_difference <= TARGET_PEAK
                             and share <= TARGET_OWN),
            **{k: walked[k] for k in ("half_cycles_walked", "stopped", "feedback_share",
                                      "joint_rms_deg", "self_test")},
            "walk_wall_s": round(time.perf_counter() - start, 1)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--deceleration", type=float, nargs="*", default=[30.0, 40.0, 50.0],
                        help=f"{DECELERATION} values, m/s^2 (besides the shipped plan)")
    parser.add_argument("--smoothness", type=float, nargs="*", default=[1e-5, 1e-4],
                        help=f"{SMOOTHNESS} values, per (N m)^2")
    parser.add_argument("--quick", action="store_true", help="walker2d only")
    parser.add_argument("--steps", type=int, default=10, help="half cycles to walk")
    parser.add_argument("--time-limit", type=float, default=300.0, help="s per plan")
    args = parser.parse_args()
    from results_io import write_results

    scenes = ["walker2d"] if args.quick else ["walker2d", "walker3d"]
    options = {DECELERATION: args.deceleration, SMOOTHNESS: args.smoothness}
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for row in rows(scenes, options):
            r = measure(row, Path(tmp), args.steps, args.time_limit)
            out.append(r)
            if r["half_cycles_walked"] is None:
                print(f"{r['scene']:9s} {r['case']:28s} no plan: {r['plan']['message']}",
                      flush=True)
                continue
            print(f"{r['scene']:9s} {r['case']:28s} J {r['plan']['cost_value']:.4f}, "
                  f"second difference {r['second_difference_of_peak']:.1%} of the peak, "
                  f"{r['roughest_own_peak']:.1%} of {r['roughest_joint']}'s (node "
                  f"{r['roughest_node']}); checks {'pass' if r['checks_pass'] else 'fail'}; "
                  f"walks {r['half_cycles_walked']}/{args.steps} "
                  f"({r['feedback_share']:.0%})", flush=True)
    print(write_results("smoothness", out, {"options": options, "steps": args.steps,
                                            "time_limit_s": args.time_limit,
                                            "target_of_peak": TARGET_PEAK,
                                            "target_of_own_peak": TARGET_OWN}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
