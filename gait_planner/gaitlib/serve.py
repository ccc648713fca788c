"""Answering a request from a gait library: the start interpolated from its neighbours.

A request of the library's scene, gait and fixed settings whose grid fields lie inside the
grid's hull starts from the multilinear interpolation of the optima of the grid cell's
corners (`interpolated_start`: primal x, multipliers and reference configurations, each
weighted like the request's position in the cell; an axis the request sits on exactly
takes one value). That start is the seed of a warm plan (`strategies.plan_once`), solved
to the full tolerance and checked as any plan. Outside the hull, or where a corner failed,
the request is planned as any other, and `library_start` says why.

A process that serves (the node) keeps what it read of a library: the manifest, its grid,
the problem of its points and the index's rows while the three files (library.json,
index.sqlite and its write-ahead log) keep their size and modification time, and the
last `STARTS_KEPT` corner optima by file and modification time. A request then reads no
file (4-7 ms of a walker3d answer were reading them, 2026-11-29).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gait_planner.gaitlib.grid import AXES, Grid, parse_grid
from gait_planner.gaitlib.index import (INDEX, MANIFEST, LibraryIndex, Manifest, PlanRow,
                                        load_start, read_manifest, start_path)
from gait_planner.gaitlib.worker import point_request
from gait_planner.model.loader import find_scene
from gait_planner.ocp.warm_starts import StoredPlan
from gait_planner.ocp.settings import GaitSettings, SolveOptions
from gait_planner.ocp.solve import Planner
from gait_planner.problem import Problem, SceneLookup, resolve

_FREE = ("max_solve_time", "compiled")  # solve options a library's plans need not share
STARTS_KEPT = 64  # corner optima kept in memory (walker3d: about 0.2 MB each)


@dataclass(frozen=True)
class _Opened:
    """What `library_start` reads of a library before its corners."""

    grid: Grid
    point: Problem  # the problem of the library's first point: its scene and settings
    rows: dict[str, PlanRow]


_OPENED: dict[tuple[str, SceneLookup], tuple[tuple, _Opened]] = {}


def _stamp(folder: Path) -> tuple:
    """(size, modification time) of the library's files; None for a missing one."""
    out = []
    for name in (MANIFEST, INDEX, INDEX + "-wal"):
        try:
            st = os.stat(folder / name)
            out.append((st.st_size, st.st_mtime_ns))
        except FileNotFoundError:
            out.append(None)
    return tuple(out)


def _open(folder: Path, scenes: SceneLookup) -> _Opened:
    """The library in `folder` as `_Opened`, read again only if its files changed."""
    key, stamp = (str(folder.resolve()), scenes), _stamp(folder)
    kept = _OPENED.get(key)
    if kept is not None and kept[0] == stamp:
        return kept[1]
    manifest: Manifest = read_manifest(folder)
    grid = parse_grid(manifest.grid)
    first = grid.indices()[0]
    point = resolve(point_request(manifest, grid.name(first), grid.values(first), cold=False),
                    scenes)
    index = LibraryIndex(folder)
    try:
        rows = {row.name: row for row in index.rows()}
    finally:
        index.close()
    opened = _OPENED[key] = (stamp, _Opened(grid, point, rows))
    return opened[1]


@functools.lru_cache(maxsize=STARTS_KEPT)
def _start(path: str, mtime_ns: int) -> StoredPlan:
    return load_start(Path(path))


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
    paths = [start_path(folder, name) for name, _ in corners]
    plans = [(_start(str(path), path.stat().st_mtime_ns), w)
             for path, (_, w) in zip(paths, corners)]
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
    opened = _open(folder, scenes)
    grid, scene, settings = opened.grid, problem.scene, problem.settings
    own_scene, own = opened.point.scene, opened.point.settings
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
    rows = opened.rows
    named = [(grid.name(i), w) for i, w in corners]
    missing = [name for name, _ in named if rows.get(name) is None or rows[name].status != "ok"]
    if missing:
        return None, (f"not from the gait library {folder.name}: its points "
                      f"{', '.join(missing)} around the request have no plan")
    start = interpolated_start(folder, named, settings.step_length,
                               settings.friction_coefficient)
    planner.fits(scene, settings, start)
    return start, f"started from {start.source}"

