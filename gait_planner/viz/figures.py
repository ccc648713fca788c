"""One-page figure of a recorded plan: what a person looks at before reading numbers.

`plot_recording(mcap, png)` reads the MCAP (`gait_planner.io.mcap_reader`, so any
recording can be plotted, not only fresh plans) and draws `recording_figure`, four blocks:

* a side view of the walker every few nodes, beside the phase schedule: which contact
  points are held when, each phase a coloured band named in the legend with its duration,
  time step and sigma. Every time plot below shades its phases in the same colours.
* the ground force on each foot: normal (solid) and tangential (dashed) per contact point.
* the joints: one row per joint (hip, knee, ankle), the angles of the right and left leg,
  then their torques (JointTrajectory efforts); pitch, roll and yaw of a spherical joint
  keep their colours everywhere (the key beside the block's title); a row shares its y
  axis between the legs.
* the kinetic, potential and total energy, and the continuous-dynamics certificate
  (`gait_planner.verify.continuous`: torque error in % of the peak effort and base
  residual force per node, its limits dashed, contact switches marked).

Every legend sits outside its axes, so none hides data. Written atomically (temporary
file, then rename).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from gait_planner.atomic import atomic_target  # noqa: E402
from gait_planner.io.mcap_reader import RecordedPlan, read_plan_mcap  # noqa: E402
from gait_planner.viz.rerun_series import axis_of, joint_of, side_of  # noqa: E402

__all__ = ["plot_recording", "recording_figure"]

_PHASE_COLOURS = plt.get_cmap("Pastel1").colors
_AXIS_COLOURS = {"pitch": "tab:blue", "roll": "tab:orange", "yaw": "tab:green", "": "tab:blue"}
_POINT_COLOURS = plt.get_cmap("tab10").colors
_OUTSIDE = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0}


# ----------------------------------------------------------------------------- phases


def _phase_runs(rec: RecordedPlan) -> list[tuple[str, int, int]]:
    """[(phase, first interval, end interval)] of the runs of equal phases over intervals
    0..N-1 (interval n: t_n .. t_n+1, phase of node n)."""
    runs: list[tuple[str, int, int]] = []
    for n, phase in enumerate(rec.phases[: len(rec.times) - 1]):
        if runs and runs[-1][0] == phase:
            runs[-1] = (phase, runs[-1][1], n + 1)
        else:
            runs.append((phase, n, n + 1))
    return runs


def _phase_colours(runs) -> dict[str, Any]:
    names = list(dict.fromkeys(name for name, _, _ in runs))
    return {name: _PHASE_COLOURS[i % len(_PHASE_COLOURS)] for i, name in enumerate(names)}


def _shade(ax, rec: RecordedPlan, runs, colours) -> None:
    t = rec.times
    for name, a, b in runs:
        ax.axvspan(t[a], t[b], color=colours[name], alpha=0.45, zorder=0, lw=0)
    ax.set_xlim(t[0], t[-1])


def _schedule(ax, rec: RecordedPlan, runs, colours, contacts: dict[str, str]) -> None:
    """Held contact points as bars over time on the phase bands; the legend names the
    phases with their total duration in the half cycle, time step and sigma."""
    t, h = rec.times, np.diff(rec.times)
    names = list(contacts)
    for row, name in enumerate(names):
        held = [(t[n], h[n]) for n in range(len(h)) if name in rec.active_contacts[n]]
        ax.broken_barh(held, (row - 0.3, 0.6), color="0.25")
    ax.set_yticks(range(len(names)), names)
    ax.set_ylim(len(names) - 0.5, -0.5)
    _shade(ax, rec, runs, colours)
    base = _float(rec.metadata.get("base_time_step"))
    last = len(t) - 2  # the half cycle's duration spans t_0 .. t_(N-1)
    handles = []
    for name in colours:
        lengths = [h[n] for phase, a, b in runs if phase == name
                   for n in range(a, min(b, last))]
        step = float(np.median([h[n] for phase, a, b in runs if phase == name
                                for n in range(a, b)]))
        sigma = f", sigma {step / base:.3g}" if np.isfinite(base) and base > 0 else ""
        span = f"{1e3 * sum(lengths):.0f} ms" if lengths else f"after the {_steps_of(rec)}"
        handles.append(Patch(color=colours[name], label=f"{name}: {span}, "
                             f"h {1e3 * step:.3g} ms{sigma}"))
    ax.axvline(t[last], color="k", ls=":", lw=1.2)
    handles.append(Line2D([], [], color="k", ls=":", lw=1.2,
                          label=f"end of the {_steps_of(rec)}, t = {t[last]:.3f} s"))
    ax.legend(handles=handles, fontsize=8, title="phases (shaded in every time plot):\n"
              "duration, time step h, sigma", title_fontsize=8, **_OUTSIDE)
    ax.set_xlabel("t (s)")
    ax.set_title("held contact points (dark bars) and phases")


def _steps_of(rec: RecordedPlan) -> str:
    """"half cycle", or "3 half cycles" of a recording of joined half cycles."""
    steps = int(_float(rec.metadata.get("steps", 1)))
    return "half cycle" if steps <= 1 else f"{steps} half cycles"


def _float(text: Any) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return float("nan")


# ----------------------------------------------------------------------------- panels


def _side_view(ax, rec: RecordedPlan, bodies: dict) -> None:
    """Each body as the polyline through its named points (world x = phi + X_i d_i; a body
    with one point is drawn from it through its centre of mass and as far again) in the
    x-z plane, every few nodes."""
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


def _foot_forces(axes, rec: RecordedPlan, feet: dict[str, list[str]]) -> None:
    for ax, (body, points) in zip(axes, feet.items()):
        for i, name in enumerate(points):
            f, colour = rec.contact_force(name), _POINT_COLOURS[i % 10]
            label = name.removeprefix(f"{body}_") if name != body else name
            ax.plot(rec.times, f[:, 2], color=colour, label=f"{label}, normal")
            ax.plot(rec.times, np.hypot(f[:, 0], f[:, 1]), "--", color=colour,
                    label=f"{label}, tangential")
        ax.set_ylabel("N")
        ax.set_xlabel("t (s)")
        ax.set_title(f"ground force on {body}")
        ax.legend(fontsize=8, **_OUTSIDE)


def _joint_key(name: str) -> tuple[str, str, str]:
    """(joint, side, axis) of a joint angle name: hip_r_pitch -> (hip, right, pitch)."""
    return joint_of(name), side_of(name), axis_of(name)


def _joints(fig, rec: RecordedPlan) -> None:
    """Rows of joints; columns: angles per side, then torques per side."""
    keys = [_joint_key(n) for n in rec.joint_names]
    joints = list(dict.fromkeys(j for j, _, _ in keys))
    sides = [s for s in ("right", "left", "joints") if any(k[1] == s for k in keys)]
    quantities = (("angle", "deg", np.degrees(rec.positions)), ("torque", "N m", rec.effort))
    axes = fig.subplots(len(joints), 2 * len(sides), squeeze=False, sharex=True)
    for r, joint in enumerate(joints):
        for q, (what, unit, values) in enumerate(quantities):
            row = axes[r, q * len(sides):(q + 1) * len(sides)]
            for ax, side in zip(row, sides):
                for i, (j, s, axis) in enumerate(keys):
                    if j == joint and s == side:
                        ax.plot(rec.times, values[:, i], color=_AXIS_COLOURS[axis], lw=1.3)
                leg = "" if side == "joints" else f", {side}"
                ax.set_title(f"{joint} {what}{leg}", fontsize=9)
                ax.set_ylabel(unit)
                if ax is not row[0]:
                    ax.sharey(row[0])
            for ax in row:
                ax.autoscale(axis="y")
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    axes_used = sorted({a for _, _, a in keys if a})
    if axes_used:
        fig.legend(handles=[Line2D([], [], color=_AXIS_COLOURS[a], label=a) for a in axes_used],
                   loc="outside upper right", ncol=len(axes_used), fontsize=9)
    fig.suptitle("joint angles and torques (JointTrajectory positions and efforts)",
                 fontsize=11)


def _energies(ax, rec: RecordedPlan) -> None:
    T, V = rec.kinetic_energy, rec.potential_energy
    for values, label in ((T, "kinetic"), (V - V[0], "potential - V(0)"),
                          (T + V - V[0], "total - V(0)")):
        ax.plot(rec.times, values, label=label)
    ax.set_ylabel("J")
    ax.set_xlabel("t (s)")
    ax.set_title("energies")
    ax.legend(fontsize=8, **_OUTSIDE)


def _certificate_panel(ax, rec: RecordedPlan, cert: Any) -> None:
    """Per inner node, on one log axis in %: max |torque error| over the joints relative to
    the peak effort, and the base residual force relative to the body weight; the
    certificate's limits dashed, the nodes where the set of held contacts changes as grey
    lines. `cert` is a ContinuousCertificate, or the text of why there is none."""
    ax.set_xlabel("t (s)")
    if isinstance(cert, str):
        ax.text(0.5, 0.5, f"continuous-dynamics certificate unavailable: {cert}",
                ha="center", va="center", transform=ax.transAxes, wrap=True)
        return
    from gait_planner.verify.continuous import LIMITS

    floor = 1e-6  # %: round-off zeros still show on the log scale
    torque = np.maximum(100 * np.abs(cert.torque_error_relative).max(axis=1), floor)
    force = np.maximum(100 * cert.base_force / cert.weight, floor)
    ax.semilogy(cert.times, torque, "o-", ms=3, color="tab:blue",
                label="torque error (max over joints),\n% of peak effort")
    ax.semilogy(cert.times, force, "s-", ms=3, color="tab:red",
                label="base residual force,\n% of body weight")
    ax.axhline(100 * LIMITS["torque"], color="tab:blue", ls="--", lw=0.8,
               label=f"torque limit {100 * LIMITS['torque']:g} %\n"
                     f"({100 * LIMITS['torque_switch']:g} % at switches)")
    ax.axhline(100 * LIMITS["force"], color="tab:red", ls="--", lw=0.8,
               label=f"force limit {100 * LIMITS['force']:g} %\n(away from switches)")
    active = rec.active_contacts
    for n in range(1, len(active)):
        if set(active[n]) != set(active[n - 1]):
            ax.axvline(rec.times[n], color="0.4", lw=0.8)
    ax.plot([], [], color="0.4", lw=0.8, label="contact switch")
    ax.set_ylabel("%")
    ax.set_title(f"continuous dynamics (Pinocchio inverse dynamics; ground wrenches: "
                 f"{cert.wrench_source}): {'OK' if cert.ok else 'FAILED'}")
    ax.legend(fontsize=8, **_OUTSIDE)


def _certificate_of(rec: RecordedPlan) -> Any:
    from gait_planner.verify.recorded import certificate_of_recording

    try:
        return certificate_of_recording(rec)
    except (ValueError, KeyError) as error:
        return str(error)


# ----------------------------------------------------------------------------- the figure


def recording_figure(rec: RecordedPlan) -> plt.Figure:
    """The figure of a decoded recording (module docstring). Close it when done."""
    meta = rec.metadata
    scene = yaml.safe_load(rec.scene_text)
    bodies = {b["name"]: b for b in scene["bodies"]}
    contacts = {c["name"]: c["body"] for c in scene.get("contacts", [])}
    feet: dict[str, list[str]] = {}
    for name, body in contacts.items():
        feet.setdefault(body, []).append(name)
    n_joints = len(dict.fromkeys(_joint_key(n)[0] for n in rec.joint_names))
    runs = _phase_runs(rec)
    colours = _phase_colours(runs)

    fig = plt.figure(figsize=(16, 12 + 2.2 * n_joints), layout="constrained")
    top, forces, joints, bottom = fig.subfigures(
        4, 1, height_ratios=(3.2, 2.2, 2.2 * n_joints + 0.4, 2.6))
    fig.suptitle(f"{meta.get('scene', '?')}: {meta.get('cost', '?')} = "
                 f"{_float(meta.get('cost_value')):.4f}, step {meta.get('step_length')} m, "
                 f"half cycle {_float(meta.get('duration')):.4f} s", fontsize=13)
    side, schedule = top.subplots(1, 2, width_ratios=(1.0, 1.6))
    _side_view(side, rec, bodies)
    _schedule(schedule, rec, runs, colours, contacts)
    force_axes = forces.subplots(1, max(1, len(feet)), squeeze=False, sharey=True)[0]
    _foot_forces(force_axes, rec, feet)
    _joints(joints, rec)
    energy, cert = bottom.subplots(1, 2, width_ratios=(1.0, 1.6))
    _energies(energy, rec)
    _certificate_panel(cert, rec, _certificate_of(rec))
    for ax in (*force_axes, *joints.axes, energy, cert):
        _shade(ax, rec, runs, colours)
    return fig


def plot_recording(mcap: str | Path, png: str | Path) -> Path:
    """Draw the figure of recording `mcap` into `png`; returns the written path."""
    fig = recording_figure(read_plan_mcap(mcap))
    target = Path(png)
    try:
        with atomic_target(target) as tmp:
            fig.savefig(tmp, dpi=80, format="png")
    finally:
        plt.close(fig)
    return target
