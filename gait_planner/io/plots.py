"""One-page figure of a recorded plan: what a person looks at before reading numbers.

`plot_recording(mcap, png)` reads the MCAP (`gait_planner.io.mcap_reader`, so any
recording can be plotted, not only fresh plans) and draws, over the half cycle, with the
phases shaded: a side view of the walker every few nodes, the joint angles, the joint
torques (JointTrajectory efforts), the vertical and tangential ground forces per contact
point, the kinetic, potential and total energy, the time steps and, across the bottom, the
continuous-dynamics certificate (`gait_planner.verify.continuous`: torque error in % of the
peak effort and base residual force per node, contact switches marked). Written atomically
(temporary file, then rename).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

from gait_planner.io.atomic import atomic_target  # noqa: E402
from gait_planner.io.mcap_reader import RecordedPlan, read_plan_mcap  # noqa: E402

_COLOURS = plt.get_cmap("tab20").colors


def _shade_phases(ax, rec: RecordedPlan) -> None:
    """Every other phase shaded grey."""
    t, phases = rec.times, list(rec.phases)
    start, run = 0, 0
    for n in range(1, len(phases) + 1):
        if n == len(phases) or phases[n] != phases[start]:
            ax.axvspan(t[start], t[min(n, len(t) - 1)], color="0.92" if run % 2 else "white",
                       zorder=0, lw=0)
            start, run = n, run + 1


def _side_view(ax, rec: RecordedPlan) -> None:
    """Each body as the polyline through its named points (world x = phi + X_i d_i; a body
    with one point is drawn from it through its centre of mass and as far again) in the
    x-z plane, every few nodes."""
    bodies = {b["name"]: b for b in yaml.safe_load(rec.scene_text)["bodies"]}
    every = max(1, (len(rec.times) - 1) // 8)
    for n in range(0, len(rec.times), every):
        colour = plt.cm.viridis(0.1 + 0.8 * n / max(1, len(rec.times) - 1))
        for b, name in enumerate(rec.body_names):
            phi = rec.q[n, 12 * b : 12 * b + 3]
            D = rec.q[n, 12 * b + 3 : 12 * b + 12].reshape(3, 3).T
            X = np.array(list(bodies[name].get("points", {}).values()), dtype=float)
            if len(X) == 0:
                continue
            if len(X) == 1:
                X = np.vstack([X[0], -X[0]])
            elif len(X) == 2 and abs(X[0, 2] - X[1, 2]) < 1e-9:  # side by side (hips)
                mid = X.mean(axis=0)
                X = np.vstack([X[0], mid, -mid, mid, X[1]])
            elif len(X) >= 3:
                X = np.vstack([X, X[:1]])
            world = phi + X @ D.T
            ax.plot(world[:, 0], world[:, 2], color=colour, lw=1.5)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_title("side view every few nodes (darker = earlier)")


def _lines(ax, t, values, names, ylabel, title) -> None:
    for i, name in enumerate(names):
        ax.plot(t, values[:, i], label=name, color=_COLOURS[i % len(_COLOURS)], lw=1.2)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=6, ncol=2, loc="best")


def _rounded(csv: str) -> str:
    try:
        return ", ".join(f"{float(v):.4f}" for v in csv.split(","))
    except ValueError:
        return csv


def _certificate_panel(ax, rec: RecordedPlan, cert: Any) -> None:
    """Per inner node, on one log axis in %: max |torque error| over the joints relative to
    the peak effort, and the base residual force relative to the body weight; the
    certificate's limits dashed, the nodes where the set of held contacts changes as grey
    lines. `cert` is a ContinuousCertificate, or the text of why there is none."""
    ax.set_xlabel("t (s)")
    if isinstance(cert, str):
        ax.text(0.5, 0.5, f"continuous-dynamics certificate unavailable: {cert}",
                ha="center", va="center", transform=ax.transAxes)
        return
    from gait_planner.verify.continuous import LIMITS

    floor = 1e-6  # %: round-off zeros still show on the log scale
    torque = np.maximum(100 * np.abs(cert.torque_error_relative).max(axis=1), floor)
    force = np.maximum(100 * cert.base_force / cert.weight, floor)
    ax.semilogy(cert.times, torque, "o-", ms=3, color="tab:blue",
                label="torque error (max over joints), % of peak effort")
    ax.semilogy(cert.times, force, "s-", ms=3, color="tab:red",
                label="base residual force, % of body weight")
    ax.axhline(100 * LIMITS["torque"], color="tab:blue", ls="--", lw=0.8,
               label=f"torque limit {100 * LIMITS['torque']:g} % "
                     f"({100 * LIMITS['torque_switch']:g} % at switches)")
    ax.axhline(100 * LIMITS["force"], color="tab:red", ls="--", lw=0.8,
               label=f"force limit {100 * LIMITS['force']:g} % (away from switches)")
    active = rec.active_contacts
    for n in range(1, len(active)):
        if set(active[n]) != set(active[n - 1]):
            ax.axvline(rec.times[n], color="0.5", lw=0.8)
    ax.set_ylabel("%")
    ax.set_title(f"continuous dynamics (Pinocchio inverse dynamics; ground wrenches: "
                 f"{cert.wrench_source}): {'OK' if cert.ok else 'FAILED'}; grey lines: "
                 f"contact switches", fontsize=9)
    ax.legend(fontsize=7, loc="best", ncol=2)


def _certificate_of(rec: RecordedPlan) -> Any:
    from gait_planner.verify.continuous import certificate_of_recording

    try:
        return certificate_of_recording(rec)
    except (ValueError, KeyError) as error:
        return str(error)


def plot_recording(mcap: str | Path, png: str | Path, certificate: Any = None) -> Path:
    """Draw the figure of recording `mcap` into `png`; returns the written path.
    `certificate`: its ContinuousCertificate if already computed (else computed here)."""
    rec = read_plan_mcap(mcap)
    meta = rec.metadata
    t = rec.times
    fig = plt.figure(figsize=(13, 14), constrained_layout=True)
    grid = fig.add_gridspec(4, 2, height_ratios=(1.0, 1.0, 1.0, 0.8))
    axes = np.array([[fig.add_subplot(grid[r, c]) for c in range(2)] for r in range(3)])
    bottom = fig.add_subplot(grid[3, :])
    fig.suptitle(f"{meta.get('scene', '?')}: {meta.get('cost', '?')} = "
                 f"{float(meta.get('cost_value', 'nan')):.4f}, step {meta.get('step_length')} m, "
                 f"half cycle {float(meta.get('duration', 'nan')):.4f} s, "
                 f"sigma = {_rounded(meta.get('phase_scaling', ''))}")
    _side_view(axes[0, 0], rec)

    ax = axes[0, 1]
    for name in sorted({c for names in rec.contact_names for c in names}):
        f = rec.contact_force(name)
        i = len(ax.lines) // 2
        ax.plot(t, f[:, 2], color=_COLOURS[2 * i % 20], label=f"{name} normal")
        ax.plot(t, np.hypot(f[:, 0], f[:, 1]), "--", color=_COLOURS[(2 * i + 1) % 20],
                label=f"{name} tangential")
    ax.set_ylabel("N")
    ax.set_title("ground force per contact point")
    ax.legend(fontsize=6)

    names = rec.joint_names
    _lines(axes[1, 0], t, np.degrees(rec.positions), names, "deg", "joint angles")
    _lines(axes[1, 1], t, rec.effort, names, "N m", "joint torques (efforts)")

    ax = axes[2, 0]
    T, V = rec.kinetic_energy, rec.potential_energy
    for values, label in ((T, "kinetic"), (V - V[0], "potential - V(0)"),
                          (T + V - V[0], "total - V(0)")):
        ax.plot(t, values, label=label)
    ax.set_ylabel("J")
    ax.set_title("energies")
    ax.legend(fontsize=7)

    ax = axes[2, 1]
    steps = np.diff(t) * 1e3
    ax.plot(t[:-1], steps, drawstyle="steps-post")
    ax.set_ylim(0.0, 1.15 * steps.max())
    ax.set_ylabel("time step (ms)")
    ax.set_title("time steps (base step x sigma of the phase)")
    _certificate_panel(bottom, rec, _certificate_of(rec) if certificate is None else certificate)
    for ax in (*axes[1], *axes[2], axes[0, 1], bottom):
        _shade_phases(ax, rec)
        ax.set_xlabel("t (s)")

    target = Path(png)
    try:
        with atomic_target(target) as tmp:
            fig.savefig(tmp, dpi=90, format="png")
    finally:
        plt.close(fig)
    return target
