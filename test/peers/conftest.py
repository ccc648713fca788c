"""Shared by the peers' tests: DMOCC's walker2d plan at 4 intervals per phase and its
problem.json (benchmarks/peers/problem.py), planned once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks.peers import exchange
from benchmarks.peers.problem import problem_of
from gait_planner.io.urdf import scene_to_urdf
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once


@pytest.fixture(scope="session")
def walker2d_dmocc(tmp_path_factory):
    """(DMOCC's plan, its problem.json dict, the problem.json path)."""
    folder = tmp_path_factory.mktemp("peers")
    scene = load_scene("walker2d")
    settings = settings_for(scene, intervals_per_phase=4)
    result = plan_once(Planner(), scene, settings)
    assert result.success, result.message
    urdf = folder / "walker2d.urdf"
    urdf.write_text(scene_to_urdf(scene))
    path = exchange.write_problem(folder / "problem.json", problem_of(result, settings, urdf))
    return result, exchange.read_problem(path), Path(path)
