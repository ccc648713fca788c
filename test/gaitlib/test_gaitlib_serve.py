"""Answering a request from a gait library: the grid cell's weights, the interpolated
start, and a request outside the library planned as usual (and said so). The library is
planned in this process (`plan_point`, as a Ray worker runs it)."""

from __future__ import annotations

import shutil
import sqlite3

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gait_planner.gaitlib.grid import parse_grid
from gait_planner.gaitlib.index import Manifest, write_manifest
from gait_planner.gaitlib.serve import cell, library_start
from gait_planner.gaitlib.worker import plan_point
from gait_planner.model.loader import find_scene
from gait_planner.ocp import solve
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.request import plan_request
from gait_planner.verify import verify_result
from gait_planner.problem import resolve

GRID = "step_length=0.55/0.65,friction_coefficient=0.6/1.0"


@settings(max_examples=60, deadline=None)
@given(step=st.floats(0.4, 0.9), mu=st.floats(0.6, 1.0))
def test_the_cell_weights_are_multilinear_and_reproduce_the_request(step, mu):
    grid = parse_grid("step_length=0.4:0.9:0.1,friction_coefficient=0.6/0.8/1.0")
    corners = cell(grid, {"step_length": step, "friction_coefficient": mu})
    assert sum(w for _, w in corners) == pytest.approx(1.0, abs=1e-12)
    assert all(w >= 0 for _, w in corners) and 1 <= len(corners) <= 4
    for k, field in enumerate(grid.fields):
        at = sum(w * grid.axes[k][1][i[k]] for i, w in corners)
        assert at == pytest.approx({"step_length": step, "friction_coefficient": mu}[field],
                                   abs=1e-9)


def test_a_value_outside_the_grid_is_named():
    grid = parse_grid(GRID)
    assert "step_length 0.8 is outside the library's range [0.55, 0.65]" in cell(
        grid, {"step_length": 0.8, "friction_coefficient": 0.8})


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    folder = tmp_path_factory.mktemp("library")
    manifest = Manifest(scene="walker2d", gait="", grid=parse_grid(GRID).text(), request={})
    write_manifest(folder, manifest)
    grid = parse_grid(manifest.grid)
    previous = None
    for i in grid.indices():
        row = plan_point(str(folder), manifest, grid.name(i), grid.values(i), previous)
        assert row.status == "ok", row.reason
        previous = grid.name(i)
    return folder


def test_a_request_inside_the_library_starts_from_its_neighbours(library):
    """The start is the weighted mix of the four corners' optima; the plan from it
    converges in fewer iterations than a cold plan and passes every check."""
    planner = Planner()
    request = plan_request(scene="walker2d", step_length=0.6, friction_coefficient=0.7,
                           compiled=True)
    problem = resolve(request, find_scene)
    start, note = library_start(planner, library, problem)
    assert note.startswith(f"started from the gait library {library.name}: p00-00 x 0.38")
    scene, s = problem.scene, problem.settings
    assert (start.step, start.mu) == (0.6, 0.7)
    assert not planner.stored_plans(scene, s)  # a seed, not a stored plan
    result = plan_once(planner, scene, s, seed=start)
    assert result.success, result.message
    assert "the gait library" in result.settings["initial_guess"]
    cold = plan_once(Planner(), scene, s, warm_start=False)
    assert result.stats.iterations < cold.stats.iterations
    assert result.cost_value == pytest.approx(cold.cost_value, rel=1e-4)
    report = verify_result(result)
    assert report.ok, report.failures


def test_a_seed_is_solved_with_the_barrier_fixed_else_adaptive_else_cold(library, monkeypatch):
    """A seed is near its optimum: the plan fixes IPOPT's barrier (`SEEDED_ATTEMPTS`); if
    that attempt fails (here: one iteration allowed), the same start is solved with the
    adaptive barrier, and if that fails too, the request is planned cold: each reaches the
    same optimum, and the plan says which way."""
    problem = resolve(plan_request(scene="walker2d", step_length=0.6, friction_coefficient=0.7,
                                   compiled=True), find_scene)
    scene, s = problem.scene, problem.settings
    stages = []
    planner = Planner(stage=stages.append)
    fixed = plan_once(planner, scene, s, seed=library_start(planner, library, problem)[0])
    assert fixed.success and stages[-1] == "warm"
    assert "restarted" not in fixed.settings["initial_guess"]
    monkeypatch.setitem(solve.VARIANTS, "seeded", {**solve.VARIANTS["seeded"],
                                                   "ipopt.max_iter": 1})
    planner = Planner()
    adaptive = plan_once(planner, scene, s, seed=library_start(planner, library, problem)[0])
    assert adaptive.success, adaptive.message
    assert "the fixed-barrier attempt stopped (iteration limit reached) after 1 iterations, " \
        "restarted with IPOPT's adaptive barrier" in adaptive.settings["initial_guess"]
    assert adaptive.stats.iterations > 1
    assert adaptive.cost_value == pytest.approx(fixed.cost_value, rel=1e-7)
    monkeypatch.setitem(solve.VARIANTS, "warm", {**solve.VARIANTS["warm"], "ipopt.max_iter": 1})
    planner = Planner()
    cold = plan_once(planner, scene, s, seed=library_start(planner, library, problem)[0])
    assert cold.success, cold.message
    assert cold.settings["initial_guess"].endswith(
        "restarted with IPOPT's adaptive barrier; then cold from the kinematic guess, sigma "
        "fixed at its upper bound and limits relaxed, then free")
    assert cold.cost_value == pytest.approx(fixed.cost_value, rel=1e-6)


@pytest.mark.parametrize("fields, words", [
    ({"step_length": 0.8}, "step_length 0.8 is outside the library's range [0.55, 0.65]"),
    ({"step_length": 0.6, "slope": 5.0}, "the request differs from it in slope"),
    ({"step_length": 0.6, "intervals_per_phase": 6}, "differs from it in base_time_step"),
    ({"step_length": 0.6, "gait": "run"}, "differs from it in"),
])
def test_a_request_the_library_cannot_serve_is_planned_as_usual(library, fields, words):
    planner = Planner()
    request = plan_request(scene="walker2d", compiled=True, **fields)
    seed, note = library_start(planner, library, resolve(request, find_scene))
    assert seed is None
    assert note.startswith(f"not from the gait library {library.name}") and words in note
    problem = resolve(request, find_scene)
    assert not planner.stored_plans(problem.scene, problem.settings)


def test_a_corner_without_a_plan_is_named(library, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(library, copy)
    with sqlite3.connect(copy / "index.sqlite") as db:
        db.execute("DELETE FROM plans WHERE name = 'p01-01'")
    request = plan_request(scene="walker2d", step_length=0.6, friction_coefficient=0.7)
    assert "its points p01-01 around the request have no plan" in library_start(
        Planner(), copy, resolve(request, find_scene))[1]


def test_a_library_that_changes_is_read_again(library, tmp_path):
    """A serving process keeps what it read (`serve._open`, `serve._start`) only while the
    files are unchanged: a point dropped from the index, or a corner's optimum replaced,
    is seen by the next request."""
    copy = tmp_path / "copy"
    shutil.copytree(library, copy)
    planner = Planner()
    problem = resolve(plan_request(scene="walker2d", step_length=0.6, friction_coefficient=1.0),
                      find_scene)
    first, _ = library_start(planner, copy, problem)
    assert first is not None
    plans = copy / "plans"
    shutil.copy(plans / "p01-01.start.npz", tmp_path / "other.npz")
    (tmp_path / "other.npz").replace(plans / "p00-01.start.npz")  # a corner replaced
    second, _ = library_start(planner, copy, problem)
    assert second is not None and not np.array_equal(second.x, first.x)
    with sqlite3.connect(copy / "index.sqlite") as db:
        db.execute("DELETE FROM plans WHERE name = 'p01-01'")
    assert "its points p01-01 around the request have no plan" in library_start(
        planner, copy, problem)[1]





def test_the_node_parameter_names_a_folder_that_is_not_a_library(library, tmp_path):
    from gait_planner.ros.parameters import check_gait_library

    assert check_gait_library("") is None and check_gait_library(str(library)) is None
    assert "is not a gait library (no library.json)" in check_gait_library(str(tmp_path))
