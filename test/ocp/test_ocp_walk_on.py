"""Walking on: K half cycles joined by the mirror are one continuous motion that satisfies the
discrete equations at every join (the verifier checks the joined recording), with positions
and velocities continuous at every join."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gait_planner.ocp.walk_on import walk_on
from gait_planner.verify import verify_result

STEPS = 4


@pytest.mark.parametrize("name", ["compass", "walker2d"])
def test_joined_half_cycles_verify_and_are_continuous(solved, name):
    r = solved(name).result
    joined = walk_on(r, STEPS)
    M = r.n_nodes - 2  # intervals per half cycle
    assert joined.n_nodes == STEPS * M + 2
    assert joined.times[-1] == pytest.approx(r.times[-1] + (STEPS - 1) * (r.times[M] - r.times[0]))
    assert joined.settings["steps"] == str(STEPS)
    report = verify_result(joined)
    assert report.ok, report.failures
    assert report.continuous.ok and report.physical.ok
    # no jump at any join: the velocity at a join is the central difference of its
    # neighbours, which belong to two different half cycles
    t, theta = joined.times, np.unwrap(joined.joint_angles, axis=0)
    for join in range(M, STEPS * M, M):
        h0, h1 = t[join] - t[join - 1], t[join + 1] - t[join]
        central = (h0 * (theta[join + 1] - theta[join]) / h1
                   + h1 * (theta[join] - theta[join - 1]) / h0) / (h0 + h1)
        np.testing.assert_allclose(joined.joint_velocities[join], central, atol=1e-9)
        step = theta[join + 1] - theta[join]
        assert np.abs(step).max() < np.radians(450) * h1 * 1.01  # no snap at the join
    # the whole motion advances by STEPS step lengths
    root = 0
    assert joined.q[STEPS * M, root] - joined.q[0, root] == pytest.approx(STEPS * r.step_length)


def test_a_broken_join_is_caught(solved):
    joined = walk_on(solved("walker2d").result, 2)
    q = joined.q.copy()
    q[50, 2] += 1e-6  # the torso's height in the second half cycle
    report = verify_result(dataclasses.replace(joined, q=q))
    assert any("not the mirror images of the first" in f for f in report.failures)


def test_one_step_is_the_plan_itself(solved):
    r = solved("compass").result
    assert walk_on(r, 1) is r
    with pytest.raises(ValueError, match="steps"):
        walk_on(r, 0)
