"""Speed against error: DMOCC (the product) and Hermite-Simpson direct collocation on
minimal coordinates (`benchmarks.collocation`), the same gait problem at several grids,
both solved cold from the same kinematic guess with the same IPOPT options, in one process.
The collocation runs twice: "collocation" with its per-point derivative elements compiled
to C as DMOCC's are (the baseline), "collocation_interpreted" with CasADi's derivatives of
its one expanded SX graph. Every method builds its NLP, derivatives and IPOPT instances
before the clock starts (build_time_s).

    .venv/bin/python benchmarks/work_precision.py            # walker2d 4..16, walker3d 4..12
    .venv/bin/python benchmarks/work_precision.py --quick    # walker2d at 4 and 8

Grids: n intervals per phase with the base time step scaled by 8 / n, so that every grid can
reach the same phase durations and only the discretisation changes. Errors, measured the
same way for both methods:
* against physics (`gait_planner.verify.drift.physics_error`): the plan's torques and
  contact schedule through the continuous dynamics (Pinocchio, DOP853, rtol 1e-10), from the
  plan's state at every node ("node": the local error of one interval; RMS and max joint
  angle drift) and at every phase start ("phase": drift over a phase, swing foot in mm);
  and the continuous-dynamics certificate (inverse dynamics, % of peak torque);
* against a fine reference: the same problem by DMOCC at `REFERENCE` intervals per phase;
  joint angles compared at the same phase-relative times (each phase's nodes mapped to
  [k, k + 1] for phase k, the reference interpolated linearly), and the cost difference.
Time per solve, from IPOPT's own timers of every stage (`StageTimes`): evaluation_s (f, g
and their derivatives; jacobian_s and hessian_s of it), callback_s (the progress callback),
kkt_s = IPOPT's wall time - evaluation - callback (the KKT factorisations and solves, and
IPOPT's own steps), rest_s = solve_time_s - IPOPT's wall time (guess, Python between stages).
Rows go to benchmarks/results/work_precision.json; the plot to benchmarks/work_precision.png.
"""

from __future__ import annotations

import argparse
import logging
import time

import numpy as np

from benchmarks.collocation import plan_collocation
from gait_planner.ocp import ipopt
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.verify.certify import continuous_certificate
from gait_planner.verify.drift import physics_error

GRIDS = (4, 6, 8, 12, 16)
GRIDS_WALKER3D = (4, 6, 8, 12)
REFERENCE = 24
TIME_LIMIT = 120.0  # s per solve (fine grids that do not converge end here)
# s per collocation solve (either form), by scene: walker2d converges within 35 s on every
# grid that converges at all; walker3d's compiled form converged in 86 s at 4 per phase and
# 52 s at 12, and stopped here at 6 and 8 (loaded machine, 2026-11-27; collocation.solve)
COLLOCATION_TIME_LIMIT = {"walker2d": 60.0, "walker3d": 300.0}
METHODS = ("dmocc", "collocation", "collocation_interpreted")
# IPOPT's timers (solver.stats() "t_wall_<key>") summed by `StageTimes`
TIMERS = ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l", "callback_fun")


class StageTimes:
    """Within `with StageTimes() as t:`, every IPOPT call of either planner (both call
    `ocp.ipopt.solve_stage`, which this wraps) adds its wall time (t.seconds["ipopt"]) and
    IPOPT's timers (`TIMERS`) to t.seconds."""

    def __enter__(self):
        self.seconds = dict.fromkeys(("ipopt",) + TIMERS, 0.0)
        self.original = ipopt.solve_stage

        def timed(solver, *args):
            start = time.perf_counter()
            out = self.original(solver, *args)
            self.seconds["ipopt"] += time.perf_counter() - start
            stats = solver.stats()
            for key in TIMERS:
                self.seconds[key] += float(stats.get(f"t_wall_{key}", 0.0))
            return out

        ipopt.solve_stage = timed
        return self

    def __exit__(self, *exc):
        ipopt.solve_stage = self.original

    def row(self, solve_time: float) -> dict:
        """The split of a solve of solve_time seconds (module docstring)."""
        t = self.seconds
        evaluation = sum(t[k] for k in TIMERS if k != "callback_fun")
        return {"evaluation_s": evaluation, "jacobian_s": t["nlp_jac_g"],
                "hessian_s": t["nlp_hess_l"], "callback_s": t["callback_fun"],
                "kkt_s": t["ipopt"] - evaluation - t["callback_fun"],
                "rest_s": solve_time - t["ipopt"]}


def settings_at(scene, n: int, time_limit: float):
    return settings_for(scene, intervals_per_phase=n, max_solve_time=time_limit, compiled=True)


def phase_clock(result) -> np.ndarray:
    """(N+1,) phase-relative time of each node: phase k's nodes run over [k, k + 1]."""
    names = [p.name for p in result.scene.gait.phases]
    out = np.zeros(len(result.times))
    for k, name in enumerate(names):
        nodes = [i for i, ph in enumerate(result.phases) if ph == name]
        if not nodes:
            continue
        first, last = nodes[0], min(nodes[-1] + 1, len(result.times) - 1)
        span = result.times[last] - result.times[first]
        for i in range(first, last + 1):
            out[i] = k + (result.times[i] - result.times[first]) / span
    return out


def reference_error(result, reference) -> float:
    """RMS joint angle difference (deg) to the reference over the half cycle."""
    clock, ref_clock = phase_clock(result), phase_clock(reference)
    inside = np.arange(len(result.times) - 1)  # nodes 0..N-1
    ref = np.column_stack([np.interp(clock[inside], ref_clock[:-1], a[:-1])
                           for a in np.unwrap(reference.joint_angles, axis=0).T])
    mine = np.unwrap(result.joint_angles, axis=0)[inside]
    return float(np.degrees(np.sqrt(np.mean((mine - ref) ** 2))))


def solve(method: str, scene, n: int, time_limit: float):
    """(result, build time s, problem size) of one cold plan by `method` (`METHODS`)."""
    s = settings_at(scene, n, time_limit)
    start = time.perf_counter()
    if method == "dmocc":
        planner = Planner()
        planner.prepare(scene, s)
        build = time.perf_counter() - start
        result = plan_once(planner, scene, s, warm_start=False)
        size = planner.problem_size(scene, s)
    else:
        s = s.with_solve(max_solve_time=COLLOCATION_TIME_LIMIT[scene.name],
                         compiled=method == "collocation")
        result = plan_collocation(scene, s)  # recursive Newton-Euler
        build = result.stats.build_time
        size = {k: result.settings.get(k) for k in ("variables", "constraints",
                                                      "jacobian_nonzeros", "hessian_nonzeros")}
    return result, build, size


def measure(method: str, scene_name: str, n: int, reference, time_limit: float) -> dict:
    scene = load_scene(scene_name)
    with StageTimes() as times:
        result, build, size = solve(method, scene, n, time_limit)
    row = {"method": method, "scene": scene_name, "intervals_per_phase": n,
           **{k: (int(v) if v is not None else None) for k, v in size.items()
              if k != "intervals"},
           "build_time_s": build, "solve_time_s": result.stats.solve_time,
           "iterations": result.stats.iterations,
           **times.row(result.stats.solve_time),
           "derivatives": result.settings.get("derivatives"),
           "cost": result.cost_value, "converged": bool(result.success),
           "message": result.message}
    if not result.success:
        return row
    node, phase = (physics_error(result, reset=r) for r in ("node", "phase"))
    cert = continuous_certificate(result)
    row.update(
        error_physics_rms_deg=node.angle_drift_rms_deg,
        error_physics_max_deg=node.angle_drift_max_deg,
        error_physics_phase_rms_deg=phase.angle_drift_rms_deg,
        error_physics_phase_max_deg=phase.angle_drift_max_deg,
        swing_drift_phase_mm=phase.swing_drift_max_mm,
        physics_failure=node.failure or phase.failure,
        certificate_torque_calm_pct=100 * cert.max_torque_calm,
        certificate_torque_switch_pct=100 * cert.max_torque_switch,
        error_reference_rms_deg=reference_error(result, reference) if reference else None,
        cost_reference_relative=(result.cost_value / reference.cost_value - 1)
        if reference else None)
    return row


def time_to_reach(rows: list[dict], level: float, key: str = "error_physics_rms_deg"):
    """Solve time (s) at which a method's error first drops to `level`, interpolated in
    log-log between the grids that bracket it (None: never reached)."""
    pts = sorted((r["solve_time_s"], r[key]) for r in rows if r.get(key) is not None)
    best = np.inf
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        best = min(best, e0)
        if best > level >= e1:
            w = np.log(level / best) / np.log(e1 / best)
            return float(np.exp(np.log(t0) + w * np.log(t1 / t0)))
    if pts and pts[0][1] <= level:
        return pts[0][0]
    return None


def run(quick: bool = False, time_limit: float = TIME_LIMIT) -> list[dict]:
    logging.getLogger("gait_planner").setLevel(logging.ERROR)
    scenes = ("walker2d",) if quick else ("walker2d", "walker3d")
    grids = {"walker2d": (4, 8) if quick else GRIDS, "walker3d": GRIDS_WALKER3D}
    rows = []
    for scene_name in scenes:
        scene = load_scene(scene_name)
        reference = None
        if not quick:
            reference, _, _ = solve("dmocc", scene, REFERENCE, time_limit)
            reference = reference if reference.success else None
            print(f"{scene_name}: reference at {REFERENCE} per phase: "
                  f"{'J = %.5f' % reference.cost_value if reference else 'did not converge'}",
                  flush=True)
        for n in grids[scene_name]:
            for method in METHODS:
                rows.append(measure(method, scene_name, n, reference, time_limit))
                print_row(rows[-1])
    return rows


def print_row(r: dict) -> None:
    def f(key, fmt):
        v = r.get(key)
        return "-" if v is None else format(v, fmt)
    it = max(r["iterations"], 1)
    print(f"{r['scene']:9s} {r['method']:23s} n={r['intervals_per_phase']:3d} "
          f"vars={f('variables', 'd'):>6} build={r['build_time_s']:6.1f} s it={r['iterations']:5d} "
          f"t={r['solve_time_s']:8.2f} s (per it.: eval {1e3 * r['evaluation_s'] / it:.1f} "
          f"kkt {1e3 * r['kkt_s'] / it:.1f} "
          f"rest {1e3 * (r['callback_s'] + r['rest_s']) / it:.1f} ms) "
          f"J={f('cost', '.5f'):>9} "
          f"phys rms/max={f('error_physics_rms_deg', '.3g')}/{f('error_physics_max_deg', '.3g')} deg "
          f"ref={f('error_reference_rms_deg', '.3g')} deg "
          f"{'' if r['converged'] else 'FAILED: ' + r['message'][:60]}", flush=True)


def plot(rows: list[dict], path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = (("error_physics_rms_deg", "against physics: one-interval drift, RMS (deg)"),
            ("error_reference_rms_deg", "against the fine reference: RMS (deg)"))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, (key, title) in zip(axes, keys):
        for scene in sorted({r["scene"] for r in rows}):
            for method, style in (("dmocc", "o-"), ("collocation", "s--"),
                                  ("collocation_interpreted", "^:")):
                pts = sorted((r["solve_time_s"], r[key], r["intervals_per_phase"]) for r in rows
                             if r["scene"] == scene and r["method"] == method
                             and r.get(key) is not None)
                if not pts:
                    continue
                t, e, n = zip(*pts)
                ax.loglog(t, e, style, label=f"{method}, {scene}")
                for ti, ei, ni in pts:
                    ax.annotate(str(ni), (ti, ei), fontsize=7, xytext=(3, 3),
                                textcoords="offset points")
        ax.set_xlabel("solve time (s), cold, 2 cores")
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--time-limit", type=float, default=TIME_LIMIT)
    args = parser.parse_args()
    from results_io import figure_path, write_results
    rows = run(args.quick, args.time_limit)
    print(write_results("work_precision", rows, {
        "quick": args.quick, "reference": REFERENCE, "time_limit_s": args.time_limit,
        "collocation_time_limit_s": COLLOCATION_TIME_LIMIT}))
    plot(rows, figure_path("work_precision.png"))


if __name__ == "__main__":
    main()
