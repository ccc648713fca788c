"""The strike approach (`strike_deceleration_max`, issue #40 item 3): bounding the striking
point's speed over its swing, growing away from the strike, spreads the swing leg's braking
over the swing. walker3d's default plan brakes in the last intervals (its left knee's second
difference 49 % of the knee's peak at node 14, 2026-11-29); with 40 m/s^2 the roughest
strong joint's is 24 %, every check passes, J 21.099 against 20.956. The verifier checks
the bound from the recording."""

from __future__ import annotations

import dataclasses

import pytest

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.verify import verify_recording
from gait_planner.verify.mechanics import parse_scene
from gait_planner.verify.physical import check_physical

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def approached(tmp_path_factory):
    scene = load_scene("walker3d")
    result = plan_once(Planner(), scene, settings_for(scene, strike_deceleration_max=40.0))
    assert result.success, result.message
    return write_plan_mcap(result, tmp_path_factory.mktemp("approach") / "walker3d.mcap")


def test_the_swing_slows_over_its_swing_and_every_check_passes(approached, solved):
    report = verify_recording(approached)
    assert report.ok, report.failures
    rough, joint, node = report.physical.roughest_joint
    default, default_joint, default_node = solved("walker3d").report.physical.roughest_joint
    assert (default_joint, default_node) == ("knee_l", 14) and default > 0.45
    assert rough < 0.3 and rough < default / 1.5, (joint, node)
    assert report.physical.max_torque_second_difference < \
        solved("walker3d").report.physical.max_torque_second_difference


def test_the_verifier_checks_the_bound_from_the_recording(approached):
    rec = read_plan_mcap(approached)
    scene, mu = parse_scene(rec.scene_text), float(rec.metadata["friction_coefficient"])
    assert rec.metadata["strike_deceleration_max"] == "40.0"
    assert check_physical(rec, scene, mu).ok
    tighter = dataclasses.replace(rec, metadata={**rec.metadata,
                                                 "strike_deceleration_max": "10.0"})
    failures = check_physical(tighter, scene, mu).failures
    assert any("before its strike" in f and "strike_deceleration_max 10 m/s^2" in f
               for f in failures), failures
