"""A scene's other gaits (`gaits:`, `gait_planner.model.loader.with_gait`): a request names
one, the scene it makes is validated when the scene loads, and its source is the YAML a
recording carries; the half cycle's last phase must mirror its first."""

from __future__ import annotations

import pytest

from gait_planner.model.loader import (SceneError, load_scene, scene_from_text, with_gait)

WALKER2D = load_scene("walker2d")


def test_walk_is_the_gait_block_and_run_changes_it():
    assert with_gait(WALKER2D, "") is WALKER2D and with_gait(WALKER2D, "walk") is WALKER2D
    run = with_gait(WALKER2D, "run")
    assert run.name == "walker2d_run" and run.gaits == ()
    assert [p.name for p in run.gait.phases] == ["right_stance", "flight", "left_stance"]
    assert run.gait.phases[1].contacts == ()
    assert run.gait.step_length == 1.0
    # options are merged entry by entry: the run's ranges, the walk's strike bound
    assert run.gait.options["joint_limits"]["knee_r"] == (0, 120)
    assert run.gait.options["strike_speed_max"] == WALKER2D.gait.options["strike_speed_max"]
    assert run.gait.mirror == WALKER2D.gait.mirror


def test_a_run_scene_source_is_the_scene_it_makes():
    run = with_gait(WALKER2D, "run")
    again = scene_from_text(run.source, "recording")
    assert again.name == run.name and again.gait == run.gait and again.bodies == run.bodies


def test_an_unknown_gait_is_refused_with_the_scene_gaits():
    with pytest.raises(SceneError, match=r"has no gait 'hop'; its gaits: walk, toe_first, run"):
        with_gait(WALKER2D, "hop")


def _with_gaits(block: str) -> str:
    return WALKER2D.source.split("\ngaits:")[0] + "\ngaits:\n" + block


def test_a_broken_gait_is_refused_when_the_scene_loads():
    with pytest.raises(SceneError, match="gaits.skip.mirror"):
        scene_from_text(_with_gaits("  skip:\n    mirror: {}\n"), "w.yaml")
    with pytest.raises(SceneError, match="walk"):
        scene_from_text(_with_gaits("  walk:\n    step_length: 0.5\n"), "w.yaml")
    with pytest.raises(SceneError, match=r"gait hop"):
        scene_from_text(_with_gaits("  hop:\n    step_length: -1\n"), "w.yaml")


def test_the_last_phase_must_mirror_the_first():
    """The half cycle's last interval is the mirror image of its first: a run that ends in
    flight (no left stance) is refused, as is a last phase with another time scale."""
    ends_in_flight = ("  run2:\n    phases:\n"
                      "      - {name: stance, contacts: [foot_r_forefoot], scaling: 0, intervals: 8}\n"
                      "      - {name: flight, contacts: [], scaling: 1, intervals: 8}\n")
    with pytest.raises(SceneError, match="must hold the mirror images of the first phase"):
        scene_from_text(_with_gaits(ends_in_flight), "w.yaml")
    other_scale = ("  run2:\n    phases:\n"
                   "      - {name: stance, contacts: [foot_r_forefoot], scaling: 0, intervals: 8}\n"
                   "      - {name: flight, contacts: [], scaling: 1, intervals: 8}\n"
                   "      - {name: land, contacts: [foot_l_forefoot], scaling: 1, intervals: 2}\n")
    with pytest.raises(SceneError, match="must share the first phase's scaling 0"):
        scene_from_text(_with_gaits(other_scale), "w.yaml")


def test_start_and_stop_phases_are_declared_with_a_time_scale_each():
    """gait.start and gait.stop (`model.scene.Gait`): their own phases, numbered after
    each other (start first), inherited by the scene's other gaits unless they change
    them; a phase name used twice and a standing phase that holds nothing are refused."""
    gait = WALKER2D.gait
    assert [(p.name, p.scaling) for p in gait.start] == [("stand", 0), ("left_heel_off", 1)]
    assert [(p.name, p.scaling) for p in gait.stop] == [("right_swing", 2), ("at_rest", 3)]
    assert set(gait.start[0].contacts) == set(gait.stop[-1].contacts) == {
        c.name for c in WALKER2D.contacts}
    assert with_gait(WALKER2D, "run").gait.start == gait.start
    text = WALKER2D.source.split("\ngaits:")[0]
    with pytest.raises(SceneError, match="duplicate phase name 'right_full'"):
        scene_from_text(text.replace("- {name: at_rest,", "- {name: right_full,"), "w.yaml")
    with pytest.raises(SceneError, match="phase 'stand' stands: it must hold contacts"):
        scene_from_text(text.replace(
            "- {name: stand, contacts: [foot_r_heel, foot_r_forefoot, foot_l_heel, "
            "foot_l_forefoot]", "- {name: stand, contacts: []"), "w.yaml")
