"""The swing-clearance schedule (`gait_planner.ocp.clearance`) against walker3d's schedule
counted by hand, and the properties any ramp keeps.

walker3d, 8 intervals per phase (39 in the half cycle; interval 39 is the image of 0):
right_full 0-7, right_forefoot 8-15, double_heel 16-23, double_full 24-31, left_full 32-38.
By the mirror, the left points were last held in the previous half cycle: foot_l_heel
released at node 8 - 39 = -31 and struck at 16, foot_l_forefoot released at 32 - 39 = -7
and struck at 24; foot_r_heel is released at 8 and struck at 16 + 39 = 55, foot_r_forefoot
released at 32 and struck at 24 + 39 = 63.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.clearance import required_clearances
from gait_planner.ocp.contacts import body_contacts
from gait_planner.verify.physical import GROUND_BAND

MARGIN = 0.01
# point -> (release node, strike node) around the half cycle, counted by hand (docstring)
EVENTS = {"foot_l_heel": (-31, 16), "foot_l_forefoot": (-7, 24),
          "foot_r_heel": (8, 55), "foot_r_forefoot": (32, 63)}


@pytest.fixture(scope="module")
def walker3d_held():
    scene = load_scene("walker3d")
    mb = Multibody(scene)
    phases = [{p for bc in body_contacts(mb, ph.contacts) for p in bc.points}
              for ph in scene.gait.phases]
    return scene, [phases[k] for k in np.repeat(np.arange(len(phases)), 8)][:39]


def expected(ramp_nodes: float, margin: float) -> dict[int, dict[str, float]]:
    out: dict[int, dict[str, float]] = {n: {} for n in range(1, 40)}
    for point, (release, strike) in EVENTS.items():
        for n in range(1, 40):
            if release < n < strike:
                k = min(n - release, strike - n)
                out[n][point] = margin * math.sin(0.5 * math.pi * min(1.0, k / max(ramp_nodes, 1)))
    return out


def test_swing_points_and_heights_match_the_schedule_counted_by_hand(walker3d_held):
    scene, held = walker3d_held
    for ramp in (0.0, 1.0, 4.0, 10.0):
        out = required_clearances(scene, held, MARGIN, ramp)
        want = expected(ramp, MARGIN)
        assert {n: set(p) for n, p in out.items()} == {n: set(p) for n, p in want.items()}
        for n in out:
            for point, height in out[n].items():
                assert height == pytest.approx(want[n][point], rel=1e-12), (ramp, n, point)


def test_without_a_ramp_every_swing_point_needs_the_full_margin(walker3d_held):
    scene, held = walker3d_held
    heights = {h for p in required_clearances(scene, held, MARGIN, 0.0).values()
               for h in p.values()}
    assert heights == {MARGIN}


def test_a_released_point_rises_and_a_striking_point_lowers(walker3d_held):
    scene, held = walker3d_held
    out = required_clearances(scene, held, MARGIN, 4.0)
    after_toe_off = [out[n]["foot_r_forefoot"] for n in range(33, 40)]
    before_heel_strike = [out[n]["foot_l_heel"] for n in range(10, 16)]
    assert np.all(np.diff(after_toe_off[:4]) > 0) and after_toe_off[3:] == [MARGIN] * 4
    assert np.all(np.diff(before_heel_strike[-4:]) < 0)
    assert "foot_r_heel" not in out[8] and "foot_l_heel" not in out[16]


@settings(max_examples=40, deadline=None)
@given(ramp=st.floats(0.0, 40.0), margin=st.floats(1e-3, 0.05))
def test_any_ramp_keeps_the_swing_points_and_bounds_the_heights(walker3d_held, ramp, margin):
    scene, held = walker3d_held
    out = required_clearances(scene, held, margin, ramp)
    flat = required_clearances(scene, held, margin, 0.0)
    assert {n: set(p) for n, p in out.items()} == {n: set(p) for n, p in flat.items()}
    lowest = margin * math.sin(math.pi / (2 * max(ramp, 1.0)))
    for points in out.values():
        for height in points.values():
            assert lowest * (1 - 1e-12) <= height <= margin


def test_the_declared_ramps_keep_swing_points_above_the_verifier_ground_band():
    for name in ("walker2d", "walker3d"):
        gait = load_scene(name).gait
        ramp_nodes = gait.options["swing_clearance_ramp"] / gait.base_time_step
        lowest = gait.options["swing_clearance"] * math.sin(math.pi / (2 * ramp_nodes))
        assert lowest > GROUND_BAND, (name, lowest)


def test_strikes_are_the_intervals_before_the_strike_nodes_counted_by_hand(walker3d_held):
    """Within the half cycle, foot_l_heel strikes at node 16 and foot_l_forefoot at 24
    (EVENTS); the right points strike in the next half cycle (55, 63), not here."""
    from gait_planner.ocp.clearance import strike_schedule

    scene, held = walker3d_held
    assert strike_schedule(scene, held) == {15: ("foot_l_heel",), 23: ("foot_l_forefoot",)}


def test_the_approach_reaches_back_over_each_striking_points_swing(walker3d_held):
    """`approach_schedule`: j intervals before each strike interval, back to the interval
    after the release, or to interval 0 for a swing that began in the previous half cycle
    (EVENTS: the left heel strikes at node 16, the forefoot at 24, both released before
    node 0)."""
    from gait_planner.ocp.clearance import approach_schedule, strike_schedule

    scene, held = walker3d_held
    expected: dict[int, dict[int, tuple[str, ...]]] = {}
    for point in ("foot_l_heel", "foot_l_forefoot"):
        last = EVENTS[point][1] - 1  # the strike's interval
        for m in range(0, last):
            expected.setdefault(last - m, {})[m] = (point,)
    assert approach_schedule(strike_schedule(scene, held), held) == expected
    # held again in interval 10: two strikes, each approached back to its own release
    held_again = [set(h) | ({"foot_l_heel"} if n == 10 else set()) for n, h in enumerate(held)]
    approach = approach_schedule(strike_schedule(scene, held_again), held_again)
    heel = sorted((m, j) for j, rows in approach.items() for m, points in rows.items()
                  if "foot_l_heel" in points)
    assert heel == [(m, 9 - m) for m in range(9)] + [(m, 15 - m) for m in range(11, 15)]


@settings(max_examples=60, deadline=None)
@given(pitch=st.floats(-0.6, 0.6), roll=st.floats(-0.6, 0.6), yaw=st.floats(-3.1, 3.1),
       width=st.floats(0.0, 0.08), slope=st.floats(-30.0, 30.0))
def test_ground_heights_are_the_foot_edges_heights_above_the_ramp(walker3d_held, pitch, roll,
                                                                   yaw, width, slope):
    """`ground_heights` of a swing point are the heights above the ground (along a ramp's
    normal) of the points +- width along its foot's d2, for any foot attitude and slope:
    the lower one is what clears the ground."""
    from gait_planner.model.ground import Ground
    from gait_planner.model.rotations import rot_x, rot_y, rot_z
    from gait_planner.ocp.clearance import ground_heights

    scene, _ = walker3d_held
    mb = Multibody(scene)
    q = np.zeros(mb.k)
    block = mb.block("foot_l")
    D = rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)
    q[block] = np.r_[0.1, 0.2, 0.3, D[:, 0], D[:, 1], D[:, 2]]
    point = mb.contact_rows("foot_l_heel") @ q
    rows = np.array(ground_heights(mb, ("foot_l_heel",), width, Ground(slope=slope))(q)).ravel()
    a = np.radians(slope)
    normal = np.array([-np.sin(a), 0.0, np.cos(a)])
    edges = sorted(normal @ (point + s * width * D[:, 1]) for s in (1.0, -1.0))
    assert rows.shape == ((2,) if width > 0 else (1,))
    assert sorted(rows) == pytest.approx(edges if width > 0 else [normal @ point], abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(x=st.floats(-0.8, 1.6), z=st.floats(-0.5, 0.5), rise=st.sampled_from([0.15, -0.15]))
def test_stair_clearance_is_the_height_above_the_tread_with_edges_moved_to_the_lower_one(
        walker3d_held, x, z, rise):
    """On stairs a swing point's `ground_heights` row is its height above the tread under
    it (treads -1 to 1, what a half cycle's swing foot passes over), except near an edge,
    where it is measured from the higher tread (the edge's step moved the ground's
    edge_margin, EDGE_MARGIN on stairs up and 0 on stairs down, towards the lower
    tread)."""
    from gait_planner.model.ground import EDGE_MARGIN, EDGE_WIDTH, Ground
    from gait_planner.ocp.clearance import ground_heights

    scene, _ = walker3d_held
    mb = Multibody(scene)
    ground = Ground(step_height=rise, riser=0.44, tread=0.63)
    q = np.zeros(mb.k)
    block = mb.block("foot_l")
    q[block] = np.r_[0.0, 0.0, 0.0, np.eye(3).T.ravel()]
    offset = mb.contact_rows("foot_l_heel") @ q
    q[block.start : block.start + 3] = np.array([x, 0.0, z]) - offset
    height = float(ground_heights(mb, ("foot_l_heel",), 0.0, ground)(q))
    edges = ground.riser + ground.tread * np.arange(-1, 2)
    distance = np.min(np.abs(x - edges))
    # away from every edge (its smooth step centred edge_margin + 5 widths from it, 10 more
    # widths clear of that centre): the tread's height
    if distance > EDGE_MARGIN + 15 * EDGE_WIDTH:
        assert height == pytest.approx(z - float(ground.height(x)), abs=1e-5)
    # near an edge (up to it from the higher tread, half the margin past it): at least the
    # higher tread's height
    towards_lower = (x - edges) * np.sign(-rise)
    near = (towards_lower >= -2 * EDGE_MARGIN) & (towards_lower <= ground.edge_margin / 2)
    if near.any():
        edge = edges[near][0]
        top = max(ground.height(edge - 1e-9), ground.height(edge + 1e-9))
        assert z - height >= top - 0.01 * abs(rise)


@pytest.mark.parametrize("rise", [0.15, -0.15, 0.0])
def test_segment_rows_are_the_free_points_of_each_interval_on_stairs_down(walker3d_held, rise):
    """On stairs down every interval lists the points it does not hold (the segment check's
    points) with the least required height of their two nodes, 0 next to a contact; on
    stairs up and on a plane none (a segment above a plane is lowest at a node)."""
    from gait_planner.model.ground import Ground
    from gait_planner.ocp.clearance import segment_schedule

    scene, held = walker3d_held
    ground = Ground(step_height=rise, riser=0.44, tread=0.63) if rise else Ground()
    clearances = required_clearances(scene, held, MARGIN, 2.0)
    out = segment_schedule(scene, held, ground, clearances)
    if rise >= 0:
        assert out == {}
        return
    # the same intervals for the midpoint rows of a start with the edge margin
    assert segment_schedule(scene, held, Ground(step_height=rise, riser=0.44, tread=0.63,
                                                segment_rows=False), clearances) == out
    names = [c.name for c in scene.contacts]
    assert {n: points for n, (points, _) in out.items()} == {
        n: tuple(p for p in names if p not in points)
        for n, points in enumerate(held) if set(names) - set(points)}
    # foot_r_heel is released at node 8 (held there): the segment 8 -> 9 starts on the tread;
    # at node 9 it is one node off the ground, sin(pi/4) of the margin with a 2-node ramp;
    # 12 -> 13 is mid-swing for all three free points
    assert out[8] == (("foot_r_heel", "foot_l_heel", "foot_l_forefoot"), 0.0)
    assert out[9][1] == pytest.approx(MARGIN * math.sin(math.pi / 4))
    assert out[12][1] == pytest.approx(MARGIN)


def _foot_at(mb, x, z, D=np.eye(3)):
    """walker3d's configuration (k,) with the left foot's director frame D and its heel at
    (x, 0.05, z); the other bodies at the origin."""
    q = np.zeros(mb.k)
    block = mb.block("foot_l")
    q[block] = np.r_[0.0, 0.0, 0.0, D[:, 0], D[:, 1], D[:, 2]]
    q[block.start : block.start + 3] = np.array([x, 0.05, z]) - mb.contact_rows("foot_l_heel") @ q
    return q


def _logistic(u):
    return 0.5 * (1.0 + np.tanh(0.5 * u))


@settings(max_examples=40, deadline=None)
@given(a=st.tuples(st.floats(-0.5, 1.5), st.floats(-0.3, 0.3)),
       b=st.tuples(st.floats(-0.5, 1.5), st.floats(-0.3, 0.3)),
       required=st.floats(0.0, 0.02))
def test_segment_heights_are_each_end_above_the_staircase_at_the_other(walker3d_held, a, b,
                                                                      required):
    """`segment_heights` of two configurations: each end's height above the smooth
    staircase at the other end's x, less the required height (positions are linear in the
    director coordinates, so the point is the heel's)."""
    from gait_planner.model.ground import Ground
    from gait_planner.model.rotations import rot_x, rot_y
    from gait_planner.ocp.clearance import segment_heights

    scene, _ = walker3d_held
    mb = Multibody(scene)
    ground = Ground(step_height=-0.15, riser=0.44, tread=0.63)
    q0, q1 = _foot_at(mb, *a, rot_y(0.3)), _foot_at(mb, *b, rot_x(0.2) @ rot_y(-0.4))
    got = np.array(segment_heights(mb, ("foot_l_heel",), 0.0, ground)(
        q0, q1, 0.01, [0.01, required])).ravel()
    g = lambda x: float(ground.clearance_height(x, _logistic))  # noqa: E731
    assert got == pytest.approx([a[1] - g(b[0]) - required, b[1] - g(a[0]) - required],
                                abs=1e-12)


@settings(max_examples=300, deadline=None)
@given(x0=st.floats(-0.5, 1.5), x1=st.floats(-0.5, 1.5), z0=st.floats(-0.3, 0.3),
       z1=st.floats(-0.3, 0.3))
def test_segments_whose_rows_hold_do_not_cut_a_stair_corner(x0, x1, z0, z1):
    """A segment whose two ends clear the smooth staircase (stairs down) at their own x and
    at each other's by the verifier's GROUND_BAND passes above every corner: the
    verifier's own segment check (`RecordedGround.edge_clearance`) finds no cut."""
    from gait_planner.model.ground import Ground
    from gait_planner.verify.ground import RecordedGround

    ground = Ground(step_height=-0.15, riser=0.44, tread=0.63)
    g = lambda x: float(ground.clearance_height(x, _logistic))  # noqa: E731
    rows = [z0 - g(x0), z1 - g(x1), z0 - g(x1), z1 - g(x0)]
    if min(rows) < GROUND_BAND:
        return
    recorded = RecordedGround(step_height=-0.15, riser=0.44, tread=0.63)
    assert recorded.edge_clearance([x0, 0.0, z0], [x1, 0.0, z1]) >= 0.0


@settings(max_examples=40, deadline=None)
@given(a=st.tuples(st.floats(-0.5, 1.5), st.floats(-0.3, 0.3)),
       b=st.tuples(st.floats(-0.5, 1.5), st.floats(-0.3, 0.3)))
def test_midpoint_heights_are_the_heights_of_the_segment_midpoints(walker3d_held, a, b):
    """`midpoint_heights` (the rows of a start with the edge margin) of two configurations
    is the clearance height of the midpoint of the point's two positions (positions are
    linear in the director coordinates)."""
    from gait_planner.model.ground import Ground
    from gait_planner.model.rotations import rot_x, rot_y
    from gait_planner.ocp.clearance import midpoint_heights

    scene, _ = walker3d_held
    mb = Multibody(scene)
    ground = Ground(step_height=-0.15, riser=0.44, tread=0.63, segment_rows=False)
    q0, q1 = _foot_at(mb, *a, rot_y(0.3)), _foot_at(mb, *b, rot_x(0.2) @ rot_y(-0.4))
    got = float(midpoint_heights(mb, ("foot_l_heel",), 0.0, ground)(
        q0, q1, 0.01, [0.01, 0.0]))
    rows = mb.contact_rows("foot_l_heel")
    mid = 0.5 * (rows @ q0 + rows @ q1)
    tread = ground.clearance_height(mid[0], _logistic)
    assert got == pytest.approx(mid[2] - float(tread), abs=1e-12)
