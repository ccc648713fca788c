"""What a planner keeps in memory (`ocp.solve.Planner`): each problem it builds is measured
(`memory_kept`), and before a new one is built, a planner short of memory forgets the
problems it used least recently, never the last one used; a refinement is built when
forgetting them makes the room for it (`strategies._no_room_for`), and nothing is forgotten
when it would not."""

from __future__ import annotations

import pytest

from gait_planner.model.loader import load_scene
from gait_planner import strategies
from gait_planner.ocp import solve
from gait_planner.ocp.refine import refined_memory, refined_settings
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner


@pytest.fixture(scope="module")
def compass_grids():
    """The compass's scene and its settings on 3, 4 and 5 intervals a phase."""
    scene = load_scene("compass")
    return scene, [settings_for(scene, intervals_per_phase=n, compiled=False)
                   for n in (3, 4, 5)]


def _built(planner: Planner, scene, grids) -> list[int]:
    """Which of `grids` the planner keeps (their intervals a phase)."""
    return [s.intervals[0] for s in grids if planner.memory_kept(scene, s) is not None]


def test_each_problem_built_is_measured(compass_grids):
    scene, grids = compass_grids
    planner = Planner()
    planner.build(scene, grids[0], ())
    assert planner.memory_kept(scene, grids[0]) > 0
    assert planner.memory_kept(scene, grids[1]) is None  # not built


def test_short_of_memory_the_problem_used_least_recently_is_forgotten(compass_grids,
                                                                      monkeypatch):
    scene, grids = compass_grids
    planner = Planner()
    for s in (grids[0], grids[1], grids[0]):  # 3 used last
        planner.build(scene, s, ())
    monkeypatch.setattr(solve, "available_bytes", lambda: 0)
    planner.build(scene, grids[2], ())
    assert _built(planner, scene, grids) == [3, 5]


def test_with_memory_to_spare_every_problem_is_kept(compass_grids, monkeypatch):
    scene, grids = compass_grids
    planner = Planner()
    monkeypatch.setattr(solve, "available_bytes", lambda: 10**15)
    for s in grids:
        planner.build(scene, s, ())
    assert _built(planner, scene, grids) == [3, 4, 5]


@pytest.mark.parametrize("room", [True, False])
def test_a_refinement_is_built_if_forgetting_makes_the_room(compass_grids, monkeypatch, room):
    """The memory available rises by what the older problem kept once it is forgotten:
    with enough then, the refinement of the last problem used is not refused and the older
    problem is forgotten; one byte short, it is refused and nothing is forgotten."""
    scene, grids = compass_grids
    planner = Planner()
    for s in grids[:2]:  # 4 used last: the coarse grid
        planner.build(scene, s, ())
    coarse, older = planner.memory_kept(scene, grids[1]), planner.memory_kept(scene, grids[0])
    need = refined_memory(coarse)
    short = need - older - (0 if room else 1)
    free = lambda: short + (0 if _built(planner, scene, grids) == [3, 4] else older)  # noqa: E731
    monkeypatch.setattr(solve, "available_bytes", free)
    why = strategies._no_room_for(planner, scene, grids[1], refined_settings(grids[1]))
    if room:
        assert why == "" and _built(planner, scene, grids) == [4]
    else:
        assert "its problem would take about" in why and _built(planner, scene, grids) == [3, 4]
