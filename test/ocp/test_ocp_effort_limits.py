"""Effort limits (`effort_limits: {joint: N m}`) bound the torques the plan publishes:
at the variables' bounds, every node torque of the limited joint (the mirror image nodes
included) is exactly +-limit, and the other joints are free."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.settings import settings_for
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
