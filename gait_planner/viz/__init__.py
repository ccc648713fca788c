"""Pictures of a plan, for people: rerun recordings and their layout, matplotlib figures,
screenshots, the walk's view. They read a `PlanResult` or a recording and never feed the
planner; `gait_planner.io` (the formats) sits below them.

* `gait_planner.viz.rerun_view`: `log_plan`, `save_rrd`, `show` (with `rerun_blueprint`,
  `rerun_draw`, `rerun_robot`, `rerun_series`: the layout, the bodies, the URDF's meshes,
  the plotted series);
* `gait_planner.viz.rrd_recorder`: `RrdRecorder`, `save_rrd` in a helper process (the node);
* `gait_planner.viz.rerun_screenshot`: a recording's picture through the rerun web viewer;
* `gait_planner.viz.rerun_walk`: a MuJoCo walk beside its plan;
* `gait_planner.viz.figures`: `plot_recording`, the summary figures of a recording.

The names below are imported lazily: importing the package loads neither rerun nor
matplotlib.
"""

from __future__ import annotations

from gait_planner.lazy import lazy_exports

_EXPORTS = {
    "log_plan": "rerun_view",
    "save_rrd": "rerun_view",
    "show": "rerun_view",
    "RrdRecorder": "rrd_recorder",
    "plot_recording": "figures",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
