"""The layout of a plan's rerun view (rerun-sdk 0.41): `blueprint`.

A large 3D view beside the plots of `gait_planner.viz.rerun_series.plot_groups`, one row per
joint (angles of the right and left leg, then their torques)::

    +-------------------------------+---------+---------+---------+---------+
    |                               | hip R   | hip L   | hip R   | hip L   |
    | walker (3D): bodies, skeleton,| (deg)   | (deg)   | (N m)   | (N m)   |
    | foot and centre-of-mass       +---------+---------+---------+---------+
    | trails, point forces, foot    | knee ...                              |
    | wrenches at the centres of    +---------+---------+---------+---------+
    | pressure                      | ankle ...                             |
    +-------------------------------+-------------------+-------------------+
    | phases (state timeline)       | ground force,     | ground force,     |
    +---------------+---------------+ foot_r            | foot_l            |
    | solve summary | roll moments  +-------------------+-------------------+
    |  (colour key) |               | energy            | angular momentum  |
    +---------------+---------------+-------------------+-------------------+

(compass: one joint-angle and one torque plot; planar scenes: no roll moments). No plot
shows a legend: rerun 0.41 draws a legend inside the plot, in a corner (`rrb.PlotLegend`
has only `corner` and `visible`), where it covers the lines of plots this small. Instead a
plot holds the series of one joint of one leg (pitch, roll, yaw: the same three colours
in every joint plot), a title names its series' colours where there is room (forces,
energy, angular momentum, roll moments), the solve summary holds the colour key of all
plots (`rerun_series.COLOUR_KEY`), and hovering a line shows its name. The time axes of
all plots are linked (zooming one zooms all), and every plot marks the phase boundaries.
The blueprint and time panels start collapsed, the selection panel hidden, the time panel
on the ``time`` timeline.
"""

from __future__ import annotations

import numpy as np
import rerun.blueprint as rrb

from gait_planner.viz.rerun_series import (PlotGroup, joint_of, plot_groups, poses,
                                          whole_body_com)
from gait_planner.result import PlanResult

__all__ = ["blueprint", "plot_view"]


def plot_view(group: PlotGroup) -> rrb.TimeSeriesView:
    """A plot of the group's series and its boundary lines, without legend, its time axis
    linked to every other plot's."""
    return rrb.TimeSeriesView(
        origin="/plots", name=group.title,
        contents=[f"+ /{p}" for p in (*group.paths, group.boundary_path)],
        axis_x=rrb.TimeAxis(link="LinkToGlobal"), plot_legend=rrb.PlotLegend(visible=False))


def _eye(result: PlanResult) -> rrb.EyeControls3D:
    """A camera in front of the walker and to its right, looking at the middle of its path
    (distances scaled by the mean height h of the centre of mass; walker3d: h = 1.0 m)."""
    com = whole_body_com(result, poses(result.q)[0])
    h = float(com[:, 2].mean())
    target = np.array([0.5 * (com[0, 0] + com[-1, 0]), float(com[:, 1].mean()), 0.6 * h])
    return rrb.EyeControls3D(kind="Orbital", position=target + h * np.array([1.5, -2.1, 0.8]),
                             look_target=target, eye_up=(0.0, 0.0, 1.0))


def blueprint(result: PlanResult) -> rrb.Blueprint:
    """The layout of the module docstring for `result`'s recording."""
    groups = plot_groups(result)
    plots = {g.key: plot_view(g) for g in groups}
    joint_rows: dict[str, list] = {}  # joint -> angles per side, then torques per side
    for g in groups:
        if g.key.startswith(("joint_angle_", "joint_torque_")):
            joint_rows.setdefault(joint_of(g.paths[0].split("/")[2]), []).append(plots.pop(g.key))
    rows = list(joint_rows.values())
    rows.append([plots.pop(k) for k in list(plots) if k.startswith("contact_force_")])
    rows.append([plots.pop("energy"), plots.pop("angular_momentum")])
    bottom = [rrb.TextDocumentView(origin="/plan", name="solve summary"), *plots.values()]
    left = rrb.Vertical(
        rrb.Spatial3DView(origin="/world", name="walker", eye_controls=_eye(result),
                          line_grid=rrb.LineGrid3D(visible=False)),
        rrb.StateTimelineView(origin="/phase", name="phases"),
        rrb.Horizontal(*bottom),  # the summary and, in 3D scenes, the roll moments
        row_shares=[6.0, 1.0, 3.0])
    right = rrb.Vertical(*(rrb.Horizontal(*row) for row in rows),
                         row_shares=[1.0] * (len(rows) - 2) + [1.2, 1.0])
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[1.0, 1.5]),
        rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="hidden"),
        rrb.TimePanel(state="collapsed", timeline="time"),
        auto_layout=False, auto_views=False)
