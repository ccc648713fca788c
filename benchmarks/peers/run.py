"""DMOCC against the tools people would pick instead (issue #27), on the same walker and
problem, measured by the project's own instruments (`benchmarks/peers/measure.py`):

    .venv/bin/python -m benchmarks.peers.run                    # walker2d, walker3d at 4, 8, 16
    .venv/bin/python -m benchmarks.peers.run --quick            # walker2d at 4
    .venv/bin/python -m benchmarks.peers.run --scenes walker2d --grids 4 8 --peers crocoddyl

For each scene and grid (intervals per phase): DMOCC plans the scene's default request
(compiled derivatives; its own row measured in this process), `problem.py` writes the
problem (DMOCC's schedule, placements, durations, guess) and each peer whose env exists
(`setup_env.sh`; a missing env is a skipped row with its reason) runs as a subprocess of its
env's Python with the time limit (`--time-limit`, default 300 s per solve, the process killed
60 s after), its plan.npz measured here; DMOCC's plan and every converged peer plan are also
walked in MuJoCo by the reference controller (`measure.walk_measures`, 10 half cycles).
Rows: benchmarks/results/peers.json (`results_io`); figure: benchmarks/peers.png (solve time
against one-interval drift). `--remeasure` measures the plans of the last run again without
running the peers.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import time
from pathlib import Path

from benchmarks.peers import exchange
from benchmarks.peers.measure import measure, measure_dmocc
from benchmarks.peers.problem import export
from benchmarks.results_io import figure_path, load_results, write_results
from gait_planner.ocp.solve import Planner

REPO = Path(__file__).resolve().parents[2]
PEER_ROOT = REPO / ".venv-peers"
WORK = REPO / "build" / "peers"
GRIDS = (4, 8, 16)
# (label, argv) per peer: each peer's variants; {n} is the grid (intervals per phase)
VARIANTS = {
    "crocoddyl": (
        ("FDDP rk4, x0 guess", ["--solver", "fddp", "--integrator", "rk4", "--start", "guess"]),
        ("FDDP rk4, x0 DMOCC", ["--solver", "fddp", "--integrator", "rk4", "--start", "dmocc"]),
        ("FDDP euler, x0 DMOCC", ["--solver", "fddp", "--integrator", "euler",
                                  "--start", "dmocc"]),
    ),
    # SNOPT first: the solver Drake's own trajectory-optimisation examples use; its wheel
    # ships SNOPT 7.4 and IPOPT (with a limited-memory Hessian here)
    "drake": (("SNOPT", ["--intervals", "{n}", "--solver", "snopt"]),
              ("IPOPT", ["--intervals", "{n}", "--solver", "ipopt"]),
              ("SNOPT midpoint", ["--intervals", "{n}", "--solver", "snopt",
                                  "--scheme", "midpoint"])),
    # Moco's CasADi solver (Hermite-Simpson, IPOPT) as example2DWalking's prediction sets it
    # up; from the kinematic guess, and from DMOCC's plan as the guess
    "opensim": (("Moco HS, guess", ["--intervals", "{n}", "--start", "guess"]),
                ("Moco HS, x0 DMOCC", ["--intervals", "{n}", "--start", "dmocc"])),
}
SOLVE_KEYS = ("build_time", "solve_time", "wall_time", "iterations")  # kept by --remeasure
COLUMNS = (("build_time", "build s", ".3g"), ("solve_time", "solve s", ".3g"),
           ("iterations", "iter", "d"), ("converged", "conv", ""),
           ("objective", "J own", ".4g"), ("squared_torque", "int tau^2", ".4g"),
           ("drift_node_rms_deg", "node RMS deg", ".3g"),
           ("drift_node_max_deg", "node max deg", ".3g"),
           ("swing_phase_mm", "phase swing mm", ".3g"),
           ("plan_periodicity_mm", "periodic mm", ".3g"),
           ("contact_hold_mm", "hold mm", ".3g"), ("cone_violation_n", "cone N", ".3g"),
           ("joint_limit_deg", "limit deg", ".3g"),
           ("walk_half_cycles", "walked", "d"), ("walk_joint_rms_deg", "walk RMS deg", ".3g"))


def peer_python(peer: str) -> tuple[Path | None, str]:
    """(the env's python, "") or (None, why the peer is skipped)."""
    script = REPO / "benchmarks" / "peers" / f"{peer}_peer.py"
    if not script.exists():
        return None, f"no {script.relative_to(REPO)}"
    python = PEER_ROOT / peer / "bin" / "python"
    if not python.exists():
        return None, (f"no env {python.parent.parent.relative_to(REPO)} "
                      f"(benchmarks/peers/setup_env.sh {peer})")
    return python, ""


def run_peer(python: Path, peer: str, argv: list[str], problem_path: Path, out: Path,
             time_limit: float) -> tuple[exchange.Plan | None, str]:
    """(plan, "") or (None, why there is none) of one peer subprocess."""
    command = [str(python), "-m", f"benchmarks.peers.{peer}_peer", str(problem_path), str(out),
               *argv, "--time-limit", str(time_limit)]
    try:
        done = subprocess.run(command, cwd=REPO, capture_output=True, text=True,
                              timeout=time_limit + 60)
    except subprocess.TimeoutExpired:
        return None, f"killed after {time_limit + 60:g} s"
    if done.returncode != 0 or not out.exists():
        lines = (done.stderr or done.stdout).strip().splitlines()
        return None, f"exit {done.returncode}: {lines[-1] if lines else ''}"
    return exchange.read_plan(out), ""


def scene_rows(scene: str, n: int, peers: list[str], time_limit: float,
               planner: Planner, remeasure: dict | None = None) -> list[dict]:
    """DMOCC's row and every peer variant's row of one scene and grid. With `remeasure`
    (the previous run's DMOCC row of this scene and grid, or {}) the peers are not run: the
    plans that run left in WORK are measured again, and their solve statistics, and
    DMOCC's, are that run's ("solved" says when)."""
    folder = WORK / f"{scene}-{n}"
    start = time.perf_counter()
    result, settings, path = export(scene, n, folder, time_limit=time_limit, planner=planner)
    wall = time.perf_counter() - start
    problem = exchange.read_problem(path)
    base = {"scene": scene, "grid": n}
    rows = [{**base, "method": "DMOCC", "peer": "dmocc", "start": "kinematic guess (free x0)",
             "build_time": result.stats.build_time, "solve_time": result.stats.solve_time,
             "wall_time": wall, "iterations": result.stats.iterations,
             "converged": result.success, "objective": result.cost_value,
             "status": result.stats.status,
             **measure_dmocc(result, problem, walk_to=folder / "DMOCC.mcap")}]
    if remeasure:
        rows[0].update({k: remeasure[k] for k in SOLVE_KEYS if k in remeasure},
                       solved=remeasure.get("measured", ""))
    for peer in peers:
        python, why = peer_python(peer)
        for label, argv in VARIANTS[peer]:
            row = {**base, "method": f"{peer} {label}", "peer": peer}
            if python is None and remeasure is None:
                rows.append({**row, "status": f"skipped: {why}"})
                continue
            out = folder / f"{peer}-{label.replace(' ', '_').replace(',', '')}.npz"
            if remeasure is not None:
                if not out.exists():  # that run did not run it: nothing to measure again
                    continue
                plan, why_not = exchange.read_plan(out), ""
            else:
                out.unlink(missing_ok=True)
                plan, why_not = run_peer(python, peer, [a.format(n=n) for a in argv], path,
                                         out, time_limit)
            if plan is None:
                rows.append({**row, "status": why_not})
                continue
            meta = plan.meta
            solved = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(out.stat().st_mtime))
            rows.append({**row, "solved": solved, **{k: meta[k] for k in (
                "build_time", "solve_time", "iterations", "converged", "objective", "status",
                "notes", "solver", "formulation", "version")}, "start": meta.get("start", ""),
                **measure(problem, plan,
                          walk_to=out.with_suffix(".mcap") if meta["converged"] else None)})
    return rows


def table(rows: list[dict]) -> str:
    """The rows as a fixed-width table."""
    head = ["scene", "n", "method"] + [title for _, title, _ in COLUMNS]
    lines = []
    for row in rows:
        cells = [row["scene"], str(row["grid"]), row["method"]]
        if "drift_node_rms_deg" not in row and "solve_time" not in row:
            lines.append(cells + [row["status"]])
            continue
        for key, _, fmt in COLUMNS:
            value = row.get(key)
            cells.append("-" if value is None else
                         str(value) if fmt == "" else format(value, fmt))
        lines.append(cells)
    widths = [max(len(line[i]) for line in [head] + lines if i < len(line))
              for i in range(len(head))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip()
                     for line in [head] + lines)


def plot(rows: list[dict], path: Path) -> None:
    """Solve time against the one-interval drift (RMS deg), a panel per scene, each
    method's grids joined in order."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenes = sorted({r["scene"] for r in rows})
    fig, axes = plt.subplots(1, len(scenes), figsize=(6 * len(scenes), 4.5), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        methods = sorted({r["method"] for r in rows if r["scene"] == scene})
        for method in methods:
            points = sorted((r["grid"], r["solve_time"], r["drift_node_rms_deg"],
                             r["converged"]) for r in rows
                            if r["scene"] == scene and r["method"] == method
                            and math.isfinite(r.get("drift_node_rms_deg", math.nan)))
            if not points:
                continue
            line, = ax.plot([p[1] for p in points], [p[2] for p in points], "-", label=method)
            for n, t, d, ok in points:
                ax.plot(t, d, "o" if ok else "x", color=line.get_color())
                ax.annotate(str(n), (t, d), textcoords="offset points", xytext=(4, 4),
                            fontsize=8)
        ax.set(xscale="log", yscale="log", xlabel="solve time (s)",
               ylabel="one-interval drift, RMS (deg)", title=f"{scene} (o converged, x not)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["walker2d", "walker3d"])
    parser.add_argument("--grids", nargs="+", type=int, default=list(GRIDS))
    parser.add_argument("--peers", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--time-limit", type=float, default=300.0)
    parser.add_argument("--quick", action="store_true", help="walker2d at 4 per phase")
    parser.add_argument("--remeasure", action="store_true",
                        help="do not run the peers: measure the plans the last run left in "
                             f"{WORK.relative_to(REPO)} again (DMOCC is planned again)")
    parser.add_argument("--merge", action="store_true",
                        help="keep the rows of results/peers.json that this run does not "
                             "measure again (another peer, scene or grid)")
    args = parser.parse_args()
    if args.quick:
        args.scenes, args.grids = ["walker2d"], [4]
    planner = Planner()
    old = load_results("peers")
    previous = {(r["scene"], r["grid"]): {"measured": old["header"]["date_utc"], **r}
                for r in (old["rows"] if old else []) if r["method"] == "DMOCC"}
    rows = []
    for scene in args.scenes:
        for n in args.grids:
            rows += scene_rows(scene, n, args.peers, args.time_limit, planner,
                               previous.get((scene, n), {}) if args.remeasure else None)
            print(table(rows[-1 - sum(len(VARIANTS[p]) for p in args.peers):]), flush=True)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows = [{**row, "measured": stamp} for row in rows]
    argv = " ".join(sys.argv[1:])
    # read again: another run may have merged its rows since this one started
    if args.merge and (old := load_results("peers")) is not None:
        again = {(r["scene"], r["grid"], r["method"]) for r in rows}
        kept = [{**r, "measured": r.get("measured", old["header"]["date_utc"])}
                for r in old["rows"] if (r["scene"], r["grid"], r["method"]) not in again]
        rows = kept + rows
        argv = f"{old['header'].get('argv', '')} | then {argv}"
    print(table(rows))
    path = write_results("peers", rows, {"time_limit_s": args.time_limit, "argv": argv})
    plot(rows, figure_path("peers.png"))
    print(path)


if __name__ == "__main__":
    main()
