"""Answering a request from a gait library: the start interpolated from its neighbours.

A request of the library's scene, gait and fixed settings whose grid fields lie inside the
grid's hull starts from the multilinear interpolation of the optima of the grid cell's
corners (`interpolated_start`: primal x, multipliers and reference configurations, each
weighted like the request's position in the cell; an axis the request sits on exactly
takes one value). That start is the seed of a warm plan (`strategies.plan_once`), solved
to the full tolerance and checked as any plan. Outside the hull, or where a corner failed,
the request is planned as any other, and `library_start` says why.
"""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np

from gait_planner.gaitlib.grid import AXES, Grid, parse_grid
from gait_planner.gaitlib.index import (LibraryIndex, Manifest, load_start, read_manifest,
                                        start_path)
from gait_planner.gaitlib.worker import point_request
from gait_planner.model.loader import find_scene
from gait_planner.ocp.warm_starts import StoredPlan
from gait_planner.ocp.settings import GaitSettings, SolveOptions
from gait_planner.ocp.solve import Planner
from gait_planner.problem import Problem, SceneLookup, resolve

_FREE = ("max_solve_time", "compiled")  # solve options a library's plans need not share


def cell(grid: Grid, values: dict[str, float]) -> list[tuple[tuple[int, ...], float]] | str:
    """The corners (indices) of the grid cell holding `values` and their multilinear
    weights (summing to 1, zero-weight corners left out), or a sentence saying which field
    lies outside the grid."""
    per_axis = []
    for field, axis in grid.axes:
        v = values[field]
        if not axis[0] - 1e-12 <= v <= axis[-1] + 1e-12:
            return (f"{field} {v:g} is outside the library's range "
                    f"[{axis[0]:g}, {axis[-1]:g}]")
        i = min(int(np.searchsorted(axis, v, side="right")) - 1, len(axis) - 1)
        i = max(i, 0)
        if i == len(axis) - 1 or abs(v - axis[i]) <= 1e-12:
            per_axis.append([(i, 1.0)])
        else:
            t = (v - axis[i]) / (axis[i + 1] - axis[i])
            per_axis.append([(i, 1.0 - t), (i + 1, t)])
    return [(tuple(i for i, _ in combo), float(np.prod([w for _, w in combo])))
            for combo in itertools.product(*per_axis)]


def interpolated_start(folder: Path, corners: list[tuple[str, float]], step: float,
                       mu: float) -> StoredPlan:
    """The weighted sum of the corners' optima [(point name, weight)]."""
    plans = [(load_start(start_path(folder, name)), w) for name, w in corners]
    mix = {name: sum(w * getattr(p, name) for p, w in plans)
           for name in ("x", "lam_x", "lam_g", "qref")}
    names = ", ".join(f"{name} x {w:.2f}" for name, w in corners)
    return StoredPlan(step, mu, source=f"the gait library {folder.name}: {names}", **mix)


def library_start(planner: Planner, folder: str | Path, problem: Problem,
                  scenes: SceneLookup = find_scene) -> tuple[StoredPlan | None, str]:
    """(the start interpolated from its neighbours (module docstring), a sentence saying
    where it came from) if `problem` lies inside the library in `folder`, else (None, why
    the library does not serve the request). The start is a seed for `planner`'s plan of
    `problem` (`pipeline.plan_and_record(..., seed=)`); ValueError if its sizes are not
    that problem's (`Planner.fits`), LibraryError if `folder` is not a library. scenes:
    finds the library's scene (as `problem.resolve`'s)."""
    folder = Path(folder)
    manifest: Manifest = read_manifest(folder)
    grid = parse_grid(manifest.grid)
    scene, settings = problem.scene, problem.settings
    first = grid.indices()[0]
    point = resolve(point_request(manifest, grid.name(first), grid.values(first), cold=False),
                    scenes)
    own_scene, own = point.scene, point.settings
    values = {field: float(getattr(settings, field)) for field in AXES}
    same = dataclasses.replace(own, **{f: values[f] for f in grid.fields},
                               solve=dataclasses.replace(
                                   own.solve, **{f: getattr(settings.solve, f) for f in _FREE}))
    if (scene.name, scene.source) != (own_scene.name, own_scene.source) or same != settings:
        differ = [f.name for f in dataclasses.fields(GaitSettings) if f.name != "solve"
                  and getattr(same, f.name) != getattr(settings, f.name)]
        differ += [f.name for f in dataclasses.fields(SolveOptions)
                   if getattr(same.solve, f.name) != getattr(settings.solve, f.name)]
        return None, (f"not from the gait library {folder.name}: the request differs from it "
                      "in " + (", ".join(differ) if differ else "its scene"))
    corners = cell(grid, values)
    if isinstance(corners, str):
        return None, f"not from the gait library {folder.name}: {corners}"
    index = LibraryIndex(folder)
    try:
        rows = {row.name: row for row in index.rows()}
    finally:
        index.close()
    named = [(grid.name(i), w) for i, w in corners]
    missing = [name for name, _ in named if rows.get(name) is None or rows[name].status != "ok"]
    if missing:
        return None, (f"not from the gait library {folder.name}: its points "
                      f"{', '.join(missing)} around the request have no plan")
    start = interpolated_start(folder, named, settings.step_length,
                               settings.friction_coefficient)
    planner.fits(scene, settings, start)
    return start, f"started from {start.source}"

