"""Foot slides (`gait_planner.walk.slides`): a point that carries load and moves has slid by
its displacement along the ground, whatever the ground's tilt; a point in the air or below
the threshold has not; each stance is measured apart, and the walk reports its largest."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.walk.slides import Slides

LEVEL = np.array([0.0, 0.0, 1.0])


def _feed(slides: Slides, loads, positions, dt: float = 0.001) -> None:
    """loads (steps,) N of one point pressed along the ground's normal, with a tangential
    force of a tenth of it; positions (steps, 3) m."""
    n = slides.normal
    side = np.cross(n, [0.0, 1.0, 0.0] if abs(n[1]) < 0.9 else [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    for k, (load, position) in enumerate(zip(loads, positions)):
        force = load * n + 0.1 * load * side
        slides.update(k * dt, force[None, :], np.array([force @ n]),
                      np.asarray(position, dtype=float)[None, :])


@settings(max_examples=60, deadline=None)
@given(tilt=st.floats(-0.35, 0.35), along=st.floats(-0.1, 0.1), across=st.floats(-0.05, 0.05),
       sink=st.floats(-0.01, 0.01))
def test_the_slide_is_the_displacement_along_the_ground(tilt, along, across, sink):
    n = np.array([-np.sin(tilt), 0.0, np.cos(tilt)])  # a ramp's normal
    t1 = np.array([np.cos(tilt), 0.0, np.sin(tilt)])  # up the ramp
    t2 = np.array([0.0, 1.0, 0.0])
    start = np.array([0.3, 0.1, 0.05])
    end = start + along * t1 + across * t2 + sink * n  # sinking into the ground is no slide
    path = [start + s * (end - start) for s in np.linspace(0.0, 1.0, 50)]
    slides = Slides(["toe"], 50.0, n)
    _feed(slides, [400.0] * 50, path)
    largest = slides.summary()
    assert largest["slide_mm"] == pytest.approx(1e3 * np.hypot(along, across), abs=0.06)
    assert largest["friction_used"] == pytest.approx(0.1, abs=1e-3)
    assert largest["point"] == "toe" and largest["start_s"] == 0.0
    assert largest["end_s"] == pytest.approx(0.049)


def test_a_point_in_the_air_has_not_slid():
    slides = Slides(["heel"], 50.0, LEVEL)
    moving = [[0.01 * k, 0.0, 0.02] for k in range(30)]
    _feed(slides, [0.0] * 15 + [40.0] * 15, moving)  # unloaded, then below the threshold
    assert slides.summary() is None


def test_each_stance_is_measured_apart_and_the_largest_reported():
    slides = Slides(["heel"], 50.0, LEVEL)
    # stands 10 steps sliding 5 mm, lifts (the point moves 0.3 m in the air), stands again
    # sliding 20 mm
    first = [[0.0005 * k, 0.0, 0.0] for k in range(11)]
    air = [[0.3, 0.0, 0.05]] * 5
    second = [[0.3 + 0.002 * k, 0.0, 0.0] for k in range(11)]
    _feed(slides, [500.0] * 11 + [0.0] * 5 + [500.0] * 11, first + air + second)
    largest = slides.summary()
    assert largest["slide_mm"] == pytest.approx(20.0)
    assert largest["start_s"] == pytest.approx(0.016)
