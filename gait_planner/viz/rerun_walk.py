"""A walk in rerun (rerun-sdk 0.41): the simulated walker over the planned one.

`save_walk_rrd(result, path, every)` writes, from `walk(..., series=True)` and the plan it
walked (its recording read again, joined as `gait_planner.walk.reference` does), an .rrd
with the layout of `walk_blueprint`. Timeline ``time``: s of the plan's time (`walk.clock`,
paced by the walker's progress), the simulated walker drawn at the plan's time it tracked,
beside the plan's joined half cycles. The simulation is drawn every `every`-th step (200 Hz
at the default step of 0.5 ms), the plan at its nodes. Entities:

* ``world``, ``world/ground``: z up, a grid along the walk (`gait_planner.viz.rerun_draw`);
* ``world/sim/<body>``, ``world/sim/skeleton``: the simulated walker, its body poses from the
  simulated torso pose and joint angles through the planner's own kinematics
  (`gait_planner.model.angles.configuration`); ``world/plan/<body>``, ``world/plan/skeleton``:
  the planned walker, faint, with a grey skeleton;
* ``world/sim/forces`` and ``world/plan/forces``: the ground's force on each contact point in
  contact as arrows, `FORCE_SCALE` m per N (simulated: the sum over the point's two spheres);
* ``plots/joint_angle/<angle>/{sim,plan}`` (deg), ``plots/joint_torque/<angle>/
  {feedforward,feedback}`` (N m), ``plots/ground_force/<contact>/{sim,plan}`` (N, z);
* ``plots/half_cycle/joint_rms`` (deg: the simulated angles against the plan's over each half
  cycle walked), ``plots/half_cycle/torso_drift/{x,y,z}`` and
  ``plots/half_cycle/foot_placement`` (m), the summary's, at each half cycle's end;
* ``plots/half_cycles/<plot>``: grey lines at the half cycles' ends in every plot;
* ``world/sim/touches/<contact>``: the ground touched where the plan has that point in the
  air (`gait_planner.walk.touches`), a red point labelled in its words while it lasts;
* ``walk``: the summary (markdown), with the touches.

Colours: the plan's series light, the simulation's (and the feedback) full; joint angles and
torques by axis (pitch blue, roll orange, yaw green); heel red, forefoot blue.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from gait_planner.atomic import atomic_target
from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.viz.rerun_blueprint import plot_view
from gait_planner.viz.rerun_draw import (Columns, log_bodies, log_boundaries, log_ground,
                                        log_poses, send_scalars, skeleton)
from gait_planner.viz.rerun_series import (AXIS_COLORS, PlotGroup, joint_color, joint_of,
                                          poses, side_of)
from gait_planner.viz.rerun_view import APPLICATION_ID, FORCE_SCALE
from gait_planner.model.angles import configuration, root_angles
from gait_planner.model.scene import InitialPose
from gait_planner.ocp.mirror import contact_partners
from gait_planner.walk.recording import output_path
from gait_planner.walk.reference import Reference
from gait_planner.walk.summary import slid
from gait_planner.walk.touches import described, in_words

__all__ = ["save_walk_rrd", "walk_blueprint"]

_POINT_COLORS = ((214, 39, 40), (31, 119, 180))  # a foot's first (heel) and second point
_PLAN_ALPHA, _PLAN_SKELETON, _SIM_SKELETON = 60, (150, 150, 150), (40, 40, 40)


def _light(color) -> tuple[int, int, int]:
    return tuple(int(c + 0.55 * (255 - c)) for c in color)  # type: ignore[return-value]


def _sim_q(scene, series, ks: np.ndarray) -> np.ndarray:
    """(len(ks), 12 nb) simulated configurations at steps ks: the torso's pose and the joint
    angles (in the plan's angle order) through the planner's kinematics."""
    rows = []
    for k in ks:
        angles, i = {}, 0
        for joint in scene.joints:
            angles[joint.name] = tuple(series["position"][k][i:i + joint.dof])
            i += joint.dof
        torso = series["torso"][k]
        pose = InitialPose(tuple(torso[:3]), root_angles(torso[3:].reshape(3, 3)), angles)
        rows.append(configuration(scene, pose))
    return np.array(rows)


def _plan_forces(rec, ref: Reference) -> np.ndarray:
    """(M, nc, 3) N: the plan's ground force on each contact point at each joined node (zero
    where not held). Half cycle k holds the recorded forces mirrored k times: on the partner
    contact, y negated."""
    names = [c.name for c in ref.scene.contacts]
    partner = contact_partners(ref.scene)
    recorded = {c: rec.contact_force(c) for c in names}
    per = rec.n_nodes - 2  # the nodes each half cycle adds (walk.reference)
    out = np.zeros((len(ref.times), len(names), 3))
    for m in range(len(ref.times)):
        k = min(m // per, ref.steps - 1)
        for j, c in enumerate(names):
            f = recorded[partner[c] if k % 2 else c][m - k * per]
            out[m, j] = f * [1.0, -1.0, 1.0] if k % 2 else f
    return out


def _contact_points(scene, q: np.ndarray) -> np.ndarray:
    """(n, nc, 3) world positions of the contact points in configurations q (n, 12 nb)."""
    phi, D = poses(q)
    return np.stack([phi[:, scene.body_index(c.body)] + D[:, scene.body_index(c.body)]
                     @ np.asarray(scene.body(c.body).points[c.point]) for c in scene.contacts],
                    axis=1)


def _log_walkers(rec, scene, sim_t, sim_q, ground, positions, plan_t, plan_q, plan_f) -> None:
    """Both walkers (bodies, skeleton, force arrows) at their times (s): the simulated one at
    configurations sim_q (n, 12 nb) with ground forces (n, nc, 3) N on its contact points
    at `positions` (n, nc, 3) m; the planned one at plan_q (M, 12 nb) with forces plan_f."""
    contacts = [c.name for c in scene.contacts]
    plan_points = _contact_points(scene, plan_q)
    for name, t, q, forces, points, color in (
            ("sim", sim_t, sim_q, ground, positions, _SIM_SKELETON),
            ("plan", plan_t, plan_q, plan_f, plan_points, _PLAN_SKELETON)):
        log_bodies(rec, scene, f"world/{name}", *(() if name == "sim" else (_PLAN_ALPHA,)))
        indexes = [rr.TimeColumn("time", duration=t)]
        phi, D = poses(q)
        log_poses(rec, f"world/{name}", [b.name for b in scene.bodies], indexes, phi, D)
        bones, arrows = Columns(indexes), Columns(indexes)
        for n in range(len(t)):
            bones.add(strips=skeleton(scene, phi[n], D[n]))
            held = [j for j in range(len(contacts)) if forces[n, j, 2] > 0]
            arrows.add(origins=list(points[n, held]), vectors=list(forces[n, held] * FORCE_SCALE),
                       labels=[f"{contacts[j]}: {np.linalg.norm(forces[n, j]):.0f} N"
                               for j in held])
        bones.send(rec, f"world/{name}/skeleton", rr.LineStrips3D, radii=0.006, colors=color)
        arrows.send(rec, f"world/{name}/forces", rr.Arrows3D, radii=0.008,
                    colors=(20, 160, 60) if name == "sim" else (150, 220, 160), show_labels=False)


def _log_touches(rec, scene, series, touches: list[dict[str, Any]]) -> None:
    """Each unplanned touch as a red point where the simulated contact point was when it
    began, from its start to its end (s)."""
    names = [c.name for c in scene.contacts]
    for touch in touches:
        j = names.index(touch["point"])
        k = int(np.argmin(np.abs(series["time"] - touch["start_s"])))
        path = f"world/sim/touches/{touch['point']}"
        rec.set_time("time", duration=touch["start_s"])
        rec.log(path, rr.Points3D([series["contact_position"][k, j]], radii=0.02,
                                  colors=(230, 30, 30),
                                  labels=[f"{in_words(touch)}, {touch['peak_n']:.0f} N"]))
        rec.set_time("time", duration=touch["end_s"] + 0.02)
        rec.log(path, rr.Clear(recursive=False))
    rec.reset_time()


def _groups(scene, names) -> list[PlotGroup]:
    """The plots: per joint and leg its angles (sim, plan) and torques (feed-forward,
    feedback); per foot its points' normal forces; the three per-half-cycle errors."""
    joints: dict[tuple[str, str], list[str]] = {}
    for name in names:
        joints.setdefault((joint_of(name), side_of(name)), []).append(name)
    groups = [PlotGroup(f"{kind}_{j}_{s}", f"{j}{'' if s == 'joints' else ' ' + s[0].upper()} "
                        f"{title}", tuple(f"plots/{kind}/{a}/{part}" for a in angles
                                          for part in parts), "half_cycles")
              for kind, title, parts in (("joint_angle", "(deg)", ("sim", "plan")),
                                         ("joint_torque", "(N m)", ("feedforward", "feedback")))
              for (j, s), angles in joints.items()]
    feet: dict[str, list[str]] = {}
    for c in scene.contacts:
        feet.setdefault(c.body, []).append(c.name)
    groups += [PlotGroup(f"ground_force_{body}", f"normal force on {body} (N): sim full, plan "
                         "light; heel red, forefoot blue",
                         tuple(f"plots/ground_force/{c}/{part}" for c in points
                               for part in ("sim", "plan")), "half_cycles")
               for body, points in feet.items()]
    return groups + [PlotGroup(key, title, paths, "half_cycles") for key, title, paths in (
        ("joint_rms", "joint RMS per half cycle (deg)", ("plots/half_cycle/joint_rms",)),
        ("torso_drift", "torso drift per half cycle (m): x red, y green, z blue",
         tuple(f"plots/half_cycle/torso_drift/{a}" for a in "xyz")),
        ("foot_placement", "foot placement error per half cycle (m)",
         ("plots/half_cycle/foot_placement",)))]


def _color(scene, path: str) -> tuple[int, int, int]:
    parts = path.split("/")
    if parts[1] == "half_cycle":
        return AXIS_COLORS["xyz".index(parts[3])] if len(parts) > 3 else (40, 40, 40)
    if parts[1] == "ground_force":
        body = scene.contact(parts[2]).body
        base = _POINT_COLORS[[c.name for c in scene.contacts if c.body == body].index(parts[2])]
    else:
        base = joint_color(parts[2])
    return _light(base) if parts[3] in ("plan", "feedforward") else base


def _summary(result: dict[str, Any]) -> str:
    rows = "".join(f"| {k + 1} | {rms:.2f} | {' '.join(f'{v:+.3f}' for v in d)} | {p:.3f} |\n"
                   for k, (rms, d, p) in enumerate(zip(result["joint_rms_per_half_cycle_deg"],
                                                       result["torso_drift_m"],
                                                       result["foot_placement_error_m"])))
    return (f"# {result['scene']}: walked {result['half_cycles_walked']} of {result['steps']} "
            f"half cycles\n\n{result['stopped']} ({result['recording']})\n\n"
            f"joint RMS {result['joint_rms_deg']:.2f} deg (max {result['joint_max_deg']:.2f}), "
            f"feedback share {100 * result['feedback_share']:.0f} %\n\n"
            f"unplanned touches: {described(result['unplanned_touches'])}\n\n"
            f"largest foot slide: {slid(result['foot_slide'])}\n\n"
            "3D: the simulated walker solid, the plan faint (grey skeleton); ground forces "
            "green (plan light), 1.5 mm per N. Plots: the plan light, the simulation full.\n\n"
            "| half cycle | joint RMS (deg) | torso drift x y z (m) | foot placement (m) |\n"
            f"|---|---|---|---|\n{rows}")


def walk_blueprint(groups: list[PlotGroup]) -> rrb.Blueprint:
    """The 3D view (camera following the simulated torso) over the summary and the errors
    per half cycle; beside it a row per joint (angles per leg, then torques per leg), then
    the feet's normal forces."""
    plots = {g.key: plot_view(g) for g in groups}
    errors = [plots.pop(k) for k in ("joint_rms", "torso_drift", "foot_placement")]
    rows: dict[str, list] = {}
    for g in groups:
        if g.key.startswith(("joint_angle_", "joint_torque_")):
            rows.setdefault(joint_of(g.paths[0].split("/")[2]), []).append(plots.pop(g.key))
    eye = rrb.EyeControls3D(kind="Orbital", position=(1.5, -2.1, 1.3), look_target=(0, 0, 0.6),
                            eye_up=(0.0, 0.0, 1.0), tracking_entity="/world/sim/torso")
    left = rrb.Vertical(
        rrb.Spatial3DView(origin="/world", name="walk: simulated (solid) over plan (faint)",
                          eye_controls=eye, line_grid=rrb.LineGrid3D(visible=False)),
        rrb.Horizontal(rrb.TextDocumentView(origin="/walk", name="walk summary"),
                       rrb.Vertical(*errors)), row_shares=[3.0, 2.0])
    right = rrb.Vertical(*(rrb.Horizontal(*row) for row in rows.values()),
                         rrb.Horizontal(*plots.values()))
    return rrb.Blueprint(rrb.Horizontal(left, right, column_shares=[1.0, 1.5]),
                         rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="hidden"),
                         rrb.TimePanel(state="collapsed", timeline="time"),
                         auto_layout=False, auto_views=False)


def _values(result: dict[str, Any], ref: Reference, plan_f: np.ndarray, ks: np.ndarray):
    """{plot path: (times s, values)} of every series of `_groups`."""
    series = result["series"]
    time = series["time"]
    values: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for a, name in enumerate(series["joint_names"]):
        values[f"plots/joint_angle/{name}/sim"] = time[ks], np.degrees(series["position"][ks, a])
        values[f"plots/joint_angle/{name}/plan"] = ref.times, np.degrees(ref.angles[:, a])
        for part in ("feedforward", "feedback"):
            values[f"plots/joint_torque/{name}/{part}"] = time[ks], series[part][ks, a]
    for j, c in enumerate(ref.scene.contacts):
        values[f"plots/ground_force/{c.name}/sim"] = time[ks], series["ground_force"][ks, j, 2]
        values[f"plots/ground_force/{c.name}/plan"] = ref.times, plan_f[:, j, 2]
    walked = ref.period * np.arange(1, result["half_cycles_walked"] + 1)
    values["plots/half_cycle/joint_rms"] = walked, np.array(result["joint_rms_per_half_cycle_deg"])
    drift = np.array(result["torso_drift_m"]).reshape(-1, 3)
    for a, axis in enumerate("xyz"):
        values[f"plots/half_cycle/torso_drift/{axis}"] = walked, drift[:, a]
    values["plots/half_cycle/foot_placement"] = walked, np.array(result["foot_placement_error_m"])
    return values


def _log_plots(rec, scene, groups: list[PlotGroup], values, ends: np.ndarray) -> None:
    for g in groups:
        for p in g.paths:
            color = _color(scene, p)
            rec.log(p, rr.SeriesLines(colors=color, widths=1.5,
                                      names=p.split("/", 2)[2].replace("/", " ")), static=True)
            if p.startswith("plots/half_cycle/"):  # a few values: marked
                rec.log(p, rr.SeriesPoints(colors=color, marker_sizes=3.0), static=True)
            send_scalars(rec, p, *values[p])
        data = np.concatenate([values[p][1] for p in g.paths] + [[0.0]])
        log_boundaries(rec, g, data, ends, "half cycle ends")


def save_walk_rrd(result: dict[str, Any], path: str | os.PathLike, every: int = 10) -> Path:
    """Write the walk `result` (with its "series") as an .rrd to `path` atomically (module
    docstring); the absolute path. ValueError if the folder does not exist."""
    target = output_path(path)
    series = {**result["series"], "time": result["series"]["plan_time"]}  # module docstring
    result = {**result, "series": series}
    plan = read_plan_mcap(result["recording"])
    ref = Reference.from_recording(plan, result["steps"])
    scene = ref.scene
    n = len(series["time"])
    ks = np.unique(np.r_[np.arange(0, n, every), n - 1]).astype(int)
    plan_f = _plan_forces(plan, ref)
    values = _values(result, ref, plan_f, ks)
    groups = _groups(scene, series["joint_names"])
    rec = rr.RecordingStream(APPLICATION_ID)
    rec.send_recording_name(f"walk of {scene.name}: {result['half_cycles_walked']} of "
                            f"{result['steps']} half cycles")
    with atomic_target(target) as tmp:
        try:
            rec.save(tmp)
            rec.send_blueprint(walk_blueprint(groups))
            log_ground(rec, float(ref.q[-1].reshape(-1, 12)[:, 0].max()) + 1.0)
            _log_walkers(rec, scene, series["time"][ks], _sim_q(scene, series, ks),
                         series["ground_force"][ks], series["contact_position"][ks],
                         ref.times, ref.q, plan_f)
            _log_plots(rec, scene, groups, values,
                       ref.period * np.arange(1, result["steps"] + 1))
            _log_touches(rec, scene, series, result["unplanned_touches"])
            rec.log("walk", rr.TextDocument(_summary(result),
                                            media_type=rr.MediaType.MARKDOWN), static=True)
            rec.flush()
        finally:
            rec.disconnect()
    return target
