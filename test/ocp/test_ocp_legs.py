"""The leg clearance rows (`gait_planner.ocp.legs`) on walker3d's spheres:

* the legs are the root's subtrees with spheres (walker3d: calf and foot; walker2d, planar,
  and the compass: none);
* the row is a smooth minimum of the saturated pair margins, never above the smallest and
  at most eps log(pairs) below it, and its sign is the sign of the smallest sphere
  distance minus the clearance (up to that amount), at random configurations of the legs;
* a negative leg_clearance, a legs_apart that is not a boolean are refused by name;
* with legs_apart (walker3d's paper problem has it off) the transcription holds one
  leg_clearance row per node 1..N-1, declared as node elements (their sum with the rest
  of g: test_ocp_derivatives.test_elements_and_rest_sum_to_g_and_cost).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.angles import configuration
from gait_planner.model.scene import InitialPose
from gait_planner.ocp.legs import (SATURATION, SMOOTHING, leg_bodies, leg_clearance_rows,
                                   leg_sphere_distances)
from gait_planner.ocp.settings import SettingsError, settings_for
from gait_planner.ocp.transcription import Transcription


def test_legs_are_the_subtrees_with_spheres(model):
    assert leg_bodies(model("walker3d").scene) == [("calf_r", "foot_r"), ("calf_l", "foot_l")]
    for name in ("walker2d", "compass"):
        assert leg_bodies(model(name).scene) == []
        assert leg_clearance_rows(model(name).mb) is None


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 0.05))
def test_row_is_a_smooth_minimum_of_the_sphere_distances(model, seed, clearance):
    scene, mb = model("walker3d").scene, model("walker3d").mb
    rng = np.random.default_rng(seed)
    angles = {j.name: tuple(rng.uniform(-0.6, 0.6, j.dof)) for j in scene.joints}
    q = configuration(scene, InitialPose((0.0, 0.0, 1.1), (0.0, 0.0, 0.0), angles))
    distance = leg_sphere_distances(mb)(q).full().ravel()
    radii = [s[3] for leg in leg_bodies(scene) for b in leg for s in scene.body(b).collision]
    left = np.array(radii[: len(radii) // 2])
    right = np.array(radii[len(radii) // 2:])
    r = (left[:, None] + right[None]).ravel()  # the rows' pairs: left against right
    R = r + clearance
    margins = SATURATION * np.tanh(((distance + r) ** 2 - R ** 2) / (2 * R * SATURATION))
    row = leg_clearance_rows(mb)(q, [clearance, SMOOTHING]).full().item()
    slack = SMOOTHING * math.log(distance.size)
    assert margins.min() - slack - 1e-12 <= row <= margins.min() + 1e-12
    if row >= 0:
        assert distance.min() >= clearance - 1e-12
    if distance.min() >= clearance + 1.01 * slack:  # margins near 0 are the distances
        assert row >= 0


def test_a_negative_clearance_and_a_legs_apart_not_boolean_are_refused_by_name(model):
    with pytest.raises(SettingsError, match="leg_clearance: must be >= 0, got -0.01"):
        settings_for(model("walker3d").scene, leg_clearance=-0.01)
    with pytest.raises(SettingsError, match="legs_apart: must be true or false, got 'yes'"):
        settings_for(model("walker3d").scene, legs_apart="yes")


def test_one_row_per_node_as_node_elements(model):
    m = model("walker3d")
    assert not settings_for(m.scene).legs_apart  # the paper's problem (walker3d.yaml)
    off = Transcription(DiscreteMechanics(m.mb), settings_for(m.scene))
    assert "leg_clearance" not in {name for name, _, _ in off.constraint_groups()}
    s = settings_for(m.scene, legs_apart=True)
    tr = Transcription(DiscreteMechanics(m.mb), s)
    sizes = {name: size for name, size, _ in tr.constraint_groups()}
    assert sizes["leg_clearance"] == tr.N - 1
    groups = [g for g in tr.elements if g.function.name() == "leg_clearance_element"]
    assert sum(g.rows.shape[1] for g in groups) == tr.N - 1
    np.testing.assert_array_equal(groups[0].constants, [s.leg_clearance, SMOOTHING])
    assert s.leg_clearance == 0.01
