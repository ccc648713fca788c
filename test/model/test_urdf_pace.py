"""sigma's drafted upper bound from the robot's own slow joints
(`gait_planner.model.urdf_pace`, issue #61): the half cycle long enough for the slowest hip
or ankle pitch joint to sweep the stride angle in the swing; walker3d's 1.5 where the
joints are fast enough."""

from __future__ import annotations

import math
import re

import pytest
import yaml

from gait_planner.model.urdf_import import draft_scene
from gait_planner.model.urdf_pace import (SIGMA_UPPER, SPEED_MARGIN, scaling_upper,
                                          stride_angle, swing_share)
from urdf_bipeds import biped

FIVE = [{"contacts": ["rh", "rf"], "intervals": 8}, {"contacts": ["rf"], "intervals": 8},
        {"contacts": ["rf", "lh"], "intervals": 8}, {"contacts": ["rf", "lh", "lf"],
                                                      "intervals": 8},
        {"contacts": ["lh", "lf"], "intervals": 8}]
SIDES = {"rh": "r", "rf": "r", "lh": "l", "lf": "l", "r": "r", "l": "l"}
POINT = [{"contacts": ["r"], "intervals": 20}, {"contacts": ["l"], "intervals": 1}]


def test_the_stride_angle_and_the_swing_share():
    assert math.degrees(stride_angle(0.6338, 0.897)) == pytest.approx(41.38, abs=0.01)
    assert swing_share(FIVE, SIDES) == pytest.approx(0.6)  # 16 + 8 of 40 intervals
    assert swing_share(POINT, SIDES) == pytest.approx(1.0)  # a point foot swings throughout


def test_a_slow_pitch_joint_lengthens_the_half_cycle_a_fast_one_keeps_walker3ds():
    """Romeo's numbers: L 0.6773 m, step 0.4785 m, time step 0.00869 s, hip pitch
    119.748 deg/s: 1.15 (pi/2) 41.37 / (119.748 0.6 40 0.00869) = 2.99, drafted 3.0."""
    args = (0.4785, 0.6773, 0.00869, FIVE, SIDES)
    pace = scaling_upper(*args, {"LHipPitch": 119.748, "RAnklePitch": 120.321})
    assert pace.needed == pytest.approx(2.99, abs=0.005) and pace.upper == 3.0
    assert pace.joint == "LHipPitch" and pace.speed == 119.748
    assert "sigma <= 3.0, so that the slowest hip or ankle pitch joint, LHipPitch" in \
        pace.comment().replace("\n# ", " ")
    fast = scaling_upper(*args, {"left_hip_pitch": 1146.0})
    assert fast.upper == SIGMA_UPPER and fast.needed < 0.5
    assert "sigma <= 1.5, walker3d's" in fast.comment()
    assert scaling_upper(*args, {}).upper == SIGMA_UPPER  # no limit: no rule
    # rounded up, never down: just above 2.0 is 2.1
    speed = SPEED_MARGIN * math.pi / 2 * math.degrees(stride_angle(0.4785, 0.6773)) / (
        2.001 * 0.6 * 40 * 0.00869)
    assert scaling_upper(*args, {"hip": speed}).upper == 2.1


def _drafted(urdf: str) -> tuple[list[float], float, dict, str]:
    text = draft_scene(urdf).yaml
    gait = yaml.safe_load(text)["gait"]
    leg = float(re.search(r"L = ([0-9.]+) m", text).group(1))
    return gait["scaling_bounds"], leg, gait, text


@pytest.mark.parametrize("joint", ["hip_pitch", "ankle"])
def test_a_draft_bounds_sigma_by_its_slow_hip_or_ankle_pitch(joint):
    """The synthetic biped's hip pitch or ankle (about y) at 1 rad/s: the draft's bound is
    the rule's, from its own step, leg and time step; its header says why."""
    slow = {f"{side}_{joint}_joint": 1.0 for side in ("left", "right")}
    bounds, leg, gait, text = _drafted(biped(velocities=slow))
    needed = SPEED_MARGIN * math.pi / 2 * math.degrees(stride_angle(gait["step_length"], leg)) \
        / (math.degrees(1.0) * 0.6 * 40 * gait["base_time_step"])
    assert needed > 2 * SIGMA_UPPER
    assert bounds == [0.5, math.ceil(needed * 10) / 10]
    assert f"# scaling_bounds: sigma <= {bounds[1]:.1f}, so that the slowest hip or ankle " \
        f"pitch joint,\n# left_{joint}_joint (57.3 deg/s)" in text


@pytest.mark.parametrize("slow", [{}, {"left_knee_joint": 1.0, "right_knee_joint": 1.0},
                                  {"left_hip_roll_joint": 1.0, "right_hip_roll_joint": 1.0}])
def test_fast_sweeping_joints_keep_walker3ds_bound(slow):
    """A slow knee (its swing flexion is the clearance's, not the step's) or a slow hip
    roll (a straight walk only sways it) leaves walker3d's 1.5."""
    bounds, *_, text = _drafted(biped(velocities=slow))
    assert bounds == [0.5, SIGMA_UPPER]
    assert "# scaling_bounds: sigma <= 1.5, walker3d's: the slowest hip or ankle pitch" in text


@pytest.mark.parametrize("path, importer, upper", [
    ("g1_description/urdf/g1_29dof_rev_1_0.urdf", {}, 1.5),
    ("talos_data/robots/talos_reduced.urdf", {"mirror_tolerance": 0.06}, 1.5),
    ("icub_description/robots/icub_reduced.urdf", {}, 1.5),
    ("bolt_description/robots/bolt.urdf", {}, 1.5),
    ("alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf", {}, 1.5),
    ("romeo_description/urdf/romeo_small.urdf", {}, 3.0),  # hip and ankle pitch 120 deg/s
])
def test_example_robots_drafted_bounds(example_robots, path, importer, upper):
    draft = draft_scene((example_robots / path).read_text(),
                        package_dirs=[str(example_robots.parents[1])], **importer)
    assert yaml.safe_load(draft.yaml)["gait"]["scaling_bounds"] == [0.5, upper]
