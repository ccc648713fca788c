"""The torques' second differences in the cost (`torque_smoothness`, issue #40 item 3).

walker2d's default plan brakes its swing leg where a strike row touches its bound for one
node: its left hip's torque jumps there and back (the roughest strong joint's second
difference half that joint's peak, 2026-11-30). With w = 1e-4 per (N m)^2 times the sum of
the squared second differences in the cost, both of item 3's figures are met (6.7 % of the
largest peak, 11.2 % of the knee's own; J 21.3247 against 21.0252), and every check passes.
"""

from __future__ import annotations

import numpy as np
import pytest

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import SettingsError, settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.verify import verify_recording

TARGET_PEAK, TARGET_OWN = 0.20, 0.25  # issue #40 item 3


@pytest.fixture(scope="module")
def smooth(tmp_path_factory):
    scene = load_scene("walker2d")
    result = plan_once(Planner(), scene, settings_for(scene, torque_smoothness=1e-4))
    assert result.success, result.message
    return result, write_plan_mcap(result, tmp_path_factory.mktemp("smooth") / "walker2d.mcap")


def test_the_penalty_meets_both_smoothness_targets_where_the_default_plan_does_not(
        smooth, solved):
    report = verify_recording(smooth[1])
    assert report.ok, report.failures
    default = solved("walker2d").report.physical
    assert default.roughest_joint[0] > TARGET_OWN  # what the option is for
    rough, joint, node = report.physical.roughest_joint
    assert rough <= TARGET_OWN, (joint, node)
    assert report.physical.max_torque_second_difference <= TARGET_PEAK


def test_the_reported_cost_is_the_kinetic_energy_without_the_penalty(smooth):
    result, path = smooth
    rec = read_plan_mcap(path)
    assert rec.metadata["torque_smoothness"] == "0.0001"
    assert float(rec.metadata["cost_value"]) == pytest.approx(
        float(rec.metadata["kinetic_energy"]), rel=1e-12)
    effort = np.asarray(rec.effort, dtype=float)
    penalty = 1e-4 * float((np.diff(effort, 2, axis=0) ** 2).sum())
    assert penalty > 1e-3 * result.cost_value  # a penalty the optimum felt, left out of J


@pytest.mark.parametrize("option, value, why", [
    ("torque_smoothness", -1.0, "torque_smoothness: must be >= 0, got -1.0"),
    ("torque_smoothness", "high", "torque_smoothness: must be a number, got 'high'"),
    ("swing_clearance", True, "swing_clearance: must be a number, got True"),
])
def test_a_weight_that_is_not_a_non_negative_number_is_refused_by_name(option, value, why):
    with pytest.raises(SettingsError, match=why):
        settings_for(load_scene("walker2d"), **{option: value})
