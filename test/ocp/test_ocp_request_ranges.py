"""Requests that cannot be planned are refused before anything is built, in milliseconds,
with the field, its value and the range the scene allows."""

from __future__ import annotations


import pytest

from gait_planner.model.loader import load_scene
from gait_planner.ocp.request_ranges import reach
from gait_planner.ocp.solve import Planner
from gait_planner.pipeline import plan_and_record
from gait_planner.request import PlanRequest, RequestError
from gait_planner.problem import resolve


def test_reach_is_the_chain_between_the_feet():
    # walker3d: forefoot to ankle, calf, thigh on each side, plus the hips' spacing
    forefoot_ankle = ((0.1403 + 0.0644) ** 2 + (0.0502 + 0.0133) ** 2) ** 0.5
    expected = 2 * (forefoot_ankle + 0.1943 + 0.1810 + 0.2803 + 0.1779) + 2 * 0.0936
    assert reach(load_scene("walker3d")) == pytest.approx(expected, rel=1e-12)
    assert reach(load_scene("compass")) == pytest.approx(2.0)  # two 1 m legs


@pytest.mark.parametrize("fields, words", [
    ({"step_length": 100.0}, ("step_length = 100.0", "(0, 2.283] m")),
    ({"step_length": 2.3}, ("step_length = 2.3", "reach")),
    ({"friction_coefficient": 1e-6}, ("friction_coefficient = 1e-06", "[0.05, 5.0]")),
    ({"intervals_per_phase": 100000}, ("intervals_per_phase = 100000", "[2, 32]")),
    ({"intervals_per_phase": 1}, ("intervals_per_phase = 1", "[2, 32]")),
    ({"max_solve_time": 1e9}, ("max_solve_time = 1000000000.0", "(0, 3600] s")),
])
def test_impossible_requests_are_refused_at_once(tmp_path, fields, words):
    planner = Planner()
    with pytest.raises(RequestError) as caught:
        plan_and_record(planner, resolve(PlanRequest(scene="walker3d", **fields)), tmp_path)
    assert all(w in str(caught.value) for w in words), str(caught.value)
    assert "walker3d" in str(caught.value)
    assert not planner._built and not list(tmp_path.iterdir())  # nothing built or written
