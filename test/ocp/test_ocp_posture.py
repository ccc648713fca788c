"""Joint-range margins (`gait_planner.ocp.posture`) against the angles of
`gait_planner.model.angles`: for random poses and random ranges, every margin is >= 0
exactly when the numpy angle lies in its range, and the margin's size is the sine of the
distance to the bound (times cos roll for pitch and yaw)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.model.angles import configuration, joint_angles
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import InitialPose, JointType
from gait_planner.ocp.posture import JointLimitError, check_joint_limits, joint_limit_margins
from gait_planner.ocp.settings import SettingsError, settings_for

_SCENE = load_scene("walker3d")
_MB = Multibody(_SCENE)
_NAMES = [n for j in _SCENE.joints for n in j.angle_names]


def _pose(values):
    angles, i = {}, 0
    for j in _SCENE.joints:
        angles[j.name] = tuple(values[i : i + j.dof])
        i += j.dof
    return InitialPose(root_position=(0.1, -0.2, 1.0), root_angles=(0.3, -0.2, 0.1),
                       joint_angles=angles)


def _is_roll(name):
    return name.endswith("_roll")


ANGLES = st.lists(st.floats(-1.4, 1.4), min_size=len(_NAMES), max_size=len(_NAMES))
RANGES = st.lists(st.tuples(st.floats(-80, 80), st.floats(1, 90)),
                  min_size=len(_NAMES), max_size=len(_NAMES))


@settings(max_examples=60, deadline=None)
@given(values=ANGLES, ranges=RANGES)
def test_margins_have_the_sign_and_size_of_the_distance_to_the_bounds(values, ranges):
    limits = {name: (lo, min(lo + width, 90.0 if _is_roll(name) else lo + width))
              for name, (lo, width) in zip(_NAMES, ranges)}
    limits = {k: v for k, v in limits.items() if v[1] > v[0]}
    checked = check_joint_limits(_SCENE, limits)
    q = configuration(_SCENE, _pose(values))
    theta = dict(zip(_NAMES, joint_angles(_SCENE, q)))
    margins = np.array(joint_limit_margins(_MB, checked)(q)).ravel()
    for i, (name, lo, hi) in enumerate(checked):
        t = theta[name]
        if _is_roll(name):
            expected = (math.sin(t) - math.sin(lo), math.sin(hi) - math.sin(t))
        else:
            k = 1.0
            if name.endswith(("_pitch", "_yaw")):
                k = math.cos(theta[name.rsplit("_", 1)[0] + "_roll"])
            expected = (k * math.sin(t - lo), k * math.sin(hi - t))
        np.testing.assert_allclose(margins[2 * i : 2 * i + 2], expected, atol=1e-12)
        inside = lo <= t <= hi
        assert (margins[2 * i] >= -1e-12 and margins[2 * i + 1] >= -1e-12) == inside or \
            min(abs(t - lo), abs(t - hi)) < 1e-9


def test_upright_pose_is_inside_symmetric_ranges_and_outside_shifted_ones():
    q = configuration(_SCENE)
    inside = check_joint_limits(_SCENE, {n: (-10, 10) for n in _NAMES})
    outside = check_joint_limits(_SCENE, {n: (5, 10) for n in _NAMES})
    assert np.all(np.array(joint_limit_margins(_MB, inside)(q)) > 0.1)
    low = np.array(joint_limit_margins(_MB, outside)(q)).ravel()[0::2]
    assert np.all(low < -0.08)


def test_revolute_axis_of_any_direction():
    knee = next(j for j in _SCENE.joints if j.type is JointType.REVOLUTE)
    q = configuration(_SCENE, _pose([0.0] * 3 + [0.7] + [0.0] * 10))
    assert joint_angles(_SCENE, q)[3] == pytest.approx(0.7)
    limits = check_joint_limits(_SCENE, {knee.angle_names[0]: (0, 40)})
    below, above = np.array(joint_limit_margins(_MB, limits)(q)).ravel()
    assert below == pytest.approx(math.sin(0.7)) and above == pytest.approx(
        math.sin(math.radians(40) - 0.7))


@pytest.mark.parametrize("limits, words", [
    ({"elbow": (0, 10)}, "'elbow' is not a joint angle"),
    ({"knee_r": (10, 0)}, "lower < upper"),
    ({"knee_r": (0, 200)}, "within 180 deg"),
    ({"knee_r": (0, float("nan"))}, "finite"),
    ({"knee_r": "straight"}, "need [lower, upper]"),
    ({"hip_r_roll": (-95, 10)}, "[-90, 90]"),
    ((("knee_r", 0.0, 1.0),), "need a mapping"),
])
def test_bad_ranges_name_what_is_wrong(limits, words):
    with pytest.raises(JointLimitError, match=None) as err:
        check_joint_limits(_SCENE, limits)
    assert words in str(err.value)
    with pytest.raises(SettingsError) as err:
        settings_for(_SCENE, joint_limits=limits)
    assert words in str(err.value)


def test_settings_carry_the_ranges_in_radians():
    s = settings_for(_SCENE, joint_limits={"knee_r": (0, 70)})
    assert s.joint_limits == (("knee_r", 0.0, pytest.approx(math.radians(70))),)
