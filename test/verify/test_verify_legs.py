"""The verifier's legs-apart check (`gait_planner.verify.legs`) on walker3d recordings: its
own (numpy) distances between the legs' spheres are the planner's (`gait_planner.ocp.legs`),
legs that touch fail and legs closer than the plan's clearance are noted. On the URDF's
own geometry by coal: test/model/test_urdf_collision.py and the robots' plans
(test/ocp/test_ocp_robot.py)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from gait_planner.model.multibody import Multibody
from gait_planner.ocp.legs import leg_sphere_distances
from gait_planner.verify import verify_result
from gait_planner.verify.legs import LegClearance, judge_legs


def test_the_recordings_sphere_distances_are_the_planners(result):
    legs = verify_result(result).legs
    assert legs.source == "the collision spheres of the scene"
    distances = leg_sphere_distances(Multibody(result.scene))
    ours = np.array([distances(q).full().min() for q in result.q])
    np.testing.assert_allclose(legs.distance, ours, rtol=0, atol=1e-12)
    assert legs.node == int(np.argmin(ours)) and legs.pair[0].endswith("_r")
    assert np.isnan(legs.clearance)  # the synthetic result's metadata names none


def test_feet_moved_into_each_other_fail_a_plan_that_kept_them_apart(result):
    q = np.array(result.q)
    index = [b.name for b in result.scene.bodies]
    right, left = (12 * index.index(name) for name in ("foot_r", "foot_l"))
    q[4, left:left + 3] = q[4, right:right + 3] + [0.0, 0.05, 0.0]  # 5 cm apart, radii 6 cm
    kept = dataclasses.replace(result, q=q, settings={**result.settings, "leg_clearance": "0.01"})
    report = verify_result(kept)
    assert report.legs.node == 4 and report.legs.smallest < 0 and report.legs.clearance == 0.01
    assert any(f.startswith("the legs touch: foot_r and foot_l at node 4") for f in
               report.failures)
    report = verify_result(dataclasses.replace(result, q=q))  # legs_apart false: noted
    assert not any("the legs touch" in f for f in report.failures)
    assert any(n.startswith("the legs touch, ") and "not asked" in n for n in report.notes)


def test_touching_fails_and_closer_than_the_clearance_is_noted():
    cases = {(0.03, 0.02, 0.01): ([], []), (0.03, 0.005, 0.01): ([], ["less than the plan's"]),
             (0.03, 0.0, 0.01): (["the legs touch"], []),
             (0.03, -0.01, 0.01): (["the legs touch"], []),
             (0.03, -0.01, math.nan): ([], ["not asked to keep them apart"]),
             (0.03, 0.005, math.nan): ([], [])}
    for (*distance, clearance), (failed, noted) in cases.items():
        failures, notes = [], []
        judge_legs(LegClearance(np.array(distance), int(np.argmin(distance)), ("a", "b"),
                                "spheres", clearance), failures, notes)
        assert [w for w in failed if any(w in f for f in failures)] == failed and \
            len(failures) == len(failed)
        assert [w for w in noted if any(w in n for n in notes)] == noted and \
            len(notes) == len(noted)
