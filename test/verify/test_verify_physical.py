"""The physical checks of a recording (gait_planner.verify.physical): the default plans pass
them, and each planted defect of a real plan is caught by its own check."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gait_planner.io.mcap_reader import read_plan_mcap
from gait_planner.verify.mechanics import Mechanics, parse_scene
from gait_planner.verify.physical import (GROUND_BAND, JOINT_SPEED_MAX, ZIGZAG_STEP,
                                          check_physical, near_switch)


@pytest.fixture(scope="module")
def walker2d(solved):
    s = solved("walker2d")
    rec = read_plan_mcap(s.path)
    return rec, parse_scene(rec.scene_text), float(rec.metadata["friction_coefficient"])


@pytest.mark.parametrize("name", ["compass", pytest.param("walker2d", marks=pytest.mark.slow),
                                  pytest.param("walker3d", marks=pytest.mark.slow)])
def test_default_plans_are_physical(solved, name):
    report = solved(name).report
    assert report.ok, report.failures
    physical = report.physical
    assert physical.ok
    assert physical.max_point_friction_ratio < 1.0
    assert physical.max_joint_speed < JOINT_SPEED_MAX
    assert not physical.zigzags
    if name != "compass":  # the rigid-legged compass must scuff at mid-stance
        assert not physical.scuffs
        # the scenes' swing_clearance (1 cm), ramped over 0.03 s = 3 base steps after a
        # release and before a strike (`ocp.clearance`): 1 cm x sin(pi / 6) one node away
        options = solved(name).scene.gait.options
        assert (options["swing_clearance"], options["swing_clearance_ramp"]) == (0.01, 0.03)
        assert physical.min_swing_height >= 0.005 - 1e-9


def test_the_default_plan_passes(walker2d):
    assert check_physical(*walker2d).ok


def test_per_point_cone_violation_with_the_same_net_force_fails(walker2d):
    rec, scene, mu = walker2d
    n = next(n for n, names in enumerate(rec.contact_names)
             if {"foot_r_heel", "foot_r_forefoot"} <= set(names))
    forces = [f.copy() for f in rec.contact_force_vectors]
    names = rec.contact_names[n]
    push = np.array([2.0 * mu * forces[n][:, 2].max(), 0.0, 0.0])
    forces[n][names.index("foot_r_heel")] += push
    forces[n][names.index("foot_r_forefoot")] -= push  # the foot's net force is unchanged
    report = check_physical(dataclasses.replace(rec, contact_force_vectors=tuple(forces)),
                            scene, mu)
    assert not report.ok
    assert report.max_point_friction_ratio > 1.0
    assert any("friction cone" in f and f"node {n}" in f for f in report.failures)


def test_swing_point_on_the_ground_is_a_scuff(walker2d):
    rec, scene, mu = walker2d
    mech = Mechanics(scene)
    C = mech.contact_matrix("foot_r_forefoot")
    free = [n for n in range(2, rec.n_nodes)
            if "foot_r_forefoot" not in rec.active_contacts[n]
            and "foot_r_forefoot" not in rec.active_contacts[n - 1]]
    n = free[len(free) // 2]
    q = rec.q.copy()
    z = (C @ q[n])[2]
    q[n, 12 * scene.body_index("foot_r") + 2] -= z  # lower the foot onto the ground
    report = check_physical(dataclasses.replace(rec, q=q), scene, mu)
    assert ("foot_r_forefoot", n) in report.scuffs
    assert report.min_swing_height < GROUND_BAND
    assert any("scuffing" in f for f in report.failures)


def test_fast_joint_fails(walker2d):
    rec, scene, mu = walker2d
    velocities = rec.velocities.copy()
    velocities[5, 1] = np.radians(JOINT_SPEED_MAX + 50.0)
    report = check_physical(dataclasses.replace(rec, velocities=velocities), scene, mu)
    assert report.max_joint_speed == pytest.approx(JOINT_SPEED_MAX + 50.0)
    assert any(rec.joint_names[1] in f and "deg/s" in f for f in report.failures)


def test_planted_zigzag_away_from_switches_fails(walker2d):
    rec, scene, mu = walker2d
    switch = near_switch(rec.n_nodes, check_physical(*walker2d).switch_nodes)
    n = next(n for n in range(2, rec.n_nodes - 4) if not switch[n - 1 : n + 5].any())
    effort = rec.effort.copy()
    amplitude = 3 * ZIGZAG_STEP * np.abs(effort).max()
    effort[n : n + 4, 0] += amplitude * np.array([1.0, -1.0, 1.0, -1.0])
    report = check_physical(dataclasses.replace(rec, effort=effort), scene, mu)
    assert any(angle == rec.joint_names[0] for angle, _ in report.zigzags)
    assert any("zigzag" in f for f in report.failures)
