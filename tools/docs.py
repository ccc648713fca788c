"""Every number in README.md and docs/*.md, rendered from the JSON files that named commands
write (`make docs` runs this).

A page holds generated regions::

    <!-- docs:NAME -->
    ...written by render_NAME from benchmarks/results/*.json or docs/measured.json...
    <!-- /docs:NAME -->

    .venv/bin/python tools/docs.py               # rewrite the regions from the stored JSON
    .venv/bin/python tools/docs.py --check       # exit 1 naming each region that differs
    .venv/bin/python tools/docs.py --plan        # first plan the defaults, write their JSON
    .venv/bin/python tools/docs.py --screenshot  # first take benchmarks/rerun_view.png
    .venv/bin/python tools/docs.py --rerun replan paper_sweep   # first re-run those commands

Each JSON file has the command that writes it in `COMMANDS`; a table names it under itself.
docs/measured.json holds what a person times by hand on a fresh clone (`time make run`,
`time make prepare`, `time make test`, ...; `HOW_TO_MEASURE`); a missing time renders as
"not measured yet" with the command to run.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
PAGES = ("README.md", "docs/user-guide.md", "docs/results.md")
REGION = re.compile(r"(<!-- docs:(\w+) -->\n)(.*?)(<!-- /docs:\2 -->)", re.S)
PLAN = (".venv/bin/gait-planner plan --scene walker3d --out build/docs/walker3d.mcap --json "
        "--cold-start")  # as `make run` plans it: from the guess
SWEEP = ".venv/bin/python benchmarks/paper_sweep.py --intervals 8"
COMMANDS = {  # stored JSON -> the command that writes it (run from the repository root)
    "default_plan": ".venv/bin/python tools/docs.py --plan",
    "posture_human": ".venv/bin/python tools/docs.py --plan",
    "default_report": ".venv/bin/python tools/docs.py --plan",
    "paper_sweep": ".venv/bin/python benchmarks/paper_sweep.py --json paper_sweep",
    "posture_none": f"{SWEEP} --set 'joint_limits={{}}' --set torso_lean_max=0 --json posture_none",
    "posture_ranges": f"{SWEEP} --set torso_lean_max=0 --json posture_ranges",
    "replan": ".venv/bin/python benchmarks/replan.py --json replan",
    "hard_cases": ".venv/bin/python benchmarks/hard_cases.py --time-limit 45",
    "cold_solve": ".venv/bin/python benchmarks/cold_solve.py",
    "node_latency_walker3d": ".venv/bin/python benchmarks/node_latency.py",
    "work_precision": ".venv/bin/python benchmarks/work_precision.py",
    "request_sweep": ".venv/bin/python benchmarks/request_sweep.py",
    "walk": ".venv/bin/python benchmarks/walk.py",
    "gait_trends": ".venv/bin/python benchmarks/gait_trends.py",
}
PAPER = {"cost": 41.2256, "duration": 0.5988, "sigma": "1.5000, 1.5000, 1.4889, 1.4724"}


def load(name: str) -> dict:
    path = ROOT / "docs" / "measured.json" if name == "measured" else RESULTS / f"{name}.json"
    return json.loads(path.read_text())


def source(*names: str) -> str:
    """The italic line under a table: when and where it was measured, and how to redo it."""
    parts = []
    for name in names:
        h = load(name)["header"]
        parts.append(f"{h['date_utc'][:16].replace('T', ' ')} UTC, {h['cpu']} ({h['cores']} "
                     f"cores), commit {h['commit'][:7]}: `{COMMANDS[name]}`")
    return "*Measured " + "; ".join(dict.fromkeys(parts)) + ".*\n"


def table(head: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def sigma(values: list[float]) -> str:
    return ", ".join(f"{v:.4f}" for v in values)


# --- regions: render_NAME() -> the text between the markers ----------------------------


HOW_TO_MEASURE = {  # docs/measured.json's rows: how to measure each again
    "first_run": "`time make run` on a fresh clone, an empty compile cache",
    "prepare": "`time make prepare` after it",
    "make_test": "`time make test` once prepared",
    "make_test_slow": "`time make test-slow` once prepared",
    "default_solve": "the solve time `make run` prints"}


def render_measured() -> str:
    """The README's table of what a person times by hand (docs/measured.json: each row's
    command, time, date and conditions), and one line under it: the machine, and the dates
    with their conditions."""
    m = load("measured")
    rows, when = [], {}
    for key, how in HOW_TO_MEASURE.items():
        row = m["rows"][key]
        rows.append([row["command"], row.get("time") or f"not measured yet ({how})"])
        if row.get("time"):
            when.setdefault(f"{row['date']} ({row['conditions']})", []).append(row["short"])
    dates = "; ".join(f"{', '.join(names)} {date}" for date, names in when.items())
    return (table(["command", "time"], rows) + f"\n*{m['machine']}: {dates}; the dated "
            "detail in [benchmarks/HISTORY.md](benchmarks/HISTORY.md).*\n")


def render_plan_line() -> str:
    s = load("default_plan")["summary"]
    return (f"J = {s['cost_value']:.4f} J·s over a {s['duration']:.4f} s half cycle in "
            f"{s['iterations']} IPOPT iterations, {s['solve_time_s']:.1f} s of solving after "
            f"{s['build_time_s']:.1f} s of building ({s['derivatives']}).\n")


def render_default_plan() -> str:
    s = load("default_plan")["summary"]
    rows = [["J = Σ h_n T(v_n) over the half cycle", f"**{s['cost_value']:.4f} J·s**",
             f"{PAPER['cost']} J·s"],
            ["2 J = Σ h_n v_nᵀ M v_n", f"{2 * s['cost_value']:.4f} J·s "
             f"({100 * (2 * s['cost_value'] / PAPER['cost'] - 1):+.2f} %)", ""],
            ["half cycle t_{N−1} − t_0", f"{s['duration']:.4f} s ({s['nodes'] - 2} intervals)",
             f"{PAPER['duration']} s"],
            ["σ = (σ1, σ2, σ3, σ4)", sigma(s["phase_scaling"]), PAPER["sigma"]],
            ["IPOPT iterations; build, solve", f"{s['iterations']}; {s['build_time_s']:.1f} s, "
             f"{s['solve_time_s']:.1f} s", ""],
            ["continuous-dynamics certificate", s["continuous_dynamics"].split(": ", 1)[1], ""]]
    return table(["walker3d, step 0.6338 m, minimal kinetic energy", "this package",
                  "the paper"], rows) + "\n" + source("default_plan")


def render_paper_sweep() -> str:
    rows = [[r["intervals"], f"{r['cost']:.4f}", f"{2 * r['cost']:.4f}", f"{r['duration']:.4f}",
             sigma(r["phase_scaling"]), r["iterations"]] for r in load("paper_sweep")["rows"]]
    return table(["intervals per phase", "J (J·s)", "2 J", "half cycle (s)", "σ", "iterations"],
                 rows) + "\n" + source("paper_sweep")


def render_posture() -> str:
    rows = []
    for name, label in (("posture_none", "none"), ("posture_ranges", "joint ranges"),
                        ("default_plan", "joint ranges + torso ≤ 5° (default)"),
                        ("posture_human", "the default + `posture: human`")):
        d = load(name)
        r = d["rows"][0] if "rows" in d else d["summary"]
        cost = r.get("cost_value", r.get("cost"))
        rows.append([label, f"{cost:.4f}", r["iterations"]])
    return table(["path constraints", "J (J·s)", "iterations"], rows) + "\n" + source(
        "posture_none", "posture_ranges", "default_plan", "posture_human")


def render_replan() -> str:
    d = load("replan")
    pairs: dict[str, dict] = {}
    for r in d["rows"]:
        label = ("step " if r["field"] == "step_length" else "μ ") + f"{r['value']:g}"
        pairs.setdefault(label, {})[r["start"]] = (
            f"{r['iterations']} it., {r['solve_s']:.2f} s, J {r['cost']:.4f}"
            if r["success"] else "failed")
    head = (f"request ({d['header']['scene']}, default plan J "
            f"{d['header']['default_cost']:.4f}, {d['header']['default_iterations']} it.)")
    return table([head, "warm start", "cold start"],
                 [[k, v["warm"], v["cold"]] for k, v in pairs.items()]) + "\n" + source("replan")


def render_hard_cases() -> str:
    rows = [[r["method"], r["scene"], r["case"], r["outcome"], r["iterations"] or "–",
             f"{r['wall_s']:.1f}" if r["wall_s"] is not None else "–", r["intervals"] or "–"]
            for r in load("hard_cases")["rows"] if r["method"] != "variational integrator"]
    return table(["method", "scene", "request", "outcome", "iterations", "s", "intervals"],
                 rows) + "\n" + source("hard_cases")


def render_gait_trends() -> str:
    rows = [[r["scene"], r["series"], f"{r['value']:g}", "yes" if r["certified"] else "no",
             f"{r['cost']:.3f}", f"{r['positive_work_J']:.1f}", f"{r['negative_work_J']:.1f}",
             " / ".join(f"{r[f'{j}_peak_torque_Nm']:.0f}" for j in ("hip", "knee", "ankle")),
             " / ".join(f"{r[f'{j}_peak_power_W']:.0f}" for j in ("hip", "knee", "ankle")),
             f"{r['stance_knee_flexion_deg']:.0f}"]
            for r in load("gait_trends")["rows"] if r["success"]]
    return table(["scene", "series", "value", "certified", "J", "W+ J", "W- J",
                  "peak torque hip / knee / ankle N m", "peak power hip / knee / ankle W",
                  "stance knee deg"], rows) + "\n" + source("gait_trends")


def render_cold_solve() -> str:
    m = load("cold_solve")["header"]["medians"]
    latency = load("node_latency_walker3d")["rows"]

    def median(rows: list[dict], key: str) -> float:
        values = sorted(r[key] for r in rows)
        return values[len(values) // 2] if len(values) % 2 else sum(
            values[len(values) // 2 - 1:len(values) // 2 + 1]) / 2
    rows = [["process start to planner ready"] + [f"{m[s]['ready_s']:.2f} s" for s in m],
            ["cold plan from the kinematic guess"] + [
                f"{m[s]['cold_s']:.2f} s ({m[s]['cold_iterations']:.0f} it.)" for s in m],
            ["warm re-plan, step length +2 %"] + [
                f"{m[s]['warm_s']:.3f} s ({m[s]['warm_iterations']:.0f} it.)" for s in m]]
    node = []
    for library in (False, True):
        runs = [r for r in latency if r["library"] is library]
        node.append([f"{'with' if library else 'without'} the warm-start store",
                     f"{median(runs, 'service_ready_s'):.2f} s",
                     f"{median(runs, 'first_answer_s'):.2f} s",
                     f"{median(runs, 'first_answer_from_start_s'):.2f} s", len(runs)])
    return (table(["median of fresh processes"] + list(m), rows) + "\n"
            + source("cold_solve") + "\n"
            + table(["`gait-planner node`, walker3d", "service offered", "first answer",
                     "first answer from the start", "runs"], node) + "\n"
            + source("node_latency_walker3d"))


def render_work_precision() -> str:
    by_grid: dict[tuple, dict] = {}
    for r in load("work_precision")["rows"]:
        cell = (f"{r['solve_time_s']:.2f} s, {r['error_physics_rms_deg']:.2f} deg"
                if r["converged"] and r["error_physics_rms_deg"] is not None
                else f"not converged in {r['solve_time_s']:.0f} s")
        by_grid.setdefault((r["scene"], r["intervals_per_phase"]), {})[r["method"]] = cell
    rows = [[scene, n, v.get("dmocc", "–"), v.get("collocation", "–")]
            for (scene, n), v in by_grid.items()]
    return table(["scene", "intervals per phase", "DMOCC: solve, drift RMS",
                  "collocation: solve, drift RMS"], rows) + "\n" + source("work_precision")


def render_request_sweep() -> str:
    d = load("request_sweep")
    rows = [[scene, f"{t['converged']} of {t['requests']}", t["iterations"],
             f"{t['solve_s']:.1f} s"] for scene, t in d["header"]["totals"].items()]
    return table(["scene", "converged", "iterations in all", "solve time in all"], rows) + (
        "\n" + source("request_sweep"))


def render_walk() -> str:
    rows = []
    for r in load("walk")["rows"]:
        tests = ", ".join(f"×{t['torque_scale']:g}: {t['half_cycles_walked']} "
                          f"({100 * t['feedback_share']:.0f} %)" for t in r["self_test"])
        if r["half_cycles_walked"] is None:  # the plan failed: nothing was walked
            rows.append([r["scene"], r["case"], "-", r["stopped"], "-", "-", "-"])
            continue
        rows.append([r["scene"], r["case"], f"{r['half_cycles_walked']} of {r['steps']}",
                     r["stopped"], f"{100 * r['feedback_share']:.0f} %",
                     f"{r['joint_rms_deg']:.2f} / {r['joint_max_deg']:.2f}", tests])
    return table(["scene", "plan", "half cycles walked", "why it stopped", "feedback share",
                  "joint error RMS / max (deg)", "plan torques scaled: walked (feedback)"],
                 rows) + "\n" + source("walk")


def render_walk_line() -> str:
    """The README's sentence on the default plans walked in MuJoCo."""
    rows = {r["scene"]: r for r in load("walk")["rows"] if r["case"] == "default"}
    parts = [f"{name}'s default plan walks {r['half_cycles_walked']} of {r['steps']} half "
             f"cycles with the feedback adding {100 * r['feedback_share']:.0f} % of the plan's "
             f"torque" for name, r in rows.items() if name in ("walker3d", "walker2d")]
    measured = source("walk")[1:-3]  # "Measured ..., commit ...: `command`"
    return "In MuJoCo, " + "; ".join(parts) + " (m" + measured[1:] + ").\n"


def render_request_limits() -> str:
    """The ranges a request meets, from the code that checks them (no JSON: a constant
    changed there changes this text)."""
    import yaml

    from gait_planner.model.loader import load_scene_file
    from gait_planner.ocp import request_ranges as ranges
    from gait_planner.ocp.settings import (SolveOptions, settings_for, speed_range, step_range,
                                           widened_scaling_bounds)
    from gait_planner.request import MAX_STEPS

    def paced(st):
        """`st` at a requested speed: sigma's bounds as a speed widens them."""
        st = dataclasses.replace(st, speed=1.0)
        return dataclasses.replace(st, scaling_bounds=widened_scaling_bounds(st))

    node = yaml.safe_load((ROOT / "config/gait_planner.yaml").read_text())
    limit = node["gait_planner"]["ros__parameters"]["max_solve_time"]
    reach = ", ".join(f"{path.stem} {ranges.reach(load_scene_file(path)):.2f} m"
                      for path in sorted((ROOT / "config/scenes").glob("*.yaml")))
    speeds = ", ".join(
        f"{path.stem} {lo:.3f} to {hi:.3f} m/s at its {st.step_length:g} m step"
        for path in sorted((ROOT / "config/scenes").glob("walker*.yaml"))
        for st in [paced(settings_for(load_scene_file(path)))] for lo, hi in [speed_range(st)])
    free = ", ".join(
        f"{path.stem} {lo:.3f} to {hi:.3f} m/s with steps of {a:g} to {b:g} m"
        for path in sorted((ROOT / "config/scenes").glob("walker*.yaml"))
        for st in [paced(settings_for(load_scene_file(path), step_length_free=True))]
        for lo, hi in [speed_range(st)] for a, b in [step_range(st)])
    fastest = ", ".join(
        f"{path.stem} {st.speed_max:g} m/s" for path in sorted((ROOT / "config/scenes").glob("walker*.yaml"))
        for st in [settings_for(load_scene_file(path))] if st.speed_max > 0)
    (mu_lo, mu_hi), (n_lo, n_hi) = ranges.FRICTION_RANGE, ranges.INTERVALS_RANGE
    return (f"* `step_length`: at most the legs' reach ({reach});\n"
            f"* `friction_coefficient`: {mu_lo:g} to {mu_hi:g};\n"
            f"* `intervals_per_phase`: {n_lo} to {n_hi};\n"
            f"* `max_solve_time`: up to {ranges.MAX_SOLVE_TIME:g} s; 0 means the node's "
            f"`max_solve_time` ({limit:g} s in `config/gait_planner.yaml`), in `plan` the "
            f"scene's option `max_solve_time` (default {SolveOptions.max_solve_time:g} s);\n"
            f"* `steps`: 1 to {MAX_STEPS} half cycles;\n"
            f"* `speed`: with a step length, what the scene's σ bounds allow at it, "
            f"step_length / longest to step_length / shortest half cycle ({speeds}); "
            f"alone, what they allow at any step within the scene's `step_length_bounds` "
            f"({free}); never above the gait's `speed_max`, the fastest walk the scene "
            f"file says was planned ({fastest}).\n")


def render_parameters() -> str:
    """The node's parameters as `gait_planner/ros/parameters.py` declares them."""
    from rcl_interfaces.msg import ParameterType

    from gait_planner.ros.parameters import DECLARATIONS

    kinds = {ParameterType.PARAMETER_BOOL: "bool", ParameterType.PARAMETER_INTEGER: "integer",
             ParameterType.PARAMETER_DOUBLE: "double",
             ParameterType.PARAMETER_STRING: "string",
             ParameterType.PARAMETER_STRING_ARRAY: "string array"}
    rows = []
    for name, (default, d) in DECLARATIONS.items():
        span = [f"{r.from_value:g} to {r.to_value:g}"
                for r in (*d.floating_point_range, *d.integer_range)]
        rows.append([f"`{name}`", kinds[d.type], f"`{json.dumps(default)}`",
                     "; ".join((["read-only"] if d.read_only else []) + span),
                     d.description.replace("|", "\\|").replace("<", "&lt;")])
    return table(["parameter", "type", "default", "range", "meaning"], rows)


def render_report_text() -> str:
    return "```text\n" + load("default_report")["text"].rstrip() + "\n```\n\n" + source(
        "default_report")


RENDER = {name[len("render_"):]: f for name, f in globals().items() if name.startswith("render_")}


# --- pages ---------------------------------------------------------------------------------


def rendered(text: str) -> str:
    """`text` with every generated region rendered anew (an unknown NAME is an error)."""
    def one(match: re.Match) -> str:
        name = match.group(2)
        if name not in RENDER:
            raise SystemExit(f"tools/docs.py: unknown region docs:{name} (known: "
                             f"{', '.join(sorted(RENDER))})")
        return match.group(1) + RENDER[name]() + match.group(4)
    return REGION.sub(one, text)


def stale() -> list[str]:
    """'page: region' for every region whose text differs from its rendering."""
    out = []
    for page in PAGES:
        text = (ROOT / page).read_text()
        for match in REGION.finditer(text):
            if rendered(match.group(0)) != match.group(0):
                out.append(f"{page}: docs:{match.group(2)}")
    return out


def run(command: str) -> str:
    print(f"docs: {command}", file=sys.stderr, flush=True)
    done = subprocess.run(shlex.split(command), cwd=ROOT, capture_output=True, text=True)
    if done.returncode not in (0, 1):  # report exits 1 when a check fails: still a result
        raise SystemExit(f"tools/docs.py: `{command}` failed:\n{done.stderr[-2000:]}")
    return done.stdout


def write_json(name: str, body: dict) -> None:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from results_io import header

    (RESULTS / f"{name}.json").write_text(
        json.dumps({"header": header(), **body}, indent=1) + "\n")


def plan_defaults() -> None:
    """The default plan, the same with posture human, and the default plan's report."""
    for name, extra in (("default_plan", ""), ("posture_human", " --posture human")):
        summary = json.loads(run(PLAN.replace("walker3d.mcap", f"{name}.mcap") + extra))
        for key in ("mcap", "rrd"):
            summary.pop(key, None)
        write_json(name, {"summary": summary})
    text = run(".venv/bin/gait-planner report build/docs/default_plan.mcap "
               "--png docs/walker3d_report.png")
    write_json("default_report", {"text": text.split("\n", 1)[1]})  # not the figure's path


def check_chromium() -> None:
    from gait_planner.viz.rerun_screenshot import chromium

    if chromium() is None:
        raise SystemExit("tools/docs.py: the screenshot needs Chromium: apt-get install "
                         "chromium (Debian), or run `make docs SCREENSHOT=` to keep the old one")


def screenshot() -> None:
    if not (ROOT / "build/docs/default_plan.rrd").is_file():
        plan_defaults()
    run(".venv/bin/python benchmarks/rerun_view.py --rrd build/docs/default_plan.rrd "
        "--out benchmarks/rerun_view.png")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only report stale regions")
    parser.add_argument("--plan", action="store_true", help="plan the defaults first")
    parser.add_argument("--screenshot", action="store_true", help="take the screenshot first")
    parser.add_argument("--rerun", nargs="+", default=[], choices=sorted(COMMANDS),
                        metavar="JSON", help="re-run the commands that write these files")
    args = parser.parse_args()
    if args.check:
        out = stale()
        print("\n".join(out) or "docs: every generated region is current")
        return 1 if out else 0
    if args.screenshot:
        check_chromium()  # before the plans: say at once what is missing
    if args.plan or any(COMMANDS[name] == COMMANDS["default_plan"] for name in args.rerun):
        plan_defaults()
    if args.screenshot:
        screenshot()
    for command in dict.fromkeys(COMMANDS[name] for name in args.rerun):
        if command != COMMANDS["default_plan"]:
            print(run(command), end="")
    for page in PAGES:
        path = ROOT / page
        text = path.read_text()
        if rendered(text) != text:
            path.write_text(rendered(text))
            print(f"docs: rewrote {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
