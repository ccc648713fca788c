"""The peers' shared plumbing (benchmarks/peers): the exchange format and the adapter test of
issue #27 — a DMOCC plan written as plan.npz and measured by measure.py reproduces DMOCC's
own physics_error, the other measures and its walk in MuJoCo (walker2d, 4 intervals per
phase)."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.peers import exchange, measure as measure_module
from benchmarks.peers.measure import (effort_physics_error, measure, measure_dmocc,
                                      plan_result, squared_torque)

# Both sides integrate the same node states and torques (the round trip through the
# exchange format changes them by round-off, 6e-16); what is left is DOP853 at rtol 1e-10
# on inputs that differ by round-off: measured 3e-10 relative on every drift.
RELATIVE = 1e-6


@pytest.fixture(scope="module")
def dmocc(walker2d_dmocc):
    return walker2d_dmocc[:2]


def _as_plan(result, problem) -> exchange.Plan:
    """DMOCC's half cycle as a peer would write it (node torques, linear between nodes)."""
    d = problem["dmocc"]
    K = len(d["times"]) - 1
    index = {p["name"]: i for i, p in enumerate(problem["phases"])}
    meta = {**{k: "" for k in exchange.META_KEYS}, "converged": True,
            "objective": result.cost_value, "iterations": result.stats.iterations,
            "solve_time": result.stats.solve_time, "build_time": 0.0}
    return exchange.Plan(times=d["times"], q=d["q"], tau_nodes=d["tau_nodes"],
                         phase_of_node=np.array([index[result.phases[n]] for n in range(K + 1)]),
                         meta=meta, forces={c: np.asarray(result.contact_forces[c])[:K + 1]
                                            for c in problem["contact_frames"]})


def test_a_dmocc_plan_through_the_exchange_format_measures_as_dmocc_itself(dmocc, tmp_path):
    result, problem = dmocc
    path = exchange.write_plan(tmp_path / "plan.npz", _as_plan(result, problem))
    plan = exchange.read_plan(path)
    rebuilt, _, hold = plan_result(problem, plan)
    assert hold == "linear"
    # the continuation node appended by the mirror is DMOCC's node N
    np.testing.assert_allclose(rebuilt.q, result.q, atol=1e-12)
    np.testing.assert_allclose(rebuilt.tau, result.tau, atol=1e-9)
    assert rebuilt.active_contacts == result.active_contacts
    ours, theirs = measure(problem, plan), measure_dmocc(result, problem)
    assert not ours["physics_failure"] and not theirs["physics_failure"]
    for key in ("drift_node_rms_deg", "drift_node_max_deg", "drift_phase_rms_deg",
                "drift_phase_max_deg", "swing_phase_mm", "periodicity_gap_mm",
                "force_error_n", "squared_torque"):
        assert ours[key] == pytest.approx(theirs[key], rel=RELATIVE), key
    assert ours["contact_hold_mm"] < 1e-6 and ours["joint_limit_deg"] < 1e-6
    assert ours["plan_periodicity_mm"] < 1e-6  # DMOCC's node N-1 is mirror(node 0)
    assert ours["cone_violation_n"] < 1e-6


def test_a_dmocc_plan_through_the_exchange_format_walks_as_dmocc_itself(dmocc, tmp_path,
                                                                        monkeypatch):
    """The peer path's PlanResult (its joint rates continued periodically as DMOCC's) is
    recorded and walked as DMOCC's own: the same reference, so the same walk."""
    result, problem = dmocc
    monkeypatch.setattr(measure_module, "WALK_STEPS", 3)
    rebuilt, _, _ = plan_result(problem, _as_plan(result, problem))
    np.testing.assert_allclose(rebuilt.joint_velocities, result.joint_velocities, atol=1e-9)
    np.testing.assert_allclose(rebuilt.joint_accelerations, result.joint_accelerations,
                               atol=1e-6)
    np.testing.assert_allclose(rebuilt.kinetic_energy, result.kinetic_energy, rtol=1e-12)
    ours = measure_module.walk_measures(rebuilt, tmp_path / "peer.mcap")
    theirs = measure_module.walk_measures(result, tmp_path / "dmocc.mcap")
    assert ours["walk_steps"] == 3 and ours["walk_half_cycles"] == theirs["walk_half_cycles"]
    assert ours["walk_stopped"] == theirs["walk_stopped"]
    assert ours["walk_joint_rms_deg"] == pytest.approx(theirs["walk_joint_rms_deg"], rel=1e-6)


def test_zero_order_hold_torques_drive_the_simulation_per_interval(dmocc):
    """The same plan with each interval's torque held at its first node's value drifts
    differently from the linear one: the hold reaches the simulation."""
    result, problem = dmocc
    linear = _as_plan(result, problem)
    held = exchange.Plan(times=linear.times, q=linear.q, tau=linear.tau_nodes[:-1],
                         phase_of_node=linear.phase_of_node, meta=linear.meta)
    drift = {}
    for plan in (linear, held):
        rebuilt, efforts, hold = plan_result(problem, plan)
        drift[hold] = effort_physics_error(rebuilt, efforts, hold, "node").angle_drift_rms_deg
        K = len(plan.times) - 1
        own = squared_torque(rebuilt.times, efforts, hold, K)
    assert abs(drift["linear"] - drift["zero"]) > 1e-3
    h = np.diff(linear.times)
    assert own == pytest.approx(float(h @ (held.tau ** 2).sum(1)), rel=1e-12)


def test_the_mirror_is_an_involution_up_to_two_steps(dmocc):
    _, problem = dmocc
    q = problem["dmocc"]["q"]
    twice = exchange.mirror_configuration(problem, exchange.mirror_configuration(problem, q))
    expected = q.copy()
    expected[:, 0] += 2 * problem["step_length"]
    np.testing.assert_allclose(twice, expected, atol=1e-12)


def test_pinocchio_configurations_round_trip():
    rng = np.random.default_rng(0)
    q = rng.uniform(-3, 3, size=(5, 10))
    pin_q = exchange.to_pinocchio(q, [2, 1, 2])
    assert pin_q.shape == (5, 12)
    np.testing.assert_allclose(exchange.from_pinocchio(pin_q, [2, 1, 2]), q, atol=1e-12)


def test_write_plan_refuses_inconsistent_shapes(tmp_path):
    meta = {k: 0 for k in exchange.META_KEYS}
    good = dict(times=np.arange(3.0), q=np.zeros((3, 8)), phase_of_node=np.zeros(3, int),
                meta=meta)
    with pytest.raises(ValueError, match="exactly one"):
        exchange.write_plan(tmp_path / "a.npz", exchange.Plan(**good))
    with pytest.raises(ValueError, match="tau"):
        exchange.write_plan(tmp_path / "a.npz", exchange.Plan(**good, tau=np.zeros((3, 1))))
    with pytest.raises(ValueError, match="meta lacks"):
        exchange.write_plan(tmp_path / "a.npz",
                            exchange.Plan(**{**good, "meta": {}}, tau=np.zeros((2, 1))))
