"""Posture: joint-range rows (`gait_planner.ocp.posture`) against the angles of
`gait_planner.model.angles` (for random poses and random ranges, every row lies in
[0, JOINT_RANGE_ROW_UPPER] exactly when the numpy angle lies in its range, and the row is
the distance from the lower bound in half widths, of the sines for a roll; near the branch
cut of atan2 both sides are outside); the posture options' checks
(`gait_planner.model.posture`), torso_lean_max in degrees; walker2d's plan upright."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.angles import configuration, joint_angles
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.model.posture import PostureError, check_joint_limits
from gait_planner.model.scene import InitialPose, JointType
from gait_planner.ocp.posture import (JOINT_RANGE_ROW_UPPER, joint_limit_constants,
                                      joint_limit_margins, joint_limit_rows,
                                      joint_margin_constants)
from gait_planner.ocp.settings import SettingsError, settings_for
from gait_planner.ocp.transcription import Transcription

_SCENE = load_scene("walker3d")
_MB = Multibody(_SCENE)
_NAMES = [n for j in _SCENE.joints for n in j.angle_names]


def _rows(limits, q):
    """The rows (n,) of `limits` ((angle, lo, hi) in rad) at configuration q."""
    names = tuple(name for name, _, _ in limits)
    return np.array(joint_limit_rows(_MB, names)(q, joint_limit_constants(_MB, limits))).ravel()


def _inside(row):
    return 0.0 <= row <= JOINT_RANGE_ROW_UPPER


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
def test_rows_are_the_distance_from_the_lower_bound_in_half_widths(values, ranges):
    limits = {name: (lo, min(lo + width, 90.0 if _is_roll(name) else lo + width))
              for name, (lo, width) in zip(_NAMES, ranges)}
    limits = {k: v for k, v in limits.items() if v[1] > v[0]}
    checked = check_joint_limits(_SCENE, limits)
    q = configuration(_SCENE, _pose(values))
    theta = dict(zip(_NAMES, joint_angles(_SCENE, q)))
    rows = _rows(checked, q)
    for row, (name, lo, hi) in zip(rows, checked):
        t = theta[name]
        if _is_roll(name):
            expected = 2 * (math.sin(t) - math.sin(lo)) / (math.sin(hi) - math.sin(lo))
        else:  # the angle about the range's middle, in (-180, 180] deg
            middle = 0.5 * (lo + hi)
            expected = 1 + math.remainder(t - middle, 2 * math.pi) / (0.5 * (hi - lo))
        assert row == pytest.approx(expected, abs=1e-9)
        inside = lo <= t <= hi
        assert _inside(row) == inside or min(abs(t - lo), abs(t - hi)) < 1e-9


@settings(max_examples=40, deadline=None)
@given(values=ANGLES, ranges=RANGES)
def test_the_baselines_margins_have_the_sign_and_size_of_the_distance_to_the_bounds(
        values, ranges):
    """`joint_limit_margins` (the collocation baseline's two rows per angle): each >= 0
    exactly when the angle lies in its range, the sine of the distance to the bound times
    cos roll for pitch and yaw, the difference of the sines for a roll."""
    limits = {name: (lo, min(lo + width, 90.0 if _is_roll(name) else lo + width))
              for name, (lo, width) in zip(_NAMES, ranges)}
    checked = check_joint_limits(_SCENE, {k: v for k, v in limits.items() if v[1] > v[0]})
    q = configuration(_SCENE, _pose(values))
    theta = dict(zip(_NAMES, joint_angles(_SCENE, q)))
    names = tuple(name for name, _, _ in checked)
    margins = np.array(joint_limit_margins(_MB, names)(
        q, joint_margin_constants(_MB, checked))).ravel()
    for i, (name, lo, hi) in enumerate(checked):
        t = theta[name]
        if _is_roll(name):
            expected = (math.sin(t) - math.sin(lo), math.sin(hi) - math.sin(t))
        else:
            k = math.cos(theta[name.rsplit("_", 1)[0] + "_roll"]) \
                if name.endswith(("_pitch", "_yaw")) else 1.0
            expected = (k * math.sin(t - lo), k * math.sin(hi - t))
        np.testing.assert_allclose(margins[2 * i : 2 * i + 2], expected, atol=1e-12)
        inside = lo <= t <= hi
        assert (min(margins[2 * i : 2 * i + 2]) >= -1e-12) == inside or \
            min(abs(t - lo), abs(t - hi)) < 1e-9


@settings(max_examples=40, deadline=None)
@given(offset=st.floats(1e-3, 3.0), width=st.floats(1, 179))
def test_the_branch_cut_is_outside_the_range_on_both_sides(offset, width):
    """A knee turned half a revolution from its range's middle, just before and after the
    cut of atan2: its row is below 0 on one side and above the upper bound on the other."""
    knee = next(j for j in _SCENE.joints if j.type is JointType.REVOLUTE).angle_names[0]
    lo, hi = -width / 2, width / 2
    limits = check_joint_limits(_SCENE, {knee: (lo, hi)})
    for side in (-1.0, 1.0):
        angle = math.pi + side * math.radians(offset)
        values = [0.0] * 3 + [angle] + [0.0] * 10
        row = _rows(limits, configuration(_SCENE, _pose(values)))[0]
        assert not _inside(row)


def test_upright_pose_is_inside_symmetric_ranges_and_outside_shifted_ones():
    q = configuration(_SCENE)
    inside = check_joint_limits(_SCENE, {n: (-10, 10) for n in _NAMES})
    outside = check_joint_limits(_SCENE, {n: (5, 10) for n in _NAMES})
    assert np.allclose(_rows(inside, q), 1.0)  # every angle 0, the ranges' middle
    assert np.all(_rows(outside, q) < -1.5)  # 5 deg below a range 5 deg wide


def test_a_row_above_its_range_counts_as_violated():
    """`ocp.solution.violations` judges a joint-range row against both of its bounds."""
    from gait_planner.ocp.solution import violations

    tr = Transcription(DiscreteMechanics(_MB), settings_for(_SCENE))
    names = [name for name, size, _ in tr.constraint_groups() for _ in range(size)]
    rows = np.flatnonzero(np.array(names) == "joint_limits")
    g = np.zeros(len(names))
    g[rows] = 1.0  # every angle at its range's middle
    assert violations(tr, g)["joint_limits"] == 0.0
    g[rows[3]], g[rows[5]] = JOINT_RANGE_ROW_UPPER + 0.25, -0.125
    assert violations(tr, g)["joint_limits"] == 0.25


def test_revolute_axis_of_any_direction():
    knee = next(j for j in _SCENE.joints if j.type is JointType.REVOLUTE)
    q = configuration(_SCENE, _pose([0.0] * 3 + [0.7] + [0.0] * 10))
    assert joint_angles(_SCENE, q)[3] == pytest.approx(0.7)
    limits = check_joint_limits(_SCENE, {knee.angle_names[0]: (0, 40)})
    assert _rows(limits, q)[0] == pytest.approx(0.7 / math.radians(20))


@pytest.mark.parametrize("limits, words", [
    ({"elbow": (0, 10)}, "'elbow' is not a joint angle"),
    ({"knee_r": (10, 0)}, "lower < upper"),
    ({"knee_r": (0, 200)}, "within 180 deg"),
    ({"knee_r": (0, float("nan"))}, "finite"),
    ({"knee_r": "straight"}, "need [lower, upper]"),
    ({"hip_r_roll": (-95, 10)}, "[-90, 90]"),
    ({"knee_r": (170, 200)}, "bounds must lie in [-180, 180] deg"),
    ({"knee_r": (0, True)}, "need [lower, upper]"),
    ({"knee_r": ("0", "10")}, "need [lower, upper]"),
    ((("knee_r", 0.0, 1.0),), "need a mapping"),
])
def test_bad_ranges_name_what_is_wrong(limits, words):
    with pytest.raises(PostureError) as err:
        check_joint_limits(_SCENE, limits)
    assert words in str(err.value)
    with pytest.raises(SettingsError) as err:
        settings_for(_SCENE, joint_limits=limits)
    assert words in str(err.value)


def test_settings_carry_the_ranges_in_radians():
    s = settings_for(_SCENE, joint_limits={"knee_r": (0, 70)})
    assert s.joint_limits == (("knee_r", 0.0, pytest.approx(math.radians(70))),)


def test_a_twist_weight_per_cost_is_chosen_by_the_cost():
    walker3d = load_scene("walker3d")
    assert settings_for(walker3d).twist_regularisation == 1.0
    assert settings_for(walker3d, cost="torque_squared").twist_regularisation == 50.0
    assert settings_for(walker3d, twist_regularisation={"torque_squared": 3.0}
                        ).twist_regularisation == 0.0
    with pytest.raises(SettingsError, match=r"twist_regularisation: unknown cost\(s\) \['effort'\]"):
        settings_for(walker3d, twist_regularisation={"effort": 1.0})


@pytest.mark.parametrize("value, words", [
    (90, "torso_lean_max: must be in [0, 90) degrees, got 90.0"),
    (-1, "torso_lean_max: must be in [0, 90) degrees, got -1.0"),
    ("5", "torso_lean_max: must be a number of degrees, got '5'"),
    (True, "torso_lean_max: must be a number of degrees, got True"),
])
def test_torso_lean_max_is_degrees_below_90(value, words):
    with pytest.raises(SettingsError) as err:
        settings_for(_SCENE, torso_lean_max=value)
    assert words in str(err.value)


def test_torso_lean_max_in_degrees_bounds_the_root_d3_at_its_cosine():
    """5 (degrees) from the option becomes d3_z - cos(5 deg) >= 0 at nodes 1..N-1 of the
    root body: the rows minus the root's d3_z are the constant -cos(5 deg) at any x, p."""
    scene = load_scene("compass")
    s = settings_for(scene, torso_lean_max=5)
    assert s.torso_lean_max == 5.0
    tr = Transcription(DiscreteMechanics(Multibody(scene)), s)
    offset = 0
    for name, size, _ in tr.constraint_groups():
        if name == "torso_lean":
            break
        offset += size
    assert size == tr.N - 1
    root = tr.mb.block(scene.root.body).start
    rows = tr.g[offset : offset + size] - ca.vec(tr.Q[root + 11, 1 : tr.N])
    f = ca.Function("f", [tr.x, tr.p], [rows])
    rng = np.random.default_rng(0)
    x, p = rng.normal(size=tr.x.shape[0]) * 0.1, rng.normal(size=tr.p.shape[0])
    np.testing.assert_allclose(np.array(f(x, p)).ravel(), -math.cos(math.radians(5)),
                               rtol=0, atol=1e-14)


def test_walker2d_plan_is_upright(solved):
    """walker2d's default plan (cold, from the kinematic guess) keeps its declared posture:
    the torso's d3 within 5 deg of vertical and every knee bent or straight (>= 0) at every
    node, every joint angle within its range; minimal kinetic energy leans it on the bound.
    Without the posture the torso hung head-down between the hips (d3_z -0.98)."""
    s = solved("walker2d")
    r, scene = s.result, s.scene
    assert r.success, r.message
    assert s.settings.torso_lean_max == 5.0
    root = [b.name for b in scene.bodies].index(scene.root.body) * 12
    d3z = r.q[:, root + 11]
    assert d3z.min() >= math.cos(math.radians(5)) - 1e-8
    assert d3z.min() == pytest.approx(math.cos(math.radians(5)), abs=1e-6)  # active
    angles = dict(zip(r.joint_angle_names, r.joint_angles.T))
    for knee in ("knee_r", "knee_l"):
        assert angles[knee].min() >= -1e-6
    for name, lo, hi in s.settings.joint_limits:
        assert lo - 1e-6 <= angles[name].min() and angles[name].max() <= hi + 1e-6, name


@pytest.mark.slow
@pytest.mark.parametrize("name", ["walker2d", "walker3d"])
def test_human_posture_straightens_the_stance_knee(name):
    """posture: human bounds the stance knee to 0..20 deg in single support; the paper's
    problem (the default) bends it to 30 deg and more."""
    from gait_planner.model.loader import load_scene
    from gait_planner.ocp.settings import settings_for
    from gait_planner.ocp.solve import Planner
    from gait_planner.strategies import plan_once

    scene = load_scene(name)
    result = plan_once(Planner(), scene, settings_for(scene, posture="human", compiled=True))
    assert result.success, result.message
    knee = np.degrees(result.joint_angles[:, list(result.joint_angle_names).index("knee_r")])
    single = [n for n in range(1, result.n_nodes - 1)
              if result.phases[n] in ("right_full", "right_forefoot")]
    assert knee[single].max() <= 20.0 + 1e-6
    assert knee[single].min() >= -1e-6


def test_unknown_posture_is_refused_with_its_name():
    from gait_planner.model.loader import load_scene
    from gait_planner.ocp.settings import SettingsError, settings_for

    with pytest.raises(SettingsError, match="posture.*'robot'.*paper, human"):
        settings_for(load_scene("walker3d"), posture="robot")
