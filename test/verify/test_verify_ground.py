"""The verifier checks a recording against the ground it was planned for (issue #26).

Ramp and stairs recordings are made from a level walker2d plan (`grounds`, `conftest`): the
level plan turned rigidly onto a ramp is geometrically a plan on it, so every geometric check
passes (the dynamics fail: gravity is not turned); a plan lifted leg by leg onto stairs keeps
its held points on their treads and its mirror image one step up and on. Then one thing at a
time is planted wrong, and the check that owns it fails: vertical-cone forces on a ramp, the
mirror shifted without the rise, a held point off its tread, a swing foot inside a tread, a
segment between two clear nodes cutting a stair's corner, a strike too fast along the ramp.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gait_planner.verify import LIMITS, verify_plan
from gait_planner.verify.ground import RecordedGround
from gait_planner.verify.mechanics import Mechanics, parse_scene
from gait_planner.verify.physical import GROUND_BAND

from grounds import on_ramp, on_stairs, schedule

# words of the failure sentences of the checks that know the ground
GEOMETRIC = ("friction cone", "off the ground", "not flat", "below the ground", "pulls on",
             "not the mirror images of nodes 0, 1", "scuffing", "through the stairs",
             "strikes at")
RISE = 0.15  # m, the stairs' step height


def _failed(report, *words):
    """The failure sentences containing every word of `words`."""
    return [f for f in report.failures if all(w in f for w in words)]


def _geometric(report):
    return [f for f in report.failures if any(w in f for w in GEOMETRIC)]


def _stairs(rec, h: float = RISE, left=None):
    """`rec` on stairs of step height h, legs lifted so that the swing foot clears every
    tread (up: the landing leg rises early in the swing; down: late, after the edge);
    `left` replaces the landing leg's knots."""
    release, strike = schedule(rec)
    lift = max(h, 0.0) + 0.01  # the released leg ends 1 cm above its plain image
    right = ((release, release + 4), (0.0, lift))
    if left is None:
        left = (((1, 5), (lift - h, h)) if h > 0
                else ((1, strike - 4, strike), (lift - h, 0.0, h)))
    return on_stairs(rec, h, left, right)


# ------------------------------------------------------------------ the ground, alone


def test_the_ground_is_read_from_the_metadata():
    assert RecordedGround.of({}) == RecordedGround()
    assert RecordedGround.of({}).describe() == "level"
    ramp = RecordedGround.of({"slope": "10.0", "step_height": "0.0"})
    assert ramp.describe() == "ramp 10 deg up"
    np.testing.assert_allclose(ramp.normal, [-math.sin(math.radians(10)), 0.0,
                                             math.cos(math.radians(10))])
    stairs = RecordedGround.of({"step_height": "-0.15", "stair_riser": "0.44",
                                "stair_tread": "0.63"})
    assert stairs.describe().startswith("stairs 0.15 m down")
    assert stairs.rise(0.63) == -0.15 and ramp.rise(2.0) == pytest.approx(2.0 * math.tan(
        math.radians(10)))
    with pytest.raises(ValueError, match="slope"):
        RecordedGround.of({"slope": "steep"})
    with pytest.raises(ValueError, match="at once"):
        RecordedGround.of({"slope": "5", "step_height": "0.1", "stair_tread": "0.6"})
    with pytest.raises(ValueError, match="stair_tread"):
        RecordedGround.of({"step_height": "0.1"})


def test_heights_above_a_ramp_and_stairs():
    a = math.radians(10)
    ramp = RecordedGround(slope=10.0)
    along, normal = np.array([math.cos(a), 0.0, math.sin(a)]), ramp.normal
    assert ramp.above(0.7 * along + 0.02 * normal) == pytest.approx(0.02, abs=1e-15)
    stairs = RecordedGround(step_height=0.15, riser=0.44, tread=0.63)
    x = np.array([0.44 - 0.63 - 1e-9, 0.44 - 0.63, 0.44 - 1e-9, 0.44, 0.44 + 0.63])
    np.testing.assert_allclose(stairs.height(x), [-0.15, 0.0, 0.0, 0.15, 0.3])  # edges: ahead
    assert stairs.above([0.5, 0.0, 0.16]) == pytest.approx(0.01)


def test_a_segment_across_a_stair_edge_is_judged_at_the_edge():
    up = RecordedGround(step_height=0.15, riser=0.44, tread=0.63)
    # from 5 cm above tread 0 to 5 cm above tread 1: halfway, at the edge, 2.5 cm too low
    assert up.edge_clearance([0.34, 0, 0.05], [0.54, 0, 0.2]) == pytest.approx(-0.025)
    assert up.edge_clearance([0.34, 0, 0.2], [0.54, 0, 0.2]) == pytest.approx(0.05)
    assert up.edge_clearance([0.34, 0, 0.0], [0.43, 0, 0.0]) == math.inf  # no edge crossed
    down = RecordedGround(step_height=-0.15, riser=0.44, tread=0.63)
    # stairs down: the higher tread is behind the edge
    assert down.edge_clearance([0.54, 0, -0.13], [0.34, 0, 0.02]) == pytest.approx(-0.055)
    assert RecordedGround(slope=10.0).edge_clearance([0, 0, 0], [1, 0, -1]) == math.inf


def test_the_mirror_image_rises_with_the_ground(level_walk):
    rec = level_walk.single
    mech = Mechanics(parse_scene(rec.scene_text))
    q = np.asarray(rec.q[3])
    lift = mech.mirror(q, 0.6, 0.15) - mech.mirror(q, 0.6)
    z = [mech.start(b.name) + 2 for b in mech.scene.bodies]
    np.testing.assert_allclose(lift[z], 0.15, rtol=1e-14)
    assert not np.delete(lift, z).any()


# ------------------------------------------------------------------ level, as before


def test_a_level_recording_is_checked_on_level_ground(level_walk):
    report = verify_plan(level_walk.single)
    assert report.ok, report.failures
    assert report.ground == "level"
    assert report.summary().splitlines()[0].endswith("ground: level")
    assert math.isnan(report.physical.min_edge_clearance)  # no stairs: not measured
    assert "stair-edge" not in report.summary()


# ------------------------------------------------------------------ a ramp


@pytest.mark.parametrize("slope", [10.0, -10.0])
def test_a_plan_turned_onto_a_ramp_passes_every_geometric_check(level_walk, slope):
    level = verify_plan(level_walk.single)
    report = verify_plan(on_ramp(level_walk.single, slope))
    assert not _geometric(report), _geometric(report)
    assert report.ground == f"ramp 10 deg {'up' if slope > 0 else 'down'}"
    assert report.max_periodicity_error <= LIMITS["periodicity"]
    assert report.max_contact_height <= LIMITS["contact"]
    assert report.min_contact_point_height >= -LIMITS["ground"]
    # the cones, clearances and strike speeds are the level plan's, measured along the ramp
    assert report.max_friction_ratio == pytest.approx(level.max_friction_ratio, rel=1e-9)
    p, p_level = report.physical, level.physical
    assert p.max_point_friction_ratio == pytest.approx(p_level.max_point_friction_ratio,
                                                       rel=1e-9)
    assert p.min_swing_height == pytest.approx(p_level.min_swing_height, abs=1e-12)
    assert p.max_strike_speed == pytest.approx(p_level.max_strike_speed, rel=1e-9)
    assert _failed(report, "Euler-Lagrange")  # gravity is not turned: not a plan on the ramp


@pytest.mark.parametrize("slope", [-10.0, 20.0])
def test_vertical_cone_forces_fail_on_a_ramp(level_walk, slope):
    """Positions turned onto the ramp, forces left as the level plan's: braking leans 10 deg
    further from the downhill ramp's normal, push-off 20 deg from the uphill one's."""
    report = verify_plan(on_ramp(level_walk.single, slope, forces=False))
    assert _failed(report, "leaves the friction cone", "mu n . F")
    assert _failed(report, "leaves its own friction cone")
    assert report.max_friction_ratio > 1.0 and report.physical.max_point_friction_ratio > 1.0


def test_a_ramp_recording_checked_as_level_fails(level_walk):
    """Without its slope in the metadata the ramp plan's mirror image is not one step along
    x, and its held points are off z = 0."""
    rec = on_ramp(level_walk.single, 10.0)
    report = verify_plan(dataclasses.replace(rec, metadata=dict(rec.metadata, slope="0.0")))
    assert report.ground == "level"
    assert _failed(report, "not the mirror images of nodes 0, 1", "rise 0 m")
    assert _failed(report, "held contact", "off the ground")
    assert report.max_contact_height > 0.01


def test_a_strike_is_measured_along_the_ramp(level_walk):
    level = verify_plan(level_walk.single).physical.max_strike_speed
    rec = on_ramp(level_walk.single, 20.0)
    slower = dataclasses.replace(rec, metadata=dict(rec.metadata,
                                                    strike_speed_max=repr(float(0.99 * level))))
    assert _failed(verify_plan(slower), "strikes at", "along the ground")
    bound = dataclasses.replace(rec, metadata=dict(rec.metadata,
                                                   strike_speed_max=repr(float(1.0001 * level))))
    assert not _failed(verify_plan(bound), "strikes at")


def test_a_joined_ramp_recording_shifts_every_half_cycle_by_the_rise(level_walk):
    rec = on_ramp(level_walk.joined, 10.0)
    report = verify_plan(rec)
    assert not _failed(report, "half cycles 2..")
    assert not _geometric(report), _geometric(report)
    unrisen = verify_plan(dataclasses.replace(rec, metadata=dict(rec.metadata, slope="0.0")))
    assert _failed(unrisen, "half cycles 2..", "configuration off by")


# ------------------------------------------------------------------ stairs


@pytest.mark.parametrize("h", [RISE, -RISE])
def test_a_plan_lifted_onto_stairs_passes_every_geometric_check(level_walk, h):
    report = verify_plan(_stairs(level_walk.single, h))
    assert not _geometric(report), _geometric(report)
    assert report.ground.startswith(f"stairs 0.15 m {'up' if h > 0 else 'down'}")
    assert report.max_periodicity_error <= LIMITS["periodicity"]
    assert report.max_contact_height <= LIMITS["contact"]
    p = report.physical
    assert p.min_swing_height >= GROUND_BAND
    assert p.min_edge_clearance > 0.005 and p.edge_clearance_at is not None
    assert _failed(report, "joint hip_")  # the legs were lifted apart from the torso
    first = report.summary().splitlines()[0]
    assert "ground: stairs 0.15 m" in first
    assert "lowest stair-edge crossing" in report.summary()


def test_stairs_of_another_height_break_the_periodicity(level_walk):
    rec = _stairs(level_walk.single)
    report = verify_plan(dataclasses.replace(rec, metadata=dict(rec.metadata,
                                                                step_height="0.1")))
    assert _failed(report, "not the mirror images of nodes 0, 1", "rise 0.1 m")
    assert report.max_periodicity_error == pytest.approx(0.05, rel=1e-6)


def test_treads_deeper_than_the_step_fail(level_walk):
    rec = _stairs(level_walk.single)
    deeper = repr(1.1 * float(rec.metadata["stair_tread"]))
    report = verify_plan(dataclasses.replace(rec, metadata=dict(rec.metadata,
                                                                stair_tread=deeper)))
    assert _failed(report, "tread depth", "differs from the step length")
    assert not _failed(verify_plan(rec), "tread depth")


def test_a_held_point_off_its_tread_fails(level_walk):
    """The landing leg sets down 1 cm short of tread 1."""
    _, strike = schedule(level_walk.single)
    left = ((1, 5, strike - 1, strike), (0.01, RISE, RISE, RISE - 0.01))
    report = verify_plan(_stairs(level_walk.single, left=left))
    assert _failed(report, "held contact foot_l", "off the ground")
    assert report.max_contact_height == pytest.approx(0.01, rel=1e-6)


def test_a_swing_foot_inside_a_tread_fails(level_walk):
    """The swing leg rises late: its forefoot passes over tread 1 below the tread's height."""
    _, strike = schedule(level_walk.single)
    left = ((1, strike - 2, strike - 1), (0.01, 0.01, RISE))
    report = verify_plan(_stairs(level_walk.single, left=left))
    assert _failed(report, "scuffing", "foot_l_forefoot")
    assert _failed(report, "below the ground")
    assert report.physical.min_swing_height < -0.01


def _turned_at(rec, node: int, body: str, point: str, drop: float, pitch: float):
    """rec with `body` at `node` moved down by `drop` m and turned by `pitch` deg about the
    y axis through its contact point `point` (toes up for pitch > 0)."""
    mech = Mechanics(parse_scene(rec.scene_text))
    q = np.array(rec.q, dtype=float)
    a = math.radians(pitch)
    R = np.array([[math.cos(a), 0.0, -math.sin(a)], [0.0, 1.0, 0.0],
                  [math.sin(a), 0.0, math.cos(a)]])
    pivot = mech.contact_matrix(point) @ q[node]
    s = mech.start(body)
    q[node, s:s + 3] = pivot + R @ (q[node, s:s + 3] - pivot) - [0.0, 0.0, drop]
    for i in range(3):
        q[node, s + 3 + 3 * i:s + 6 + 3 * i] = R @ q[node, s + 3 + 3 * i:s + 6 + 3 * i]
    return dataclasses.replace(rec, q=q)


def test_a_segment_cutting_a_stair_corner_fails_between_clear_nodes(level_walk):
    """At the last node before the swing heel crosses the first edge, the foot is lowered
    to 1 cm above tread 0 and turned toes up so that its forefoot still clears tread 1: every
    node is clear, but the heel's straight path to the next node, over tread 1, cuts the
    edge."""
    rec = _stairs(level_walk.single)
    ground = RecordedGround.of(rec.metadata)
    mech = Mechanics(parse_scene(rec.scene_text))
    heel = np.array([mech.contact_matrix("foot_l_heel") @ row for row in rec.q])
    _, strike = schedule(rec)
    node = max(n for n in range(strike) if heel[n, 0] < ground.riser)
    cut = _turned_at(rec, node, "foot_l", "foot_l_heel", ground.above(heel[node]) - 0.01, 15.0)
    report = verify_plan(cut)
    assert _failed(report, "foot_l_heel passes", "through the stairs",
                   f"between nodes {node} and {node + 1}")
    p = report.physical
    assert p.edge_clearance_at == ("foot_l_heel", node)
    assert p.min_edge_clearance < -0.05
    assert p.min_swing_height >= GROUND_BAND and not _failed(report, "scuffing")
    assert "lowest stair-edge crossing (foot_l_heel" in report.summary()
    line = next(r for r in report.summary().splitlines() if "stair-edge" in r)
    assert line.endswith("FAILED")


# ------------------------------------------------------------------ walker3d: feet and edges


@pytest.mark.slow
def test_walker3d_on_a_ramp_keeps_its_feet_flat_on_it_and_its_foot_edges_clear(level_walker3d):
    """In 3D a full contact lies flat on the ramp (n . d2 = 0) and a swing foot's two edges
    p +- w d2 are measured along the normal: the turned plan measures as the level one;
    its vertical-cone forces fail downhill."""
    level = verify_plan(level_walker3d)
    report = verify_plan(on_ramp(level_walker3d, -10.0))
    assert not _geometric(report), _geometric(report)
    assert report.max_full_contact_roll <= LIMITS["contact"]
    assert report.physical.min_swing_height == pytest.approx(level.physical.min_swing_height,
                                                             abs=1e-12)
    assert report.physical.max_point_friction_ratio == pytest.approx(
        level.physical.max_point_friction_ratio, rel=1e-9)
    vertical = verify_plan(on_ramp(level_walker3d, -10.0, forces=False))
    assert _failed(vertical, "leaves its own friction cone")


def test_a_swing_point_on_the_ground_at_node_0_is_a_scuff_unless_released_there(level_walk):
    """Node 0 follows the previous half cycle's node N-2 mirrored: a point held there lifts
    off at node 0 (Bolt's point foot) and may touch; any other swing point may not."""
    rec = level_walk.single
    mech = Mechanics(parse_scene(rec.scene_text))
    assert not _failed(verify_plan(rec), "scuffing")
    held_before = {c.replace("_r_", "_x_").replace("_l_", "_r_").replace("_x_", "_l_")
                   for c in rec.active_contacts[rec.n_nodes - 3]}
    swing = [c for c in mech.scene.contacts if c not in rec.active_contacts[0]
             and c not in held_before]
    assert swing  # walker3d: the swing foot's points at node 0
    name = max(swing, key=lambda c: (mech.contact_matrix(c) @ rec.q[0])[2])
    body, _ = mech.scene.contacts[name]
    height = float((mech.contact_matrix(name) @ rec.q[0])[2])
    report = verify_plan(_turned_at(rec, 0, body, name, height, 0.0))
    assert _failed(report, "scuffing", f"('{name}', 0)")
