"""The warm-start store (`gait_planner.ocp.warm_starts`): a fresh planner re-plans warm from the plans
an earlier one kept on disk, to the same optimum; a damaged or foreign file is ignored."""

from __future__ import annotations

import dataclasses

import pytest

from gait_planner.model.loader import load_scene
from gait_planner.ocp.warm_starts import WarmStartStore, StoredPlan
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once


@pytest.fixture(scope="module")
def walker2d():
    return load_scene("walker2d")


@pytest.mark.slow
def test_a_fresh_planner_replans_warm_from_the_library_to_the_same_optimum(walker2d, tmp_path):
    settings = settings_for(walker2d)
    cold = plan_once(Planner(library=WarmStartStore(tmp_path)), walker2d, settings,
                     warm_start=False)
    assert cold.success, cold.message
    files = list((tmp_path / "plans").glob("*.npz"))
    assert len(files) == 1

    fresh = Planner(library=WarmStartStore(tmp_path))
    warm = plan_once(fresh, walker2d, settings)
    assert warm.success, warm.message
    assert "(the warm-start store" in warm.settings["initial_guess"]
    assert warm.stats.iterations < cold.stats.iterations / 4
    assert warm.cost_value == pytest.approx(cold.cost_value, rel=1e-8)

    again = plan_once(fresh, walker2d, settings, warm_start=False)  # cold_start ignores it
    assert again.settings["initial_guess"].startswith("kinematic guess")


@pytest.mark.slow
def test_a_request_with_other_settings_does_not_read_the_file(walker2d, tmp_path):
    plan_once(Planner(library=WarmStartStore(tmp_path)), walker2d, settings_for(walker2d),
              warm_start=False)
    other = plan_once(Planner(library=WarmStartStore(tmp_path)), walker2d,
                      settings_for(walker2d, friction_coefficient=0.6, intervals_per_phase=6))
    assert other.settings["initial_guess"].startswith("kinematic guess")
    assert len(list((tmp_path / "plans").glob("*.npz"))) == 2


@pytest.mark.slow
def test_a_damaged_file_is_ignored(walker2d, tmp_path):
    library = WarmStartStore(tmp_path)
    plan_once(Planner(library=library), walker2d, settings_for(walker2d), warm_start=False)
    (path,) = (tmp_path / "plans").glob("*.npz")
    path.write_bytes(path.read_bytes()[:200])
    result = plan_once(Planner(library=library), walker2d, settings_for(walker2d))
    assert result.success, result.message
    assert result.settings["initial_guess"].startswith("kinematic guess")


def test_the_newest_plan_of_a_request_replaces_the_older_and_at_most_max_plans_are_kept(tmp_path):
    import numpy as np

    from gait_planner.ocp.warm_starts import MAX_PLANS

    library = WarmStartStore(tmp_path)
    plans = [StoredPlan(0.1 * (i % (MAX_PLANS + 4)), 0.8, np.full(3, float(i)), np.zeros(3),
                        np.zeros(2), np.zeros((2, 4))) for i in range(MAX_PLANS + 8)]
    library.save("k", plans)
    loaded = library.load("k", 3, 2)
    assert len(loaded) == MAX_PLANS
    assert len({p.step for p in loaded}) == MAX_PLANS
    assert max(p.x[0] for p in loaded) == MAX_PLANS + 7
    assert library.load("k", 4, 2) == []


def test_pinned_plans_outlive_any_number_of_later_plans(tmp_path):
    """The plans `gait-planner prepare` keeps (the default and the warm-start anchors) stay
    when a busy process keeps more than MAX_PLANS of its own; one re-planned stays pinned."""
    import numpy as np

    from gait_planner.ocp.warm_starts import MAX_PLANS

    def plan(step: float, pinned: bool = False) -> StoredPlan:
        return StoredPlan(step, 0.8, np.full(3, step), np.zeros(3), np.zeros(2),
                          np.zeros((2, 4)), pinned=pinned)

    library = WarmStartStore(tmp_path)
    anchors = [plan(10.0 + i, pinned=True) for i in range(3)]
    later = [plan(0.01 * i) for i in range(3 * MAX_PLANS)]
    library.save("k", anchors + later + [plan(11.0)])  # anchor 11.0 re-planned, unpinned
    loaded = library.load("k", 3, 2)
    assert len(loaded) == 3 + MAX_PLANS
    assert {p.step for p in loaded if p.pinned} == {10.0, 11.0, 12.0}
    assert [p.step for p in loaded if not p.pinned] == [p.step for p in later[-MAX_PLANS:]]


def test_a_plan_kept_keeps_the_plans_another_process_pinned_meanwhile(tmp_path):
    """A node reads a problem's file once, when it builds the problem; a background
    `prepare` pins its plans into the file after that; the node's next plan is saved with
    them, not over them."""
    compass = load_scene("compass")
    settings = settings_for(compass)
    node = Planner(library=WarmStartStore(tmp_path))
    node.build(compass, settings, ())  # the file does not exist yet
    prepared = plan_once(Planner(library=WarmStartStore(tmp_path), pin=True), compass,
                         settings, warm_start=False)
    later = plan_once(node, compass, dataclasses.replace(settings, step_length=0.32),
                      warm_start=False)
    assert prepared.success and later.success, (prepared.message, later.message)
    kept = Planner(library=WarmStartStore(tmp_path)).stored_plans(compass, settings)
    assert sorted((p.step, p.pinned) for p in kept) == [(0.3, True), (0.32, False)]
