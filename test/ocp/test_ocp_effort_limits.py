"""Effort limits (``effort_limits: {joint: N m}``, a URDF's <limit effort>) bound the
planned torques in N m: the compass's hip, limited to half the peak torque of its plan
without a limit, plans within that limit (the bound once applied to the scaled torque
variables, TORQUE_SCALE = 100 N m times too loose, left Talos's hip at 320 N m against its
160 N m)."""

from __future__ import annotations

import numpy as np

from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner


def test_a_limit_below_the_free_peak_bounds_every_node_torque():
    scene = load_scene("compass")
    free = Planner().plan(scene, settings_for(scene))
    assert free.success
    limit = 0.5 * float(np.abs(free.tau).max())
    bounded = Planner().plan(scene, settings_for(scene, effort_limits={"hip": limit}))
    assert bounded.success, bounded.message
    peak = float(np.abs(bounded.tau).max())
    assert limit * (1 - 1e-6) <= peak <= limit * (1 + 1e-6)  # the bound is active
