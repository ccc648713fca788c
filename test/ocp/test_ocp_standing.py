"""The standing pose a start from standing begins at (`ocp.transition.standing_configuration`):
every contact point of the scene's first start phase on the level ground and, in 3D, every
foot with two of them flat (n . d2 = 0, the roll row the planner imposes on a full contact
and the verifier checks), found by moving the scene's initial_pose the least.

* the shipped walkers' poses already are: unchanged, bit for bit;
* a drafted robot's pose is its URDF's zero pose, whose feet need not be flat: Unitree G1's
  stand rolled by 1.55e-3, and its plan from standing failed the verifier for it
  (2026-12-07); its standing start is flat to round-off and passes `check_start`;
* property: walker3d's pose tilted, lifted and its ankles turned by up to 0.02 rad, 1 cm, is
  brought back onto the ground, flat, by a move of the same order.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.model.angles import configuration
from gait_planner.model.loader import load_scene, scene_from_text
from gait_planner.model.multibody import Multibody
from gait_planner.model.urdf_import import draft_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.transition import check_start, standing_configuration, standing_start

ROUND_OFF = 1e-12


def _held_and_rolls(scene, q):
    """(heights (m) of the first start phase's contact points, d2_z of its flat feet)."""
    mb = Multibody.of(scene)
    points = [scene.contact(n) for n in scene.gait.start[0].contacts]
    heights = np.array([(mb.point_matrix(c.body, c.point) @ q)[2] for c in points])
    feet = {c.body for c in points if sum(d.body == c.body for d in points) > 1}
    return heights, np.array([q[mb.block(b).start + 8] for b in sorted(feet)])


@pytest.mark.parametrize("name", ["walker3d", "walker2d"])
def test_the_shipped_walkers_stand_as_their_scene_says(name):
    scene = load_scene(name)
    assert np.array_equal(standing_configuration(scene), configuration(scene))


def test_g1s_standing_start_is_flat_on_the_ground(example_robots):
    path = example_robots / "g1_description/urdf/g1_29dof_rev_1_0.urdf"
    draft = draft_scene(path.read_text(), package_dirs=[str(example_robots.parents[1])])
    scene = scene_from_text(draft.yaml, "g1.yaml")
    heights, rolls = _held_and_rolls(scene, configuration(scene))
    assert np.abs(rolls).max() > 1e-3  # the URDF's zero pose: feet rolled 1.55e-3
    start = standing_start(scene)
    heights, rolls = _held_and_rolls(scene, start.q)
    assert np.abs(heights).max() < ROUND_OFF and np.abs(rolls).max() < ROUND_OFF
    assert np.abs(start.q - configuration(scene)).max() < 5e-3  # moved the least
    assert np.abs(np.asarray(Multibody.of(scene).constraints(start.q))).max() < ROUND_OFF
    check_start(scene, settings_for(scene, compiled=False), start)


@settings(max_examples=25, deadline=None)
@given(tilt=st.tuples(*[st.floats(-0.02, 0.02)] * 2), lift=st.floats(-0.01, 0.01),
       ankles=st.tuples(*[st.floats(-0.02, 0.02)] * 3))
def test_a_disturbed_stand_is_brought_back_flat_onto_the_ground(tilt, lift, ankles):
    scene = load_scene("walker3d")
    pose = scene.initial_pose
    x, y, z = pose.root_position
    disturbed = dataclasses.replace(scene, initial_pose=dataclasses.replace(
        pose, root_position=(x, y, z + lift), root_angles=(0.0, *tilt),
        joint_angles={"ankle_r": ankles, "ankle_l": ankles[::-1]}))
    q = standing_configuration(disturbed)
    heights, rolls = _held_and_rolls(disturbed, q)
    assert np.abs(heights).max() < ROUND_OFF and np.abs(rolls).max() < ROUND_OFF
    assert np.abs(np.asarray(Multibody.of(disturbed).constraints(q))).max() < ROUND_OFF
    size = max(abs(lift), *map(abs, tilt), *map(abs, ankles))
    assert np.abs(q - configuration(disturbed)).max() <= 5 * size + ROUND_OFF
