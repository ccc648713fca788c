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

One run, one machine state (issue #38): every row, DMOCC's included, is solved in this run,
one solver at a time (measuring a plan happens after its solve, never beside another).
Before each solve the run waits (at most `--settle` s, default 240) for the 1-minute load
average to fall to `--load-threshold` (default 0.5 on the 2 cores: less than half a core
busy besides; the run's own previous solve decays from ~1 to 0.5 in ~42 s) and records it
(`load_before`), and after the solve `load_after` and `load_other`, the load the rest of
the machine added during the solve (from the 1-minute average's exponential decay,
`other_load`; rows of 30 s and more). A row whose solve started above the threshold, or
during which the rest of the machine added more than it, is solved once more, and the kept
measurement is marked `under_load` when it still was. `cpu_per_wall` is the solve's CPU
time over its wall time: on an idle machine the cores it kept busy.

Threads stated and equal: the solves run single-threaded (`--threads single`, the
default): this process re-executes itself with OMP_NUM_THREADS, OPENBLAS_NUM_THREADS,
MKL_NUM_THREADS and DRAKE_NUM_THREADS at 1 (IPOPT/MUMPS and BLAS for DMOCC, Drake and
Moco; DMOCC runs one thread either way: gait_planner sets the first two itself; what the
main venv sets for DMOCC is not passed to the peers, MAIN_VENV_ENV),
the peers inherit them, Crocoddyl's `ShootingProblem.nthreads` (which OMP_NUM_THREADS
does not change) is set to 1 (`crocoddyl_peer.py --threads 1`), and so is Moco's: its
MocoCasADiSolver evaluates the grid points on every core by default (its `parallel`
property, nor read from OMP_NUM_THREADS; `opensim_peer.py --threads 1` sets it to 0). `--threads default` (or
`both`) adds the peers at their libraries' defaults: those variables unset in the peer's
environment and Crocoddyl's nthreads left at its build's default, methods labelled
"[default threads]". Every row says its threads (`threads`, `thread_env`).
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import signal
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
SCENES = ("walker2d", "walker3d")
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
# the peers' variants added to the table (issue #38): Crocoddyl's regularisation is carried
# between the chunks of its time-limited solve in every FDDP row (crocoddyl_peer)
VARIANTS["crocoddyl"] += (
    # the biped example's integrator and weights (crocoddyl/utils/biped.py)
    ("FDDP euler example weights, x0 DMOCC", ["--solver", "fddp", "--integrator", "euler",
                                              "--setup", "example", "--start", "dmocc"]),
    # mim_solvers' CSQP with its README settings (crocoddyl_peer.CSQP_SETTINGS)
    ("CSQP euler, x0 DMOCC", ["--solver", "csqp", "--integrator", "euler",
                              "--start", "dmocc"]),
)
# once per table, a variant given a longer limit (issue #38): whether Moco converges at all
# on walker2d at 4 per phase (at 300 s and the example's 1000 iterations it stops at ~450
# iterations, not converged); (scene, grid), time limit s, label, argv
LONG_VARIANTS = {"opensim": ((("walker2d", 4), 1200.0, "Moco HS, x0 DMOCC, 1200 s",
                              ["--intervals", "{n}", "--start", "dmocc",
                               "--max-iterations", "5000"]),)}
SOLVE_KEYS = ("build_time", "solve_time", "wall_time", "iterations")  # kept by --remeasure
THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
              "DRAKE_NUM_THREADS")
# set in this process by the main venv, not passed to the peers: gait_planner pins numpy's
# OpenBLAS kernels to Haswell (gait_planner/__init__.py; in a peer it changes the round-off
# of its numpy, e.g. Crocoddyl's start from the guess: 355 against 381 FDDP iterations on
# walker2d at 4 per phase, RK4), the ROS wheels add their libraries' folders
MAIN_VENV_ENV = ("OPENBLAS_CORETYPE", "LD_LIBRARY_PATH", "_ROS_WHEELS_BOOTSTRAP_COMPLETE")
# per peer, the arguments that leave its library's own thread count ("default" rows)
DEFAULT_THREAD_ARGS = {"crocoddyl": ["--threads", "0"], "opensim": ["--threads", "0"]}
LOAD_THRESHOLD = 0.5  # 1-minute load average on the 2 cores (see the module docstring)
SETTLE_S = 240.0  # at most this long waited for the load to fall to the threshold
OTHER_LOAD_MIN_S = 30.0  # shorter solves say nothing reliable of the load beside them
COLUMNS = (("build_time", "build s", ".3g"), ("solve_time", "solve s", ".3g"),
           ("iterations", "iter", "d"), ("converged", "conv", ""),
           ("objective", "J own", ".4g"), ("squared_torque", "int tau^2", ".4g"),
           ("drift_node_rms_deg", "node RMS deg", ".3g"),
           ("drift_node_max_deg", "node max deg", ".3g"),
           ("swing_phase_mm", "phase swing mm", ".3g"),
           ("plan_periodicity_mm", "periodic mm", ".3g"),
           ("contact_hold_mm", "hold mm", ".3g"), ("cone_violation_n", "cone N", ".3g"),
           ("joint_limit_deg", "limit deg", ".3g"),
           ("walk_half_cycles", "walked", "d"), ("walk_joint_rms_deg", "walk RMS deg", ".3g"),
           ("threads", "thr", ""), ("cpu_per_wall", "cpu/wall", ".2f"),
           ("load_before", "load", ".2f"), ("under_load", "loaded", ""))


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


def thread_env(pinned: bool) -> dict[str, str]:
    """A peer's environment: this process's without what the main venv set for DMOCC
    (MAIN_VENV_ENV), THREAD_ENV at 1 (pinned) or unset (the defaults)."""
    env = {k: v for k, v in os.environ.items()
           if k not in THREAD_ENV and k not in MAIN_VENV_ENV}
    return {**env, **dict.fromkeys(THREAD_ENV, "1")} if pinned else env


def run_peer(python: Path, peer: str, argv: list[str], problem_path: Path, out: Path,
             time_limit: float, pinned: bool = True) -> tuple[exchange.Plan | None, str]:
    """(plan, "") or (None, why there is none) of one peer subprocess, its threads pinned
    to one (`thread_env`) or left at their defaults."""
    command = [str(python), "-m", f"benchmarks.peers.{peer}_peer", str(problem_path), str(out),
               *argv, "--time-limit", str(time_limit)]
    try:
        done = subprocess.run(command, cwd=REPO, capture_output=True, text=True,
                              timeout=time_limit + 60, env=thread_env(pinned))
    except subprocess.TimeoutExpired:
        return None, f"killed after {time_limit + 60:g} s"
    if done.returncode != 0 or not out.exists():
        lines = (done.stderr or done.stdout).strip().splitlines()
        code = done.returncode
        killed = f" ({signal.Signals(-code).name})" if code < 0 else ""
        return None, f"exit {code}{killed}: {lines[-1] if lines else ''}"
    return exchange.read_plan(out), ""


def settle(threshold: float, wait: float) -> float:
    """Wait (at most `wait` s) until the 1-minute load average is at most `threshold`;
    the load average then."""
    end = time.monotonic() + wait
    while (load := os.getloadavg()[0]) > threshold and time.monotonic() < end:
        time.sleep(5.0)
    return load


def other_load(before: float, after: float, wall: float, own: float) -> float | None:
    """The load the rest of the machine added during a solve of `wall` s that kept `own`
    cores busy: the 1-minute average relaxes towards the number of runnable tasks with time
    constant 60 s, after = before e + (own + other)(1 - e), e = exp(-wall/60); None for
    solves shorter than OTHER_LOAD_MIN_S (the average is updated every 5 s)."""
    if wall < OTHER_LOAD_MIN_S:
        return None
    e = math.exp(-wall / 60.0)
    return (after - before * e) / (1.0 - e) - own


def _cpu_s() -> float:
    """CPU time (user + system) of this process and its waited-for children so far."""
    return sum(r.ru_utime + r.ru_stime for r in (resource.getrusage(resource.RUSAGE_SELF),
                                                  resource.getrusage(resource.RUSAGE_CHILDREN)))


def measured(solve, threshold: float, wait: float):
    """(solve()'s value, its load record): solved after `settle`, once more when the load
    before exceeded `threshold` or the rest of the machine added more than it during the
    solve; the record of the kept (last) solve, `under_load` when that one still was."""
    attempts = []
    for _ in range(2):
        before = settle(threshold, wait)
        cpu, start = _cpu_s(), time.perf_counter()
        value = solve()
        wall, cpu = time.perf_counter() - start, _cpu_s() - cpu
        after = os.getloadavg()[0]
        own = cpu / wall if wall > 0 else 1.0
        other = other_load(before, after, wall, own)
        loaded = before > threshold or (other is not None and other > threshold)
        attempts.append({"load_before": round(before, 2), "load_after": round(after, 2),
                         "load_other": None if other is None else round(other, 2),
                         "cpu_per_wall": round(own, 2), "solve_wall_s": round(wall, 2),
                         "under_load": loaded})
        if not loaded:
            break
    return value, {**attempts[-1], "attempts": len(attempts),
                   "load_first_attempt": attempts[0] if len(attempts) > 1 else None,
                   "load_threshold": threshold}


def scene_rows(scene: str, n: int, peers: list[str], time_limit: float,
               planner: Planner, remeasure: dict | None = None, *,
               thread_sets: tuple[bool, ...] = (True,), threshold: float = LOAD_THRESHOLD,
               wait: float = SETTLE_S) -> list[dict]:
    """DMOCC's row and every peer variant's row of one scene and grid, each solve
    `measured` (its load record in the row); per peer variant a row per thread set
    (True: pinned to one thread, False: the libraries' defaults). With `remeasure` (the
    previous run's DMOCC row of this scene and grid, or {}) the peers are not run: the
    plans that run left in WORK are measured again, and their solve statistics, and
    DMOCC's, are that run's ("solved" says when)."""
    folder = WORK / f"{scene}-{n}"
    start = time.perf_counter()
    (result, settings, path), load = measured(
        lambda: export(scene, n, folder, time_limit=time_limit, planner=planner),
        threshold if remeasure is None else math.inf, wait if remeasure is None else 0.0)
    wall = time.perf_counter() - start
    problem = exchange.read_problem(path)
    base = {"scene": scene, "grid": n}
    pinned_env = {k: os.environ.get(k, "unset") for k in THREAD_ENV}
    rows = [{**base, "method": "DMOCC", "peer": "dmocc", "start": "kinematic guess (free x0)",
             "build_time": result.stats.build_time, "solve_time": result.stats.solve_time,
             "wall_time": wall, "iterations": result.stats.iterations,
             "converged": result.success, "objective": result.cost_value,
             "status": result.stats.status, "threads": 1, "thread_env": pinned_env,
             **load, **measure_dmocc(result, problem, walk_to=folder / "DMOCC.mcap")}]
    if remeasure:
        rows[0].update({k: remeasure[k] for k in SOLVE_KEYS if k in remeasure},
                       solved=remeasure.get("measured", ""))
    for peer in peers:
        python, why = peer_python(peer)
        variants = [(label, argv, time_limit) for label, argv in VARIANTS[peer]] + \
            [(label, argv, limit) for where, limit, label, argv in LONG_VARIANTS.get(peer, ())
             if where == (scene, n)]
        for label, argv, limit in variants:
            for pinned in thread_sets:
                method = f"{peer} {label}" + ("" if pinned else " [default threads]")
                row = {**base, "method": method, "peer": peer,
                       "thread_env": {k: thread_env(pinned).get(k, "unset")
                                      for k in THREAD_ENV}}
                if python is None and remeasure is None:
                    rows.append({**row, "status": f"skipped: {why}"})
                    continue
                name = label.replace(" ", "_").replace(",", "") + ("" if pinned else
                                                                   "-default_threads")
                out = folder / f"{peer}-{name}.npz"
                args = [a.format(n=n) for a in argv] + \
                    ([] if pinned else DEFAULT_THREAD_ARGS.get(peer, []))
                if remeasure is not None:
                    if not out.exists():  # that run did not run it: nothing to measure again
                        continue
                    plan, why_not = exchange.read_plan(out), ""
                else:
                    def solve(out=out, args=args, pinned=pinned, limit=limit):
                        out.unlink(missing_ok=True)  # a re-run reads only its own plan
                        return run_peer(python, peer, args, path, out, limit, pinned)

                    (plan, why_not), load = measured(solve, threshold, wait)
                    row.update(load)
                if plan is None:
                    rows.append({**row, "status": why_not})
                    continue
                meta = plan.meta
                solved = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(out.stat().st_mtime))
                rows.append({**row, "solved": solved, **{k: meta[k] for k in (
                    "build_time", "solve_time", "iterations", "converged", "objective",
                    "status", "notes", "solver", "formulation", "version")},
                    "start": meta.get("start", ""),
                    "threads": meta.get("threads", 1 if pinned else "default"),
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


def plot(tables: dict[str, list[dict]], path: Path) -> None:
    """Solve time against the one-interval drift (RMS deg), a panel per scene's table,
    each method's grids joined in order."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(tables), figsize=(6 * len(tables), 4.5), squeeze=False)
    for ax, (scene, rows) in zip(axes[0], tables.items()):
        methods = sorted({r["method"] for r in rows})
        for method in methods:
            points = sorted((r["grid"], r["solve_time"], r["drift_node_rms_deg"],
                             r["converged"]) for r in rows
                            if r["method"] == method
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
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=SCENES)
    parser.add_argument("--grids", nargs="+", type=int, default=list(GRIDS))
    parser.add_argument("--peers", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--time-limit", type=float, default=300.0)
    parser.add_argument("--quick", action="store_true", help="walker2d at 4 per phase")
    parser.add_argument("--remeasure", action="store_true",
                        help="do not run the peers: measure the plans the last run left in "
                             f"{WORK.relative_to(REPO)} again (DMOCC is planned again)")
    parser.add_argument("--merge", action="store_true",
                        help="keep the rows of results/peers_<scene>.json that this run does not "
                             "measure again (another peer or grid; the table is then "
                             "no longer one run)")
    parser.add_argument("--threads", choices=("single", "default", "both"), default="single",
                        help="peers single-threaded, at their libraries' defaults, or both "
                             "(DMOCC: single-threaded always)")
    parser.add_argument("--load-threshold", type=float, default=LOAD_THRESHOLD,
                        help="1-minute load average above which a solve is re-run once "
                             "and, still so, marked under_load")
    parser.add_argument("--settle", type=float, default=SETTLE_S,
                        help="s waited at most before each solve for the load to fall to "
                             "the threshold")
    args = parser.parse_args()
    if any(os.environ.get(k) != "1" for k in THREAD_ENV):
        # pin the BLAS, OpenMP and Drake threads of this process (DMOCC) before numpy's and
        # CasADi's libraries start their pools: run again with the variables set; the
        # peers' "default threads" rows unset them again (`thread_env`)
        os.execve(sys.executable, [sys.executable, "-m", "benchmarks.peers.run",
                                   *sys.argv[1:]], {**os.environ,
                                                    **dict.fromkeys(THREAD_ENV, "1")})
    if args.quick:
        args.scenes, args.grids = ["walker2d"], [4]
    thread_sets = {"single": (True,), "default": (False,), "both": (True, False)}[args.threads]
    planner = Planner()
    for scene in args.scenes:
        run_scene(scene, args, planner, thread_sets)
    plot({scene: doc["rows"] for scene in SCENES if (doc := load_results(result_name(scene)))},
         figure_path("peers.png"))


def result_name(scene: str) -> str:
    """The results file of a scene's table (benchmarks/results/peers_<scene>.json): each
    scene's table is one run."""
    return f"peers_{scene}"


def run_scene(scene: str, args, planner: Planner, thread_sets: tuple[bool, ...]) -> None:
    """One scene's table at args.grids, written with its run's header (machine, date,
    commit, load) to `result_name(scene)`; with --merge the rows this run does not measure
    again are kept (the header then says the table is not one run)."""
    load_start = os.getloadavg()[0]
    old = load_results(result_name(scene))
    previous = {r["grid"]: {"measured": old["header"]["date_utc"], **r}
                for r in (old["rows"] if old else []) if r["method"] == "DMOCC"}
    rows = []
    for n in args.grids:
        new = scene_rows(scene, n, args.peers, args.time_limit, planner,
                         previous.get(n, {}) if args.remeasure else None,
                         thread_sets=thread_sets, threshold=args.load_threshold,
                         wait=args.settle)
        rows += new
        print(table(new), flush=True)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows = [{**row, "measured": stamp} for row in rows]
    argv = " ".join(sys.argv[1:])
    # read again: another run may have merged its rows since this one started
    if args.merge and (old := load_results(result_name(scene))) is not None:
        again = {(r["grid"], r["method"]) for r in rows}
        kept = [{**r, "measured": r.get("measured", old["header"]["date_utc"])}
                for r in old["rows"] if (r["grid"], r["method"]) not in again]
        rows = kept + rows
        argv = f"{old['header'].get('argv', '')} | then {argv}"
    print(table(rows))
    this_run = [r for r in rows if r.get("measured") == stamp and "load_before" in r]
    path = write_results(result_name(scene), rows, {
        "scene": scene, "time_limit_s": args.time_limit, "argv": argv,
        "one_run": not args.merge, "threads": args.threads,
        "thread_env_pinned": dict.fromkeys(THREAD_ENV, "1"),
        "load_threshold": args.load_threshold, "settle_s": args.settle,
        "load_average_1min_at_start": load_start,
        "load_average_1min_at_end": os.getloadavg()[0],
        "load_before_max": max((r["load_before"] for r in this_run), default=None),
        "rows_under_load": sum(bool(r.get("under_load")) for r in this_run),
        "rows_re_run": sum(r.get("attempts", 1) > 1 for r in this_run)})
    print(path)


if __name__ == "__main__":
    main()
