"""The plan's time of a walk (`gait_planner.walk.clock`): it runs with the simulated time
while the walker keeps up, slower while it lags, faster while it leads, within its bounds."""

from __future__ import annotations

import pytest
from hypothesis import given, strategies as st

from gait_planner.walk.clock import PlanClock

H = 0.0005


def test_a_walker_on_its_plan_follows_the_simulated_time():
    clock = PlanClock(0.25, 0.5, 1.5)
    for _ in range(1000):
        clock.pace(H, 0.0, 1.2)
    assert clock(0.5) == pytest.approx(0.5, abs=1e-12)


def test_a_walker_behind_its_plan_slows_the_plan_and_one_ahead_hurries_it():
    behind, ahead = PlanClock(0.25, 0.5, 1.5), PlanClock(0.25, 0.5, 1.5)
    for _ in range(1000):  # 0.5 s, 0.12 m behind / ahead of a plan at 1.2 m/s
        behind.pace(H, -0.12, 1.2)
        ahead.pace(H, 0.12, 1.2)
    assert behind(0.5) == pytest.approx(0.5 * (1 - 0.025), rel=1e-9)  # rate 1 - 0.25 * 0.1
    assert ahead(0.5) == pytest.approx(0.5 * (1 + 0.025), rel=1e-9)


@given(lead=st.floats(-10, 10), speed=st.floats(0.1, 5), gain=st.floats(0, 10))
def test_the_rate_stays_within_its_bounds(lead, speed, gain):
    rate = PlanClock(gain, 0.5, 1.5).rate(lead, speed)
    assert 0.5 <= rate <= 1.5
    assert rate == pytest.approx(min(max(1 + gain * lead / speed, 0.5), 1.5))


@pytest.mark.parametrize("low, high", [(0.0, 1.5), (1.1, 1.5), (0.5, 0.9)])
def test_bounds_that_stop_or_reverse_the_plan_are_refused(low, high):
    with pytest.raises(ValueError, match="0 < low <= 1 <= high"):
        PlanClock(0.25, low, high)
