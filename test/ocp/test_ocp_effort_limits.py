"""Effort limits (``effort_limits: {joint: N m}``, a URDF's <limit effort>) bound the
planned torques in N m: at the variables' bounds every node torque of the limited joint
(the mirror image nodes included) is exactly +-limit and the other joints are free; the
compass's hip, limited to half the peak torque of its plan without a limit, plans at that
limit (the bound once applied to the scaled torque variables, TORQUE_SCALE = 100 N m times
too loose: G1's ankle at 52 N m against 35, Talos's hip at 320 N m against 160)."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.ocp.transcription import Transcription


def test_node_torques_at_the_bounds_are_the_effort_limits():
    scene = load_scene("walker2d")
    settings = dataclasses.replace(settings_for(scene, intervals_per_phase=2),
                                   effort_limits=(("knee_r", 35.0),))
    tr = Transcription(DiscreteMechanics(Multibody(scene)), settings)
    lbx, ubx, _, _ = tr.bounds()
    torques = ca.Function("tau", [tr.x], [tr.TAU])
    knee = tr.mb.joint_slices["knee_r"].start
    for bound, sign in ((ubx, 1.0), (lbx, -1.0)):
        tau = np.array(torques(np.where(np.isfinite(bound), bound, 0.0)))
        assert np.allclose(tau[knee, :-2], sign * 35.0, rtol=1e-12)  # the planned nodes
        others = np.delete(tau[:, :-2], knee, axis=0)
        assert not others.any()  # free joints: unbounded, 0 where the test put them


def test_a_limit_below_the_free_peak_bounds_every_node_torque():
    scene = load_scene("compass")
    free = plan_once(Planner(), scene, settings_for(scene))
    assert free.success
    limit = 0.5 * float(np.abs(free.tau).max())
    bounded = plan_once(Planner(), scene, settings_for(scene, effort_limits={"hip": limit}))
    assert bounded.success, bounded.message
    peak = float(np.abs(bounded.tau).max())
    assert limit * (1 - 1e-6) <= peak <= limit * (1 + 1e-6)  # the bound is active
