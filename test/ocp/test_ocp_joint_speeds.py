"""A joint's own speed limit (issue #61: Romeo's hip yaw at 18 deg/s was the one bound of
every joint): the draft writes each joint's URDF velocity limit (a left-right pair's the
smaller), the transcription bounds each joint by its own, and the verifier judges each
published joint against its own where it is higher than the general one."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from gait_planner.model.angles import configuration
from gait_planner.model.loader import scene_from_text
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import InitialPose
from gait_planner.model.urdf_import import draft_scene
from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.ocp.posture import joint_speeds_margins
from gait_planner.ocp.settings import SettingsError, joint_speed_bounds, settings_for
from gait_planner.ocp.transcription import Transcription
from gait_planner.verify.mechanics import parse_scene
from gait_planner.verify.physical import JOINT_SPEED_MAX, joint_speed_limits
from urdf_bipeds import biped

SLOW, FAST = 2.0, 20.0  # rad/s: the left knee's limit (the right's 4), every other joint's


@pytest.fixture(scope="module")
def slow_knee():
    urdf = biped(velocities={"left_knee_joint": SLOW, "right_knee_joint": 4.0})
    draft = draft_scene(urdf)
    return draft, scene_from_text(draft.yaml, "biped.yaml")


def test_the_draft_writes_each_joints_own_limit_a_pairs_the_smaller(slow_knee):
    draft, scene = slow_knee
    options = scene.gait.options
    assert "joint_speed_max" not in options
    limits = options["joint_speed_limits"]
    assert set(limits) == set(draft.joints)  # the locked waist (5 rad/s) is not planned
    for name, value in limits.items():
        expected = SLOW if "knee" in name else FAST
        assert value == pytest.approx(math.degrees(expected), abs=1e-5), name
    assert "joint_speed_max, the slowest, where none is under 600 deg/s" in draft.yaml
    uniform = scene_from_text(draft_scene(biped()).yaml, "biped.yaml")
    assert uniform.gait.options["joint_speed_max"] == pytest.approx(math.degrees(FAST), abs=1e-5)
    assert "joint_speed_limits" not in uniform.gait.options


def test_the_slow_joints_bound_applies_to_that_joint_only(slow_knee):
    _, scene = slow_knee
    s = settings_for(scene)
    bounds = dict(zip((j.name for j in scene.joints), joint_speed_bounds(scene, s)))
    assert bounds["left_knee_joint"] == pytest.approx(math.degrees(SLOW), abs=1e-5)
    assert bounds["left_hip_pitch_joint"] == pytest.approx(math.degrees(FAST), abs=1e-5)
    mb = Multibody(scene)
    tr = Transcription(DiscreteMechanics(mb), s)
    groups = [g for g in tr.elements if g.function.name().startswith("joint_speeds_element")]
    assert groups and not [g for g in tr.elements
                           if g.function.name().startswith("joint_speed_element")]
    np.testing.assert_allclose(groups[0].constants[1:],
                               np.radians([bounds[j.name] for j in scene.joints]))
    sizes = {name: size for name, size, _ in tr.constraint_groups()}
    assert sizes["joint_speed"] == len(scene.joints) * (tr.N - 1)

    names = tuple(j.name for j in scene.joints)
    margins = joint_speeds_margins(mb, names)
    c = np.r_[s.base_time_step, np.radians([bounds[n] for n in names])]
    h, pose = 0.01, scene.initial_pose
    q0 = configuration(scene)
    for joint in ("left_knee_joint", "left_hip_pitch_joint"):
        # turned at 5 rad/s over h: past the knee's 2 rad/s, within the others' 20
        turned = InitialPose(pose.root_position, pose.root_angles, {joint: (5.0 * h,)})
        row = np.asarray(margins(q0, configuration(scene, turned), h, c)).ravel()
        over = {n for n, r in zip(names, row) if r < 0}
        assert over == ({joint} if joint == "left_knee_joint" else set()), (joint, row)


def test_a_speed_limit_naming_no_joint_or_not_positive_is_refused(slow_knee):
    _, scene = slow_knee
    with pytest.raises(SettingsError, match="joint_speed_limits.elbow: not a joint"):
        settings_for(scene, joint_speed_limits={"elbow": 10.0})
    with pytest.raises(SettingsError, match="joint_speed_limits.left_knee_joint: need a "
                                            "positive speed"):
        settings_for(scene, joint_speed_limits={"left_knee_joint": 0})


def test_the_verifier_judges_each_joint_against_its_own_higher_limit(slow_knee):
    draft, _ = slow_knee
    data = parse_scene(draft.yaml)
    names = ("left_knee_joint", "left_hip_pitch_joint", "waist_joint")
    # the knee's 114.6 deg/s is below the general 600: the verifier keeps 600 for it; the
    # hip's 1145.9 is above it; the locked waist has none in the scene
    np.testing.assert_allclose(joint_speed_limits(data, names),
                               [JOINT_SPEED_MAX, math.degrees(FAST), JOINT_SPEED_MAX])
    data = SimpleNamespace(options={"joint_speed_max": 700.0,
                                    "joint_speed_limits": {"left_hip_pitch_joint": 900.0}})
    np.testing.assert_allclose(joint_speed_limits(data, names), [700.0, 900.0, 700.0])
