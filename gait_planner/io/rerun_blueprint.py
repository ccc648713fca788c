"""The layout of a plan's rerun view (rerun-sdk 0.41): `blueprint`.

A large 3D view beside the plots of `gait_planner.io.rerun_series.plot_groups`::

    +-------------------------------+----------------------+----------------------+
    |                               | joint angles, right  | joint angles, left   |
    | walker (3D): bodies, skeleton,+----------------------+----------------------+
    | foot and centre-of-mass       | joint torques, right | joint torques, left  |
    | trails, point forces, foot    +----------------------+----------------------+
    | wrenches at the centres of    | ground force, foot_r | ground force, foot_l |
    | pressure                      +----------------------+----------------------+
    +-------------------------------+ energy               | angular momentum     |
    | phases (state timeline)       |                      |                      |
    +---------------+---------------+                      |                      |
    | solve summary | roll moments  |                      |                      |
    +---------------+---------------+----------------------+----------------------+

(compass: one joint-angle and one torque plot; planar scenes: no roll moments). The time
axes of all plots are linked (zooming one zooms all), and every plot marks the phase
boundaries. The torque plots have no legend: their colours are those of the angle plot
above. The blueprint and time panels start collapsed, the selection panel hidden, the time
panel on the ``time`` timeline.
"""

from __future__ import annotations

import numpy as np
import rerun.blueprint as rrb

from gait_planner.io.rerun_series import PlotGroup, plot_groups, poses, whole_body_com
from gait_planner.result import PlanResult

__all__ = ["blueprint"]


def _plot(group: PlotGroup) -> rrb.TimeSeriesView:
    # a torque plot has the colours of the angle plot above it: no legend of its own
    legend = rrb.PlotLegend(corner="LeftTop", visible=not group.key.startswith("joint_torque"))
    return rrb.TimeSeriesView(
        origin="/plots", name=group.title,
        contents=[f"+ /{p}" for p in (*group.paths, group.boundary_path)],
        axis_x=rrb.TimeAxis(link="LinkToGlobal"), plot_legend=legend)


def _eye(result: PlanResult) -> rrb.EyeControls3D:
    """A camera in front of the walker and to its right, looking at the middle of its path
    (distances scaled by the mean height h of the centre of mass; walker3d: h = 1.0 m)."""
    com = whole_body_com(result, poses(result)[0])
    h = float(com[:, 2].mean())
    target = np.array([0.5 * (com[0, 0] + com[-1, 0]), float(com[:, 1].mean()), 0.6 * h])
    return rrb.EyeControls3D(kind="Orbital", position=target + h * np.array([1.5, -2.1, 0.8]),
                             look_target=target, eye_up=(0.0, 0.0, 1.0))


def blueprint(result: PlanResult) -> rrb.Blueprint:
    """The layout of the module docstring for `result`'s recording."""
    plots = {g.key: _plot(g) for g in plot_groups(result)}
    rows = [[plots.pop(f"{kind}_{s}") for s in ("right", "left", "joints")
             if f"{kind}_{s}" in plots] for kind in ("joint_angle", "joint_torque")]
    rows.append([plots.pop(k) for k in list(plots) if k.startswith("contact_force_")])
    rows.append([plots.pop("energy"), plots.pop("angular_momentum")])
    bottom = [rrb.TextDocumentView(origin="/plan", name="solve summary"), *plots.values()]
    left = rrb.Vertical(
        rrb.Spatial3DView(origin="/world", name="walker", eye_controls=_eye(result),
                          line_grid=rrb.LineGrid3D(visible=False)),
        rrb.StateTimelineView(origin="/phase", name="phases"),
        rrb.Horizontal(*bottom),  # the summary and, in 3D scenes, the roll moments
        row_shares=[6.0, 1.0, 3.0])
    # the legends of the joint angles (7 lines per leg in 3D) and forces need the height
    shares = {0: 1.3, 1: 1.0, 2: 1.2, 3: 1.0}
    right = rrb.Vertical(*(rrb.Horizontal(*row) for row in rows if row),
                         row_shares=[shares[k] for k, row in enumerate(rows) if row])
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[1.0, 1.25]),
        rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="hidden"),
        rrb.TimePanel(state="collapsed", timeline="time"),
        auto_layout=False, auto_views=False)
