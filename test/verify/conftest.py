"""Level plans, recorded, shared by the verifier's ground tests.

`level_walk` plans walker2d with its default settings once per session (about 10 s on this
2-core machine, the compiled cache warm), records it with the real MCAP writer, and also
records it joined to two of its mirror images (`gait_planner.ocp.walk_on`, 3 half cycles);
both are read back with `gait_planner.io.mcap_reader`. `level_walker3d` is walker3d's
default plan, recorded the same way (20 to 45 s: for tests marked slow). The synthetic ramp
and stairs recordings of `grounds` are made from these.
"""

from __future__ import annotations

from typing import NamedTuple

import pytest

from solved_plans import solved  # noqa: F401  (the plans shared with test/ocp)

from gait_planner.io.mcap_reader import RecordedPlan, read_plan_mcap
from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.ocp.walk_on import walk_on

JOINED_STEPS = 3


class LevelWalk(NamedTuple):
    single: RecordedPlan  # one half cycle
    joined: RecordedPlan  # JOINED_STEPS half cycles


def _recorded(name: str, folder, steps: int = 1) -> list[RecordedPlan]:
    """Scene `name`'s default plan, recorded as one half cycle (and joined, steps > 1)."""
    scene = load_scene(name)
    result = plan_once(Planner(), scene, settings_for(scene))
    if not result.success:
        pytest.fail(f"{name}: no level plan: {result.message}")
    paths = [write_plan_mcap(result, folder / f"{name}.mcap")]
    if steps > 1:
        paths.append(write_plan_mcap(walk_on(result, steps), folder / f"{name}_joined.mcap"))
    return [read_plan_mcap(path) for path in paths]


@pytest.fixture(scope="session")
def level_walk(tmp_path_factory: pytest.TempPathFactory) -> LevelWalk:
    return LevelWalk(*_recorded("walker2d", tmp_path_factory.mktemp("level_walk"),
                                JOINED_STEPS))


@pytest.fixture(scope="session")
def level_walker3d(tmp_path_factory: pytest.TempPathFactory) -> RecordedPlan:
    return _recorded("walker3d", tmp_path_factory.mktemp("level_walker3d"))[0]
