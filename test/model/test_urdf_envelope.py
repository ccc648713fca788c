"""The walking envelope a draft writes (`gait_planner.model.urdf_envelope`, issue #61):
the knees and hip yaws found by their axes in the world at the zero pose, not by name,
and the options that keep a drafted robot upright."""

from __future__ import annotations

import pytest
import yaml

from gait_planner.model.urdf_envelope import HIP_YAW_DEG, STANCE_KNEE_DEG, UPRIGHT_DEG
from gait_planner.model.urdf_import import draft_scene
from urdf_bipeds import biped

ROBOTS = {"g1": ("g1_description/urdf/g1_29dof_rev_1_0.urdf", {},
                 ("left_hip_yaw_joint", "right_hip_yaw_joint"),
                 ("left_knee_joint", "right_knee_joint")),
          "talos": ("talos_data/robots/talos_reduced.urdf", {"mirror_tolerance": 0.06},
                    ("leg_left_1_joint", "leg_right_1_joint"),
                    ("leg_left_4_joint", "leg_right_4_joint"))}


def _options(text: str) -> dict:
    return yaml.safe_load(text)["gait"]["options"]


@pytest.mark.parametrize("knee_axis", ["y", "-y"])
def test_the_stance_knee_is_bounded_in_single_support(knee_axis):
    options = _options(draft_scene(biped(knee_axis=knee_axis)).yaml)
    assert options["torso_lean_max"] == UPRIGHT_DEG
    phases = options["phase_joint_limits"]
    assert set(phases) == {"right_full", "right_forefoot", "left_full"}  # single support
    assert list(phases["left_full"]) == ["left_knee_joint"]
    assert list(phases["right_full"]) == list(phases["right_forefoot"]) == ["right_knee_joint"]
    lo, hi = options["joint_limits"]["left_knee_joint"]  # the URDF's range
    assert phases["left_full"]["left_knee_joint"] == [max(lo, -STANCE_KNEE_DEG),
                                                       min(hi, STANCE_KNEE_DEG)]


def test_a_knee_about_roll_is_no_knee():
    """The biped's knee turned about x: one pitch joint per leg (hip), so no knee row."""
    assert "phase_joint_limits" not in _options(draft_scene(biped(knee_axis="x")).yaml)


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_robots_hips_and_knees_are_found_by_their_axes(name, example_robots):
    relative, importer, hips, knees = ROBOTS[name]
    draft = draft_scene((example_robots / relative).read_text(),
                        package_dirs=[str(example_robots.parents[1])], **importer)
    options = _options(draft.yaml)
    for hip in hips:
        lo, hi = options["joint_limits"][hip]
        assert -HIP_YAW_DEG <= lo < 0 < hi <= HIP_YAW_DEG
    phases = options["phase_joint_limits"]
    assert set(phases["left_full"]) == {knees[0]} and set(phases["right_full"]) == {knees[1]}
