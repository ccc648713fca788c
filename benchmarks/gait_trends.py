"""Joint work, peak torques and powers of planned gaits over slope and over speed, next to
the trends of human walking (issue #26).

    .venv/bin/python benchmarks/gait_trends.py            # walker2d and walker3d (~10 min)
    .venv/bin/python benchmarks/gait_trends.py --quick    # walker2d, three slopes (~1 min)

Each row is one certified plan (`gait_planner.strategies.plan_certified`, compiled
derivatives, cold): a slope of -10, -5, 0, 5, 10 deg at the scene's step and free
durations, or a speed (m/s, `GaitSettings.speed`) on level ground at the scene's step
(1.1 to 2.5 m/s: what sigma's bounds reach at 0.6338 m) and 0.8 m/s at a 0.45 m step.
From the published efforts conjugate to the joint angles (`model.angles.conjugate_torques`)
and the joint-angle rates, over the half cycle t_0 .. t_(N-1) (trapezoidal rule):

* positive and negative joint work W+ and W- (J, all joints), and the mechanical cost of
  transport W+ / (m g s) (s the step length);
* the peak |torque| (N m) and the peak positive power (W) of the hips, knees and ankles;
* the stance knee's peak flexion (deg) in single support (the knee of the leg whose foot
  alone is held; knee > 0 bent).

Human trends they are set against (the numbers are for people, the model is not fitted to
them; `report.py` says where the rows agree):
* Slope. Positive leg work rises and negative work falls steadily from downhill to uphill
  (Franz, Lyddon & Kram 2012, J Biomech 45:257-262, -9 to +9 deg at 1.25 m/s); uphill the
  hip's positive work dominates, downhill the knee absorbs (Lay, Hass & Gregor 2006,
  J Biomech 39:1621-1628). The metabolic cost of transport is least near -10 % grade
  (-5.7 deg) and rises steeply uphill (Minetti et al. 2002, J Appl Physiol 93:1039-1046).
* Speed. Peak stance knee flexion and peak joint moments and powers grow with walking
  speed (Lelas et al. 2003, Gait Posture 17:106-112, 0.6 to 2.0 m/s). People change from
  walking to running at about 2.0 m/s (Hreljac 1993, Med Sci Sports Exerc 25:1158-1162:
  2.07 m/s): a walk planned faster has no human counterpart.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gait_planner.model.angles import conjugate_torques
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_certified
from results_io import figure_path, write_results

SLOPES = (-10.0, -5.0, 0.0, 5.0, 10.0)  # deg
SPEEDS = (1.1, 1.3, 1.6, 2.0, 2.5)  # m/s at the scene's step
SLOW = (0.8, 0.45)  # m/s, step m: a slow walk needs a shorter step
JOINTS = ("hip", "knee", "ankle")
TIME_LIMIT = 300.0  # s per plan


def _trapezoid(y: np.ndarray, t: np.ndarray) -> float:
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))


def metrics(result) -> dict:
    """The row's numbers (module docstring) of one successful half cycle."""
    scene, N = result.scene, result.n_nodes - 1
    names = list(result.joint_angle_names)
    efforts = conjugate_torques(scene, result.joint_angles, result.tau)
    power = efforts * result.joint_velocities  # W per joint angle
    t, p = result.times[:N], power[:N]
    mass = sum(b.mass for b in scene.bodies)
    out = {"cost": result.cost_value, "duration_s": result.duration,
           "speed_m_s": result.step_length / result.duration,
           "positive_work_J": _trapezoid(np.clip(p, 0, None).sum(axis=1), t),
           "negative_work_J": _trapezoid(np.clip(p, None, 0).sum(axis=1), t),
           "rise_work_J": mass * scene.gravity * result.ground.rise(result.step_length)}
    out["mechanical_cost_of_transport"] = out["positive_work_J"] / (
        mass * scene.gravity * result.step_length)
    for joint in JOINTS:
        cols = [i for i, n in enumerate(names) if n.startswith(joint)]
        out[f"{joint}_peak_torque_Nm"] = float(np.abs(efforts[:N, cols]).max())
        out[f"{joint}_peak_power_W"] = float(p[:, cols].max())
    out["stance_knee_flexion_deg"] = _stance_knee(result, names)
    return out


def _stance_knee(result, names: list[str]) -> float:
    """Peak knee angle (deg) of the leg whose foot alone is held (single support)."""
    scene, peak = result.scene, 0.0
    for n, active in enumerate(result.active_contacts[: result.n_nodes - 1]):
        bodies = {scene.contact(c).body for c in active}
        if len(bodies) != 1:
            continue
        side = next(iter(bodies)).rsplit("_", 1)[-1]  # foot_r -> r
        knee = [i for i, name in enumerate(names) if name.startswith(f"knee_{side}")]
        if knee:
            peak = max(peak, float(np.degrees(result.joint_angles[n, knee[0]])))
    return peak


def run(scene_name: str, series: str, value: float, overrides: dict) -> dict:
    scene = load_scene(scene_name)
    settings = settings_for(scene, compiled=True, max_solve_time=TIME_LIMIT, **overrides)
    start = time.perf_counter()
    result, cert = plan_certified(Planner(), scene, settings, warm_start=False)
    row = {"scene": scene_name, "series": series, "value": value,
           "step_length": settings.step_length, "success": bool(result.success),
           "certified": bool(cert is not None and cert.ok), "wall_s": time.perf_counter() - start,
           "iterations": result.stats.iterations, "nodes": result.n_nodes,
           "message": "" if result.success else result.message}
    if result.success:
        row.update(metrics(result))
    print(f"{scene_name} {series} {value:g}: {'ok' if result.success else result.message} "
          f"({row['wall_s']:.0f} s)", flush=True)
    return row


def plot(rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    for scene, marker in (("walker2d", "o"), ("walker3d", "s")):
        mine = [r for r in rows if r["scene"] == scene and r.get("success")]
        slope = sorted((r for r in mine if r["series"] == "slope"), key=lambda r: r["value"])
        speed = sorted((r for r in mine if r["series"] == "speed"), key=lambda r: r["value"])
        if slope:
            x = [r["value"] for r in slope]
            axes[0, 0].plot(x, [r["positive_work_J"] for r in slope], marker + "-",
                            label=f"{scene} W+")
            axes[0, 0].plot(x, [r["negative_work_J"] for r in slope], marker + "--",
                            label=f"{scene} W-")
            for joint, color in zip(JOINTS, ("C0", "C1", "C2")):
                axes[0, 1].plot(x, [r[f"{joint}_peak_power_W"] for r in slope], marker + "-",
                                color=color, label=f"{scene} {joint}")
        if speed:
            x = [r["value"] for r in speed]
            axes[1, 0].plot(x, [r["stance_knee_flexion_deg"] for r in speed], marker + "-",
                            label=scene)
            for joint, color in zip(JOINTS, ("C0", "C1", "C2")):
                axes[1, 1].plot(x, [r[f"{joint}_peak_torque_Nm"] for r in speed], marker + "-",
                                color=color, label=f"{scene} {joint}")
    axes[0, 0].set(xlabel="slope (deg, uphill > 0)", ylabel="joint work per half cycle (J)",
                   title="Work over slope (humans: W+ up, |W-| down uphill)")
    axes[0, 1].set(xlabel="slope (deg)", ylabel="peak positive joint power (W)",
                   title="Peak power over slope (humans: hip uphill)")
    axes[1, 0].set(xlabel="speed (m/s)", ylabel="peak stance knee flexion (deg)",
                   title="Stance knee over speed (humans: rises)")
    axes[1, 0].axvline(2.07, color="grey", ls=":", label="human walk-run 2.07 m/s")
    axes[1, 1].set(xlabel="speed (m/s)", ylabel="peak |torque| (N m)",
                   title="Peak torque over speed (humans: rises)")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(figure_path("gait_trends.png"), dpi=90)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--scenes", nargs="+", default=None)
    args = parser.parse_args()
    scenes = args.scenes or (["walker2d"] if args.quick else ["walker2d", "walker3d"])
    slopes = (-10.0, 0.0, 10.0) if args.quick else SLOPES
    speeds = () if args.quick else SPEEDS
    rows = []
    for scene in scenes:
        rows += [run(scene, "slope", s, {"slope": s}) for s in slopes]
        rows += [run(scene, "speed", v, {"speed": v}) for v in speeds]
        if not args.quick:
            rows.append(run(scene, "speed at a short step", SLOW[0],
                            {"speed": SLOW[0], "step_length": SLOW[1]}))
    write_results("gait_trends", rows, {"time_limit_s": TIME_LIMIT, "slopes_deg": list(slopes),
                                        "speeds_m_s": list(speeds), "slow": list(SLOW)})
    plot(rows)


if __name__ == "__main__":
    main()
