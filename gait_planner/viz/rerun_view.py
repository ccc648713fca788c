"""A plan in rerun (rerun-sdk 0.41): the moving walker, contact forces and time series.

Entities (timeline ``time``: s from the start of the half cycle, duration type; timeline
``node``: the node index):

* ``world``: z up; ``world/ground``: a grid on the ground the plan was made for
  (`PlanResult.ground`: z = 0, a ramp's tilted plane, or stairs, whose treads are boxes at
  ``world/ground/treads``), over the plan's x range (level ground: -1.5 to 1.5 m).
* ``world/robot``: for a scene drafted from a URDF, the robot's own meshes moved by /tf
  (`gait_planner.viz.rerun_robot`) instead of ``world/walker``.
* ``world/walker/<body>``: the body's drawing primitive (`gait_planner.io.urdf.body_shapes`,
  box or cylinder, in body coordinates, partly transparent), placed per node by a
  Transform3D (the COM phi and the directors [d1 d2 d3] from q); ``world/skeleton``: line
  segments COM -> joint point -> COM along every joint and heel -> forefoot on every foot;
  ``world/com``: body COMs; ``world/com_total``: the whole-body centre of mass.
* ``world/trails/<contact>``: each contact point's path up to the node (right foot red,
  left blue); ``world/trails/com``: the whole-body centre of mass's path and its vertical
  projection on the ground.
* ``world/contacts/points`` and ``world/contacts/forces``: the active contact points and
  the ground forces on them as arrows, `FORCE_SCALE` m per N (1.5 mm/N);
  ``world/contacts/wrenches`` and ``world/contacts/centers_of_pressure``: per foot in
  contact, its net ground force drawn from its centre of pressure
  (`gait_planner.io.messages.foot_wrenches`; the label gives the free moment).
* ``phase``: the gait phase (StateChange at each phase start).
* ``plots/...``: the time series of `gait_planner.viz.rerun_series` (joint angles and
  torques, contact forces and roll moments, energies, angular momentum about the centre of
  mass, phase boundaries) as Scalars with their SeriesLines style.
* ``plan``: a text summary (cost, duration, step length, sigma, solver statistics).

`save_rrd` and `show` also send the layout of `gait_planner.viz.rerun_blueprint` as the
recording's active and default blueprint, so the saved .rrd opens in it.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import rerun as rr

from gait_planner.atomic import atomic_target
from gait_planner.io.messages import contact_points, foot_wrenches
from gait_planner.viz.rerun_blueprint import blueprint
from gait_planner.viz.rerun_robot import log_robot_model, log_robot_motion
from gait_planner.viz.rerun_draw import (Columns, log_bodies, log_boundaries, log_ground,
                                        log_poses, send_scalars, skeleton)
from gait_planner.viz.rerun_series import (COLOUR_KEY, phase_boundaries, plot_groups, poses,
                                          series_color, series_name, series_values, side_of,
                                          whole_body_com)
from gait_planner.result import PlanResult

__all__ = ["FORCE_SCALE", "APPLICATION_ID", "log_plan", "save_rrd", "show"]

APPLICATION_ID = "gait_planner"
FORCE_SCALE = 1.5e-3  # m of arrow per N of force
_CONTACT_COLOR = (20, 160, 60)
_WRENCH_COLOR = (230, 120, 0)
_SKELETON_COLOR = (40, 40, 40)
_COM_TRAIL_COLOR = (190, 0, 170)
_SIDE_COLORS = {"right": (200, 60, 60), "left": (50, 90, 200)}


def _log_static(result: PlanResult, rec: rr.RecordingStream) -> None:
    if result.ground.level:
        log_ground(rec)
    else:  # over the plan's x range (a joined plan climbs a tread per half cycle)
        phi, _ = poses(result.q)
        log_ground(rec, float(phi[..., 0].max()) + 1.0, result.ground)
    if result.scene.robot is not None:  # the robot itself, not the draft's primitives
        log_robot_model(rec, result)
    else:
        log_bodies(rec, result.scene, "world/walker")
    stats = result.stats
    sigma = ", ".join(f"{s:.4f}" for s in result.phase_scaling)
    summary = (
        f"# {result.scene.name}: {'success' if result.success else 'FAILED'}\n\n"
        f"{result.message}\n\n"
        f"Plot colours: {COLOUR_KEY}\n\n"
        f"| | |\n|---|---|\n| cost ({result.cost_name}) | {result.cost_value:.6g} |\n"
        f"| step length | {result.step_length:.4f} m |\n| duration | {result.duration:.4f} s |\n"
        f"| phase scaling | {sigma} |\n| friction coefficient | {result.friction_coefficient} |\n"
        f"| nodes | {result.n_nodes} |\n| solver | {stats.status}, {stats.iterations} "
        f"iterations, {stats.solve_time:.2f} s |\n"
        f"| max constraint violation | {stats.max_constraint_violation:.3g} m |\n"
        f"| max dynamics residual | {stats.max_dynamics_residual:.3g} |\n")
    rec.log("plan", rr.TextDocument(summary, media_type=rr.MediaType.MARKDOWN), static=True)


def _trail_points(result: PlanResult) -> dict[str, np.ndarray]:
    """Contact name -> (N+1, 3) world path of the contact point."""
    names = [c.name for c in result.scene.contacts]
    paths = np.array([contact_points(result, n, names) for n in range(result.n_nodes)])
    return {name: paths[:, k] for k, name in enumerate(names)}


def _contact_rows(result: PlanResult, n: int) -> dict[str, list]:
    """Node n's contact points and point forces, and per foot its net force drawn from its
    centre of pressure (the wrench of `foot_wrenches`), as lists of instances."""
    names = list(result.active_contacts[n])
    points = np.array(contact_points(result, n, names)).reshape(-1, 3)
    forces = np.array([np.asarray(result.contact_forces[c], dtype=float)[n]
                       for c in names]).reshape(-1, 3)
    wrenches = foot_wrenches(result, n)
    return {
        "points": list(points), "point_labels": names, "forces": list(forces * FORCE_SCALE),
        "force_labels": [f"{c}: {np.linalg.norm(f):.0f} N" for c, f in zip(names, forces)],
        "cops": [w[4] for w in wrenches], "feet": [w[0] for w in wrenches],
        "totals": [w[2] * FORCE_SCALE for w in wrenches],
        # the free moment: the wrench's moment about the COP, z
        "wrench_labels": [f"{body}: {np.linalg.norm(F):.0f} N, free moment "
                          f"{(M + np.cross(r - cop, F))[2]:.2f} N m"
                          for body, r, F, M, cop in wrenches]}


def _log_motion(result: PlanResult, rec: rr.RecordingStream) -> None:
    """The walker, skeleton, trails and contacts at every node, each entity one columnar
    chunk (timelines time and node): the same data as logging node after node, about 0.1 s
    faster per recording of walker3d (615 log calls)."""
    phi, D = poses(result.q)
    com = whole_body_com(result, phi)
    below = com * [1.0, 1.0, 0.0]  # the centre of mass on the ground, 2 mm above the grid
    below[:, 2] += result.ground.height(com[:, 0]) + 0.002
    trails = _trail_points(result)
    side = {c.name: side_of(c.body) for c in result.scene.contacts}
    t = np.asarray(result.times, dtype=float) - float(result.times[0])
    nodes = np.arange(result.n_nodes)
    indexes = [rr.TimeColumn("time", duration=t), rr.TimeColumn("node", sequence=nodes)]
    if result.scene.robot is not None:
        log_robot_motion(rec, result)
    else:
        log_poses(rec, "world/walker", result.body_names, indexes, phi, D)
    names = ("skeleton", "com", "com_total", "trail_com", *trails, "points", "forces", "cops",
             "wrenches")
    columns = {name: Columns(indexes) for name in names}
    for n in nodes:
        columns["skeleton"].add(strips=skeleton(result.scene, phi[n], D[n]))
        columns["com"].add(positions=list(phi[n]), labels=list(result.body_names))
        columns["com_total"].add(positions=[com[n]], labels=["centre of mass"])
        columns["trail_com"].add(strips=[com[: n + 1], below[: n + 1]])
        for name, path in trails.items():
            columns[name].add(strips=[path[: n + 1]])
        c = _contact_rows(result, n)
        columns["points"].add(positions=c["points"], labels=c["point_labels"])
        columns["forces"].add(origins=c["points"], vectors=c["forces"],
                              labels=c["force_labels"])
        columns["cops"].add(positions=c["cops"], labels=c["feet"])
        columns["wrenches"].add(origins=c["cops"], vectors=c["totals"],
                                labels=c["wrench_labels"])
    hidden = {"show_labels": False}
    columns["skeleton"].send(rec, "world/skeleton", rr.LineStrips3D, radii=0.006,
                             colors=_SKELETON_COLOR)
    columns["com"].send(rec, "world/com", rr.Points3D, radii=0.015, colors=_SKELETON_COLOR,
                        **hidden)
    columns["com_total"].send(rec, "world/com_total", rr.Points3D, radii=0.025,
                              colors=_COM_TRAIL_COLOR, **hidden)
    columns["trail_com"].send(rec, "world/trails/com", rr.LineStrips3D, radii=[0.007, 0.004],
                              colors=_COM_TRAIL_COLOR)
    for name in trails:
        columns[name].send(rec, f"world/trails/{name}", rr.LineStrips3D, radii=0.005,
                           colors=_SIDE_COLORS.get(side[name], _SKELETON_COLOR))
    columns["points"].send(rec, "world/contacts/points", rr.Points3D, radii=0.012,
                           colors=_CONTACT_COLOR, **hidden)
    columns["forces"].send(rec, "world/contacts/forces", rr.Arrows3D, radii=0.006,
                           colors=_CONTACT_COLOR, **hidden)
    columns["cops"].send(rec, "world/contacts/centers_of_pressure", rr.Points3D, radii=0.02,
                         colors=_WRENCH_COLOR, **hidden)
    columns["wrenches"].send(rec, "world/contacts/wrenches", rr.Arrows3D, radii=0.012,
                             colors=_WRENCH_COLOR, **hidden)
    phases = list(result.phases)
    changes = [n for n in range(result.n_nodes) if n == 0 or phases[n] != phases[n - 1]]
    rec.send_columns("phase", indexes=[rr.TimeColumn("time", duration=t[changes])],
                     columns=rr.StateChange.columns(state=[phases[n] for n in changes]))


def _log_series(result: PlanResult, rec: rr.RecordingStream) -> None:
    t = np.asarray(result.times, dtype=float) - float(result.times[0])
    values = series_values(result)
    boundaries = phase_boundaries(result)
    for group in plot_groups(result):
        for path in group.paths:
            rec.log(path, rr.SeriesLines(colors=series_color(result, path),
                                         names=series_name(result, path),
                                         widths=1.5), static=True)
            send_scalars(rec, path, t, values[path])
        log_boundaries(rec, group, np.concatenate([values[p] for p in group.paths]),
                       boundaries, "phase boundaries")


def log_plan(result: PlanResult, recording: rr.RecordingStream) -> None:
    """Log `result` to `recording` (module docstring for the entities)."""
    _log_static(result, recording)
    _log_motion(result, recording)
    _log_series(result, recording)


def _recording(result: PlanResult) -> rr.RecordingStream:
    rec = rr.RecordingStream(APPLICATION_ID)
    rec.send_recording_name(f"{result.scene.name} {result.cost_name} "
                            f"step {result.step_length:.4f} m")
    return rec


def save_rrd(result: PlanResult, path: str | os.PathLike) -> Path:
    """Write `result` as a rerun recording (.rrd) to `path`, atomically (a temporary file
    in the same folder is renamed when complete); return the absolute path."""
    target = Path(path).expanduser().resolve()
    rec = _recording(result)
    with atomic_target(target) as tmp:
        try:
            rec.save(tmp)
            rec.send_blueprint(blueprint(result))  # active and the default: part of the file
            log_plan(result, rec)
            rec.flush()
        finally:
            rec.disconnect()  # closes the file sink: footer written, nothing more to come
    return target


def show(result: PlanResult) -> rr.RecordingStream:
    """Spawn a rerun viewer (the `rerun` executable of rerun-sdk) and stream `result` to it.

    Raises RuntimeError when no viewer can be shown (a Linux machine without a display);
    use `save_rrd` and open the file elsewhere (``rerun plan.rrd``) instead.
    """
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        raise RuntimeError("no display (DISPLAY/WAYLAND_DISPLAY unset) to show a rerun viewer "
                           "on; save the plan with save_rrd() and open it with `rerun FILE.rrd`")
    rec = _recording(result)
    rec.spawn()
    rec.send_blueprint(blueprint(result))
    log_plan(result, rec)
    rec.flush()
    return rec
