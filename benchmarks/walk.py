"""The default plans walked in MuJoCo (issue #25): `gait-planner walk` on walker2d's and
walker3d's default plans, 10 half cycles, with the self-test (plan torques x0, x0.5).

    .venv/bin/python benchmarks/walk.py [--steps 10]

Each plan is made by `gait-planner plan --scene NAME --out ...` in a temporary folder (as a
user makes it); rows go to benchmarks/results/walk.json: half cycles walked (of --steps),
why the walk stopped, feedback share (RMS feedback / RMS plan torque), joint RMS and max
error (deg), the torso's drift after the last half cycle walked, the worst foot placement
error, and the self-test's half cycles and shares.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

SCENES = ("walker2d", "walker3d")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10)
    args = parser.parse_args()
    from gait_planner.cli.walk import self_test
    from gait_planner.walk.simulate import walk
    from results_io import write_results

    exe = Path(sys.executable).with_name("gait-planner")
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for scene in SCENES:
            plan = Path(folder) / f"{scene}.mcap"
            subprocess.run([str(exe), "plan", "--scene", scene, "--out", str(plan)], check=True,
                           capture_output=True)
            r = walk(plan, args.steps)
            tests = self_test(str(plan), args.steps, r)
            row = {"scene": scene, "steps": args.steps,
                   "half_cycles_walked": r["half_cycles_walked"], "stopped": r["stopped"],
                   "feedback_share": round(r["feedback_share"], 3),
                   "joint_rms_deg": round(r["joint_rms_deg"], 2),
                   "joint_max_deg": round(r["joint_max_deg"], 2),
                   "torso_drift_last_m": [round(x, 3) for x in (r["torso_drift_m"] or [[]])[-1]],
                   "foot_placement_error_max_m": round(max(r["foot_placement_error_m"],
                                                           default=0.0), 3),
                   "self_test": [{k: (round(v, 3) if isinstance(v, float) else v)
                                  for k, v in t.items() if k != "stopped"} for t in tests]}
            rows.append(row)
            selftest = ", ".join(f"x{t['torque_scale']:g}: {t['half_cycles_walked']} "
                                 f"({100 * t['feedback_share']:.0f} %)" for t in tests)
            print(f"{scene:9s} {r['half_cycles_walked']:2d}/{args.steps} half cycles, feedback "
                  f"{100 * r['feedback_share']:4.0f} %, joint RMS {r['joint_rms_deg']:.2f} deg, "
                  f"drift {row['torso_drift_last_m']} m; self-test {selftest}; {r['stopped']}",
                  flush=True)
    write_results("walk", rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
