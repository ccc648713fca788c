"""The grid of a gait library: parsing, refusals, neighbours and seeds."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.gaitlib.grid import GridError, parse_grid
from gait_planner.gaitlib.build import seed_points


def test_ranges_include_their_stop_and_lists_are_sorted():
    grid = parse_grid("step_length=0.4:0.9:0.05, friction_coefficient=1.0/0.4/0.7")
    assert grid.fields == ("step_length", "friction_coefficient")
    assert grid.axes[0][1] == pytest.approx([0.4 + 0.05 * i for i in range(11)])
    assert grid.axes[1][1] == (0.4, 0.7, 1.0)
    assert grid.shape == (11, 3) and len(grid.indices()) == 33
    assert grid.values((2, 1)) == {"step_length": pytest.approx(0.5), "friction_coefficient": 0.7}
    assert parse_grid(grid.text()) == grid


@pytest.mark.parametrize("text, words", [
    ("", "no axis"), ("step_length", "not field=values"), ("height=0.1:0.2:0.1", "step_height"),
    ("step_length=0.4:0.9", "start:stop:step"), ("step_length=0.9:0.4:0.1", "stop >= start"),
    ("step_length=0.4:0.9:0", "step > 0"), ("step_length=0.5/0.5", "repeated"),
    ("step_length=0.5/nan", "not finite"), ("step_length=a", "not a number"),
    ("step_length=0.5,step_length=0.6", "twice"),
    ("step_length=0:10:0.001,speed=0:10:0.001", "more than"),
    ("step_length=0:1000:0.001", "values"),
])
def test_a_bad_grid_is_refused_naming_the_axis(text, words):
    with pytest.raises(GridError, match=words):
        parse_grid(text)


@settings(max_examples=50, deadline=None)
@given(shape=st.lists(st.integers(1, 5), min_size=1, max_size=3), data=st.data())
def test_neighbours_are_one_index_away_along_one_axis_and_mutual(shape, data):
    fields = ["step_length", "friction_coefficient", "slope"][: len(shape)]
    grid = parse_grid(",".join(f"{f}=" + "/".join(str(v) for v in range(n))
                               for f, n in zip(fields, shape)))
    index = data.draw(st.sampled_from(grid.indices()))
    around = grid.neighbours(index)
    assert len(set(around)) == len(around)
    for other in around:
        assert sum(abs(a - b) for a, b in zip(index, other)) == 1
        assert index in grid.neighbours(other)
    assert len(around) == sum((i > 0) + (i < n - 1) for i, n in zip(index, shape))


def test_seeds_start_at_the_centre_and_spread_to_the_corners():
    grid = parse_grid("step_length=0/1/2/3/4,friction_coefficient=0/1/2/3/4")
    seeds = seed_points(grid, 3, grid.indices())
    assert seeds[0] == (2, 2)
    assert all(max(abs(a - 2) for a in s) == 2 for s in seeds[1:])
    assert len(set(seeds)) == 3
    assert seed_points(grid, 5, [(0, 0)]) == [(0, 0)]
