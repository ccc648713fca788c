"""Transitions (`ocp.transition`, `gait_planner.transitions`): from a given start state onto
the periodic gait, as one certified motion; starts the first phase cannot hold refused."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from gait_planner.model.angles import configuration
from gait_planner.model.loader import load_scene
from gait_planner.model.multibody import Multibody
from gait_planner.ocp.contacts import body_contacts, phase_treads
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.transition import (StartError, StartState, check_start, standing_start,
                                         start_of_plan, transition_scene, transition_settings,
                                         turned_start)
from gait_planner.ocp.transcription import Transcription
from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.ocp.mirror import configuration_mirror, mirror_parts
from gait_planner.ocp.walk_on import walk_on
from gait_planner.strategies import plan_certified
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.transitions import plan_transition, start_of_node, start_of_recording
from gait_planner.verify import verify_result
from gait_planner.walk.followed import Followed
from synthetic_result import make_result


@pytest.fixture(scope="module", params=["walker2d", "walker3d"])
def gait(request):
    """(scene, settings, planner, the certified periodic plan), derivatives compiled
    (`make setup` builds the shipped scenes' elements)."""
    scene = load_scene(request.param)
    settings = settings_for(scene, compiled=True)
    planner = Planner()
    plan, _ = plan_certified(planner, scene, settings)
    assert plan.success, plan.message
    return scene, settings, planner, plan


def test_the_transition_from_the_plans_own_first_node_is_that_plan(gait):
    """From the gait's node 0 with its discrete momentum the gait is feasible; the
    transition's optimum may differ only by what the transition frees: the torques and
    contact forces of node 0 and node N-1, which the periodic plan ties by the mirror
    (walker3d: J 4.5e-7 higher, nodes within 0.43 mm; without the cost on the join's
    torques, `CostTerms._join_torques`, 2.3e-5 and 2.8 mm)."""
    scene, settings, planner, plan = gait
    result = plan_transition(planner, scene, settings, start_of_plan(plan), steps=1,
                             halves=1)
    assert result.success, result.message
    N = plan.n_nodes - 1
    assert result.n_nodes == 2 * (N - 1) + 2  # the transition, one half cycle, its last two nodes
    assert result.settings["transition_nodes"] == str(N)
    assert result.cost_value == pytest.approx(plan.cost_value, rel=1e-5)
    assert np.abs(result.q[:N] - plan.q[:N]).max() < 1e-3
    assert np.array_equal(result.q[0], plan.q[0])
    assert "OK" in result.settings["continuous_dynamics"]


def test_a_start_off_the_gait_returns_onto_it(gait):
    """2 cm sideways (3D) and 0.1 rad/s off the gait's first node: the transition ends
    on the gait's next half cycle, the joined motion continues it, and the recording
    passes every check of the verifier."""
    scene, settings, planner, plan = gait
    start = turned_start(scene, start_of_plan(plan), 0.02, 0.1)
    result = plan_transition(planner, scene, settings, start, steps=2, halves=1)
    assert result.success, result.message
    N = plan.n_nodes - 1
    assert np.abs(result.q[0] - start.q).max() < 1e-12  # the start, to round-off
    # node N-1 is the gait's node 0 mirrored (a step on): the root back at the gait's side
    assert result.n_nodes == 3 * (N - 1) + 2
    assert result.q[N - 1, 1] == pytest.approx(-plan.q[0, 1], abs=1e-8)
    assert np.all(np.diff(result.times) > 0)
    report = verify_result(result)
    assert report.ok, report.summary()


@pytest.mark.parametrize("gait", ["walker2d", pytest.param("walker3d", marks=pytest.mark.slow)],
                         indirect=True)
def test_two_half_cycles_from_the_plans_own_first_node_are_the_gait_walked(gait):
    """A transition of two half cycles (the second copy of the phases mirrored) from the
    gait's own first node is the gait walked two half cycles: J twice the gait's."""
    scene, settings, planner, plan = gait
    result = plan_transition(planner, scene, settings, start_of_plan(plan), steps=2,
                             halves=2)
    assert result.success, result.message
    N = plan.n_nodes - 1
    assert result.settings["transition_nodes"] == str(2 * (N - 1) + 1)
    assert result.cost_value == pytest.approx(2 * plan.cost_value, rel=1e-5)
    walked = walk_on(plan, 4)
    assert np.abs(result.q - walked.q).max() < 1e-3
    assert verify_result(result).ok


@pytest.mark.slow
def test_a_start_one_half_cycle_cannot_mend_takes_two():
    """walker3d 1.3 cm sideways and rolling at -0.099 rad/s: in one half cycle the
    optimum needs 2000-4600 iterations, J twice the gait's, and misses the certificate or
    zigzags (benchmarks/HISTORY.md); in two (the default) every check passes."""
    scene = load_scene("walker3d")
    settings = settings_for(scene, compiled=True)
    planner = Planner()
    plan, _ = plan_certified(planner, scene, settings)
    start = turned_start(scene, start_of_plan(plan), 0.013, -0.099)
    result = plan_transition(planner, scene, settings, start, steps=2)
    assert result.success, result.message
    assert result.settings["transition_half_cycles"] == "2"
    assert result.cost_value < 2.02 * plan.cost_value
    report = verify_result(result)
    assert report.ok, report.summary()


def test_a_start_on_the_other_foot_is_planned_as_its_mirror_image(gait, tmp_path):
    """The state a walk's recording has where its second half cycle begins (the other
    foot flat): planned mirrored and mirrored back, the answer begins at that state and
    is the gait walked on (J the gait's), and passes every check."""
    scene, settings, planner, plan = gait
    walked = walk_on(plan, 3)
    path = write_plan_mcap(walked, tmp_path / "walked.mcap")
    N = plan.n_nodes - 1
    start = start_of_recording(scene, str(path), float(walked.times[N - 1]) + 1e-9)
    result = plan_transition(planner, scene, settings, start, steps=2, halves=1)
    assert result.success, result.message
    assert result.settings["transition_mirrored"] == "true"
    assert np.abs(result.q[0] - walked.q[N - 1]).max() < 1e-12
    assert result.active_contacts[0] == walked.active_contacts[N - 1]
    assert result.cost_value == pytest.approx(plan.cost_value, rel=1e-5)
    report = verify_result(result)
    assert report.ok, report.summary()


def test_starts_the_first_phase_cannot_hold_are_refused():
    scene = load_scene("walker2d")
    settings = settings_for(scene)
    mb = Multibody(scene)
    q = configuration(scene)  # the scene's pose
    contact = next(c for c in scene.contacts if c.name == scene.gait.phases[0].contacts[0])
    height = float(mb.point_matrix(contact.body, contact.point)[2] @ q)
    lowered = q.copy()
    lowered[2::12] -= height + 0.02  # every body 2 cm lower than the contact on the ground
    with pytest.raises(StartError, match=rf"{contact.name} is 20.0 mm below the ground"):
        check_start(scene, settings, StartState(lowered, np.zeros(mb.k), "test"))
    with pytest.raises(StartError, match="NaN"):
        check_start(scene, settings, StartState(np.full(mb.k, np.nan), np.zeros(mb.k), "t"))
    with pytest.raises(StartError, match="director coordinates"):
        check_start(scene, settings, StartState(q[:-1], np.zeros(mb.k), "test"))
    broken = q.copy()
    broken[3] += 0.1  # a director no longer of unit length
    with pytest.raises(StartError, match="breaks the joints"):
        check_start(scene, settings, StartState(broken, np.zeros(mb.k), "test"))
    name, lo, hi = next((n, lo, hi) for n, lo, hi in settings.joint_limits
                        if n in {j.name for j in scene.joints})
    pose = scene.initial_pose
    bent = configuration(scene, dataclasses.replace(
        pose, joint_angles={**pose.joint_angles, name: (hi + 0.2,)}))
    with pytest.raises(StartError, match=rf"joint {name} is at {np.degrees(hi + 0.2):.1f} deg"):
        check_start(scene, settings, StartState(bent, np.zeros(mb.k), "test"))


def test_a_stop_ends_at_rest_in_the_scenes_stop_phases(gait):
    """The stop's problem (`transition_scene(..., stop=True)`, settings.end_at_rest): the
    half cycle one interval short, then the scene's stop phases (the swing on, then both
    feet flat), each with a sigma of its own; its nodes N-1 and N are node N-2 for any
    unknowns (at rest: node N-1's equation a static equilibrium), only node 0 is fixed."""
    scene, settings, planner, plan = gait
    tr_settings = transition_settings(settings, plan, walk_on(plan, 2), start_of_plan(plan), 1,
                                      stop=True)
    tr_scene = transition_scene(scene, 1, stop=True)
    stop = scene.gait.stop
    assert tr_scene.gait.phases[-len(stop):] == tuple(
        dataclasses.replace(p, scaling=scene.gait.n_scalings + i) for i, p in enumerate(stop))
    assert set(tr_scene.gait.phases[-1].contacts) == {c.name for c in scene.contacts}
    one = [int(i) for i in plan.settings["intervals_per_phase"].split(",")]
    assert tr_settings.intervals == tuple(one[:-1]) + (one[-1] - 1,) + tuple(
        p.intervals for p in stop)
    tr = Transcription(DiscreteMechanics(Multibody(tr_scene)), tr_settings)
    N, nd = tr.N, tr.mb.ndof
    rng = np.random.default_rng(1)
    x, p = 0.05 * rng.standard_normal(tr.x.shape[0]), rng.standard_normal(tr.p.shape[0])
    p[: tr.layout.free * tr.mb.k] = np.tile(plan.q[0], tr.layout.free)
    Q = np.array(ca.Function("Q", [tr.x, tr.p], [tr.Q])(x, p))
    assert np.array_equal(Q[:, N], Q[:, N - 2]) and np.array_equal(Q[:, N - 1], Q[:, N - 2])
    lbx, ubx, _, _ = tr.bounds()
    fixed = np.flatnonzero(lbx == ubx)
    assert set(fixed) == set(range(nd))  # u_0 only


def test_a_standing_start_begins_with_the_scenes_start_phases(gait):
    """`standing_start`: the scene's pose at rest, held by its first start phase (both feet
    flat); `transition_scene(..., standing=True)`: the start phases first, a sigma each
    after the K copies'; the settings' grid begins with their intervals. A scene that
    declares no start phases is refused."""
    scene, settings, planner, plan = gait
    start = standing_start(scene)
    assert start.standing and not start.momentum.any()
    check_start(scene, settings, start)  # all four points on the ground
    tr_scene = transition_scene(scene, 2, standing=True)
    n, begin = scene.gait.n_scalings, scene.gait.start
    assert tr_scene.gait.phases[: len(begin)] == tuple(
        dataclasses.replace(p, scaling=2 * n + i) for i, p in enumerate(begin))
    assert tr_scene.gait.phases[len(begin)] == scene.gait.phases[0]
    tr_settings = transition_settings(settings, plan, walk_on(plan, 3), start, 2)
    assert tr_settings.intervals[: len(begin)] == tuple(p.intervals for p in begin)
    assert not any(tr_settings.start_momentum)
    with pytest.raises(StartError, match="'compass' declares no start from standing"):
        standing_start(load_scene("compass"))


@pytest.mark.parametrize("stop", [False, True])
def test_on_stairs_each_landing_foot_steps_one_tread_beyond_the_last(stop):
    """`phase_treads` over walker3d's transition of two half cycles, from standing or to
    standing: both feet stand on tread 0, the first landing foot touches down on tread 1,
    the second (the first copy's stance foot) on tread 2, a foot that stays down keeps its
    tread, and a stop's last foot sets down beside the other. (The establishing rows held
    every point but the first half cycle's landing foot at tread 0, so no transition of
    two half cycles on stairs could converge; benchmarks/HISTORY.md.)"""
    scene = load_scene("walker3d")
    mb = Multibody(scene)
    phases = transition_scene(scene, 2, standing=not stop, stop=stop).gait.phases
    stops = {p.name for p in scene.gait.stop} if stop else set()
    treads = phase_treads([body_contacts(mb, p.contacts) for p in phases],
                          [p.name in stops for p in phases])
    down = {phase.name: t for phase, t in zip(phases, treads)}
    assert down["double_heel"] == {"foot_r_forefoot": 0, "foot_l_heel": 1}
    assert down["double_full~2"] == {"foot_l_forefoot": 1, "foot_r_heel": 2,
                                     "foot_r_forefoot": 2}
    if stop:
        assert set(down["at_rest"].values()) == {2}
    else:
        assert set(down["left_heel_off"].values()) == {0}


@pytest.mark.slow
def test_from_standing_the_walker_sets_off_onto_the_gait(gait):
    """From the scene's standing pose at rest (two half cycles, the first step 0.7 of the
    gait's, `transitions.FIRST_STEP`): node 0 is that pose, all four contact points loaded
    there, the motion joins the gait and passes every check of the verifier, the
    certificate included; from this module's gait, planned cold (walker3d's did not
    converge with a first step half the gait's: 2706 iterations; benchmarks/HISTORY.md)."""
    scene, settings, planner, plan = gait
    start = standing_start(scene)
    result = plan_transition(planner, scene, settings, start, steps=1, from_last=False)
    assert result.success, result.message
    assert np.abs(result.q[0] - start.q).max() < 1e-12
    assert result.settings["transition_standing"] == "true"
    assert set(result.active_contacts[0]) == {c.name for c in scene.contacts}
    assert all(f[0, 2] > 0 for f in result.contact_forces.values())
    report = verify_result(result)
    assert report.ok, report.summary()


@pytest.mark.parametrize("gait", ["walker2d", pytest.param("walker3d", marks=pytest.mark.slow)],
                         indirect=True)
def test_a_stop_ends_standing_at_rest(gait):
    """From the gait's first node, one half cycle and the scene's stop phases: the last
    three nodes are one configuration (at rest), both feet flat and loaded there, every
    check of the verifier passed."""
    scene, settings, planner, plan = gait
    result = plan_transition(planner, scene, settings, None, stop=True, from_last=False)
    assert result.success, result.message
    assert np.array_equal(result.q[-1], result.q[-3]) and np.array_equal(result.q[-2],
                                                                         result.q[-3])
    assert set(result.active_contacts[-2]) == {c.name for c in scene.contacts}
    assert all(f[-2, 2] > 0 for f in result.contact_forces.values())
    report = verify_result(result)
    assert report.ok, report.summary()


def _strike_nodes(plan) -> list[int]:
    """The nodes of `walk.followed.Followed.strikes` of a plan."""
    t = np.asarray(plan.times) - plan.times[0]
    return [int(np.argmin(np.abs(t - s))) for s in Followed.of_result(plan).strikes]


def test_a_walks_strikes_are_the_first_nodes_of_its_gaits_half_cycles(gait):
    """Where a re-plan or a stop starts: at each strike of the gait walked on, and of the
    gait's part after a transition, the configuration is the gait's first node's mirrored
    k times and k steps on (a join node is recorded with the earlier half cycle's phase
    name; the node after it is not the strike's: walker2d 0.12 off)."""
    scene, settings, planner, plan = gait
    mb = Multibody.of(scene)
    A, e, c = configuration_mirror(mb, plan.ground)
    along = mirror_parts(mb)[1]
    s, N = plan.step_length, plan.n_nodes - 1

    def on_gait(q: np.ndarray) -> int | None:
        """k if q is the gait's first node k half cycles on, moved along x, else None."""
        image = np.asarray(plan.q[0], float)
        for k in range(8):
            moved = q - image
            if np.abs(moved - moved[along > 0][0] * along).max() < 1e-6:
                return k
            image = A @ image + s * e + c
        return None

    walked = walk_on(plan, 3)
    assert _strike_nodes(walked) == [N - 1, 2 * (N - 1)]
    # mirrored once; twice: the first node itself, two steps on
    assert [on_gait(walked.q[n]) for n in _strike_nodes(walked)] == [1, 0]
    joined = plan_transition(planner, scene, settings, turned_start(
        scene, start_of_plan(plan), 0.0, 0.05), steps=2, halves=2)
    assert joined.success, joined.message
    gait_part = [n for n in _strike_nodes(joined)
                 if n >= int(joined.settings["transition_nodes"]) - 1]
    assert len(gait_part) == 2  # the join node and one more (the last half cycle's end is none)
    assert None not in [on_gait(joined.q[n]) for n in gait_part]


def test_a_stop_from_where_the_last_stop_began_starts_warm_and_repeats_it(gait):
    """A stop from a strike of the gait walked on begins where the stop from the gait's
    first node began (mirrored and moved along x): it is planned from that stop with
    IPOPT's warm variant (`transitions.REPEATED_ATTEMPT`) in at most two iterations, and is
    that stop moved along, also when a stop from elsewhere was planned after it."""
    scene, settings, planner, plan = gait
    first = plan_transition(planner, scene, settings, None, stop=True)
    assert first.success, first.message
    elsewhere = turned_start(scene, start_of_plan(plan), 0.002, 0.01)
    newest = plan_transition(planner, scene, settings, elsewhere, stop=True)
    assert newest.success, newest.message
    walked = walk_on(plan, 3)
    n = _strike_nodes(walked)[1]  # the same foot's, two steps on
    start = start_of_node(scene, walked.q, walked.times, walked.generalized_force, n,
                          "the walk's second strike")
    again = plan_transition(planner, scene, settings, start, stop=True)
    assert again.success, again.message
    assert again.stats.iterations <= 2, again.stats.iterations
    assert "warm: it began at this start" in again.settings["initial_guess"]
    moved = again.q - first.q
    assert np.abs(moved - moved[0]).max() < 1e-5  # m: to the solver's tolerance


def test_a_planner_keeps_the_gaits_its_transitions_join_the_newest_first(monkeypatch):
    """`transitions.gait_to_join`: the same request's gait is planned once whatever the
    time limit, a failed plan is not kept, and at most `GAITS_KEPT` are, the least recently
    used dropped first."""
    import gait_planner.transitions as transitions

    planned = []

    def plan(planner, scene, settings, warm_start=True):
        planned.append(settings.step_length)
        return dataclasses.replace(solved, success=settings.step_length != 0.9), None

    scene = load_scene("walker2d")
    settings = settings_for(scene)
    solved = make_result("walker2d")
    monkeypatch.setattr(transitions, "plan_certified", plan)
    planner = Planner()
    ask = lambda step, limit=60.0: transitions.gait_to_join(  # noqa: E731
        planner, scene, dataclasses.replace(settings, step_length=step).with_solve(
            max_solve_time=limit))
    assert ask(0.5).success and ask(0.5, 0.3).success and planned == [0.5]
    assert not ask(0.9).success and not ask(0.9).success and planned == [0.5, 0.9, 0.9]
    for k in range(transitions.GAITS_KEPT):
        ask(0.6 + 0.01 * k)
    assert len(planner.gaits) == transitions.GAITS_KEPT
    ask(0.5)  # dropped as the least recently used: planned again
    assert planned[-1] == 0.5 and planned.count(0.5) == 2
