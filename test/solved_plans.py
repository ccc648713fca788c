"""Plans shared by the optimal-control and verifier tests (test/ocp, test/verify): solved
once per session, recorded, verified.

`solved(name)` plans scene `name` with its default settings on one `Planner` per scene
(kept, so warm-start and failure tests reuse the built problem), records the result with
the real MCAP writer into the session's temporary folder and verifies the recording with
`gait_planner.verify`. Costs on this 2-core machine (benchmarks/plan.py, 2026-11-23):
compass under 1 s, walker2d ~10 s (build 6 s), walker3d ~21 s (build 13 s): tests needing
walker3d are marked slow. A folder's conftest imports the fixture.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pytest

from gait_planner.io.mcap_writer import write_plan_mcap
from gait_planner.model.loader import load_scene
from gait_planner.model.scene import Scene
from gait_planner.ocp.settings import GaitSettings, settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.result import PlanResult
from gait_planner.verify import VerificationReport, verify_recording


@dataclass(frozen=True)
class Solved:
    """One scene planned with default settings, its recording and the recording's check."""

    name: str
    scene: Scene
    settings: GaitSettings
    planner: Planner  # holds the built problem and the stored plan (warm starts)
    result: PlanResult
    seconds: float  # wall time of plan(), build included
    path: Path  # the MCAP recording
    report: VerificationReport


_CACHE: dict[str, Solved] = {}


@pytest.fixture(scope="session")
def solved(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str], Solved]:
    """Factory: solved("walker2d") -> `Solved`, planned once per session (one cache for
    every folder whose conftest imports this fixture)."""
    folder = tmp_path_factory.mktemp("plans")

    def get(name: str) -> Solved:
        if name not in _CACHE:
            scene = load_scene(name)
            settings = settings_for(scene)
            planner = Planner()
            start = time.perf_counter()
            result = plan_once(planner, scene, settings)
            seconds = time.perf_counter() - start
            if result.times.size == 0:
                pytest.fail(f"{name}: no plan: {result.message}")
            # an unsuccessful solve with a trajectory is still recorded and verified: the
            # verifier reports the planner's failure among its measurements
            path = write_plan_mcap(result, folder / f"{name}.mcap")
            _CACHE[name] = Solved(name, scene, settings, planner, result, seconds, path,
                                  verify_recording(path))
        return _CACHE[name]

    return get
