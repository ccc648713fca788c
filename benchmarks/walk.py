"""Plans walked in MuJoCo (issue #25): `gait-planner walk` on the default plans of walker2d
and walker3d, walker3d's plan with the human posture, walker3d's hard requests (the run and
the forefoot-first stairs down in their own gaits) and a plan recorded over 10 half cycles,
each walked --steps half cycles, with the self-test (the plan's torques x0 and x0.5,
config/walk.yaml).

    .venv/bin/python benchmarks/walk.py            # every row (~10 min on 2 cores)
    .venv/bin/python benchmarks/walk.py --quick    # walker2d's default plan only (~30 s)
    .venv/bin/python benchmarks/walk.py --plans DIR  # keep the plans in DIR; a later run
                                                     # walks those it finds there again

Each plan is made as a user makes it: `gait-planner plan --json` in a subprocess, in a
temporary folder, with --cold-start (the warm-start store's later plans would make a row
depend on what the machine planned before; the hard requests plan cold). The hard
requests are those of `hard_cases.py` a user can ask for: its plan options (step length,
mu, grid, cost) as `plan` options, its scene changes (the sigma bounds, the knee ranges) in
a copy of walker3d.yaml; its solver starts (cold from standing,
a poor guess) are no request and are left out. A plan that fails is a row without a walk.
Rows go to benchmarks/results/walk.json: half cycles walked (of --steps), why the walk
stopped (walk's own sentence), feedback share (RMS feedback / RMS plan torque), joint RMS
and max error (deg), the torso's drift after the last half cycle walked, the worst foot
placement error, the unplanned touches (`gait_planner.walk.touches`: the first three and
how many), and the self-test's half cycles and shares.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from hard_cases import cases as hard_cases

ROOT = Path(__file__).resolve().parent.parent
# hard_cases.py's request fields that `gait-planner plan` takes as options
FLAGS = {"step_length": "--step-length", "friction_coefficient": "--mu",
         "intervals_per_phase": "--intervals", "cost": "--cost", "slope": "--slope",
         "step_height": "--step-height", "speed": "--speed"}


@dataclass(frozen=True)
class Row:
    """A plan to walk: `gait-planner plan --scene SCENE ARGS`, the scene file changed by
    `gait` (keys of its gait section) and `options` (gait options) if either is given."""

    scene: str
    case: str
    args: tuple[str, ...] = ()
    gait: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)


def rows_to_walk(quick: bool) -> list[Row]:
    """The default plans, walker3d's human posture, its hard requests (each in its gait: the
    run, the forefoot-first stairs down), a 10-step plan."""
    if quick:
        return [Row("walker2d", "default")]
    from gait_planner.model.loader import load_scene, with_gait

    scene = load_scene("walker3d")
    out = [Row("walker2d", "default"), Row("walker3d", "default"),
           Row("walker3d", "human posture", ("--posture", "human"))]
    for case in hard_cases(scene):
        if case.guess != "kinematic":  # a solver start, not a request
            continue
        overrides = dict(case.overrides)
        # `plan --speed` without --step-length frees the step (step_length_free); the hard
        # case's speed keeps its gait's step unless it frees it
        if "speed" in overrides and not overrides.pop("step_length_free", False):
            gait = with_gait(scene, case.gait) if case.gait else scene
            overrides.setdefault("step_length", gait.gait.step_length)
        args = [a for key, value in overrides.items() if key in FLAGS
                for a in (FLAGS[key], str(value))] + (["--gait", case.gait] if case.gait else [])
        # gait options: a dict option (joint_limits) keeps only the entries it changes
        declared = scene.gait.options
        options = {k: ({n: r for n, r in v.items() if declared.get(k, {}).get(n) != r}
                       if isinstance(v, dict) else v)
                   for k, v in overrides.items() if k not in FLAGS}
        out.append(Row("walker3d", case.name, tuple(args), dict(case.replace), options))
    return out + [Row("walker3d", "10 half cycles recorded (--steps 10)", ("--steps", "10"))]


def scene_file(row: Row, path: Path) -> str:
    """The scene's name, or `path`: a copy of its file with the row's changes (as a user
    edits one; a dict option is updated entry by entry)."""
    if not row.gait and not row.options:
        return row.scene
    doc = yaml.safe_load((ROOT / "config" / "scenes" / f"{row.scene}.yaml").read_text())
    doc["gait"].update({k: list(v) if isinstance(v, tuple) else v for k, v in row.gait.items()})
    options = doc["gait"]["options"]
    for key, value in row.options.items():
        options[key] = {**options.get(key, {}), **value} if isinstance(value, dict) else value
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return str(path)


def plan(row: Row, stem: Path, time_limit: float) -> tuple[Path | None, dict]:
    """Make the row's plan with `gait-planner plan` into stem.mcap (stem.yaml its scene file
    if changed): (the recording, or None if the plan failed; {success, wall_s, message,
    cost_value, iterations, nodes, refinement, continuous_dynamics: the certificate's sentence,
    certified: whether it holds})."""
    exe = Path(sys.executable).with_name("gait-planner")
    out = stem.with_suffix(".mcap")
    start = time.perf_counter()
    done = subprocess.run([str(exe), "plan", "--scene",
                           scene_file(row, stem.with_suffix(".yaml")), *row.args,
                           "--max-time", str(time_limit), "--no-rrd", "--json", "--cold-start",
                           "--out", str(out)], capture_output=True, text=True)
    wall = time.perf_counter() - start
    try:
        data = json.loads(done.stdout)
    except json.JSONDecodeError:  # refused before planning: the reason is on stderr
        lines = done.stderr.strip().splitlines()
        return None, {"success": False, "wall_s": wall,
                      "message": lines[-1] if lines else f"exit {done.returncode}"}
    summary = {"success": bool(data["success"]) and done.returncode == 0, "wall_s": wall,
               **{k: data.get(k) for k in ("message", "cost_value", "iterations", "nodes",
                                           "refinement", "continuous_dynamics")},
               "certified": str(data.get("continuous_dynamics", "")).endswith(": OK")}
    return (out if summary["success"] else None), summary


def _rounded(x, digits: int = 3):
    return round(x, digits) if isinstance(x, float) else x


def kept_plan(row: Row, stem: Path, time_limit: float) -> tuple[Path | None, dict]:
    """`plan`, unless stem.json holds the summary of an earlier run's plan of the same row
    (its scene, case and options): then that plan (stem.mcap) is walked again."""
    key = {"scene": row.scene, "case": row.case, "args": list(row.args),
           "gait": {k: list(v) if isinstance(v, tuple) else v for k, v in row.gait.items()},
           "options": row.options}
    saved = stem.with_suffix(".json")
    if saved.is_file():
        earlier = json.loads(saved.read_text())
        if earlier["row"] == key:
            out = stem.with_suffix(".mcap")
            return (out if earlier["plan"]["success"] and out.is_file() else None), \
                earlier["plan"]
    recording, planned = plan(row, stem, time_limit)
    saved.write_text(json.dumps({"row": key, "plan": planned}))
    return recording, planned


def walk_row(recording: Path, steps: int) -> dict:
    """The walk of the recording and its self-test, as JSON-ready numbers."""
    from gait_planner.cli.walk import self_test
    from gait_planner.walk.walk_plan import walk

    r = walk(recording, steps)
    tests = self_test(str(recording), steps, r)
    return {"half_cycles_walked": r["half_cycles_walked"], "stopped": r["stopped"],
            "feedback_share": round(r["feedback_share"], 3),
            "joint_rms_deg": round(r["joint_rms_deg"], 2),
            "joint_max_deg": round(r["joint_max_deg"], 2),
            "torso_drift_last_m": [round(x, 3) for x in (r["torso_drift_m"] or [[]])[-1]],
            "foot_placement_error_max_m": round(max(r["foot_placement_error_m"], default=0.0),
                                                3),
            "unplanned_touches": r["unplanned_touches"][:3],
            "unplanned_touch_count": len(r["unplanned_touches"]),
            "foot_slide": r["foot_slide"],
            "self_test": [{k: _rounded(v) for k, v in t.items()} for t in tests]}


def progress_line(r: dict) -> str:
    head = (f"{r['scene']:9s} {r['case'][:38]:38s} plan {r['plan']['wall_s']:5.1f} s"
            + ("" if r["plan"].get("certified", True) else " (certificate fails)"))
    if r["half_cycles_walked"] is None:
        return f"{head}  no walk: {r['stopped']}"
    tests = ", ".join(f"x{t['torque_scale']:g}: {t['half_cycles_walked']} "
                      f"({100 * t['feedback_share']:.0f} %)" for t in r["self_test"])
    return (f"{head}  {r['half_cycles_walked']:2d}/{r['steps']}, feedback "
            f"{100 * r['feedback_share']:3.0f} %, joint RMS {r['joint_rms_deg']:.2f} deg, drift "
            f"{r['torso_drift_last_m']} m, placement {r['foot_placement_error_max_m']} m; "
            f"self-test {tests}; walk {r['walk_wall_s']:.0f} s; {r['stopped']}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10, help="half cycles to walk")
    parser.add_argument("--quick", action="store_true", help="walker2d's default plan only")
    parser.add_argument("--time-limit", type=float, default=120.0, help="s per plan")
    parser.add_argument("--plans", type=Path, default=None,
                        help="keep the plans in this folder and walk those found there again "
                             "(the controller's work without re-planning)")
    args = parser.parse_args()
    from results_io import write_results

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.plans or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        for i, row in enumerate(rows_to_walk(args.quick)):
            recording, planned = kept_plan(row, folder / f"plan_{i:02d}", args.time_limit)
            out = {"scene": row.scene, "case": row.case, "plan_options": " ".join(row.args),
                   "scene_changes": {**row.gait, **row.options}, "steps": args.steps,
                   "plan": {k: _rounded(v) for k, v in planned.items()}}
            if recording is None:
                out.update(half_cycles_walked=None, self_test=[],
                           stopped=f"not planned: {planned['message']}")
            else:
                start = time.perf_counter()
                out.update(walk_row(recording, args.steps))
                out["walk_wall_s"] = round(time.perf_counter() - start, 1)
            rows.append(out)
            print(progress_line(out), flush=True)
    print(write_results("walk", rows, {"steps": args.steps, "time_limit_s": args.time_limit,
                                       "quick": args.quick}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
