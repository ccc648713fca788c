"""Building a gait library on Ray: every grid point planned, by continuation.

A few seed points are planned cold (`seed_points`: spread over the grid, one per worker);
every other point is planned warm from the optimum of a finished neighbour (one index away
along one axis, `Grid.neighbours`) as soon as one exists, so the plans spread from the
seeds across the grid. A point whose plan fails is tried again from another finished
neighbour, then cold, and recorded as failed with its reason once all have failed
(`MAX_ATTEMPTS`). Points are Ray tasks (`gaitlib.worker.plan_point`), at most one per
worker in flight, so that each starts from the freshest neighbours; a worker that dies is
replaced by Ray and its task run again (`max_retries`). Ray runs locally by default
(`workers` processes) or on an existing cluster (`address`, as `ray start` prints it; the
cluster's nodes need this package and the library folder on a shared path).

The folder's index (`gaitlib.index`) is the record of what is finished: a build on an
existing folder plans only the points without a row, continuing from the finished ones.
"""

from __future__ import annotations

import dataclasses
import os
import socket
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from gait_planner.gaitlib.grid import Grid, parse_grid
from gait_planner.gaitlib.index import (PLANS, LibraryError, LibraryIndex, Manifest, PlanRow,
                                        write_manifest)
from gait_planner.atomic import remove_stale_temporaries

MAX_ATTEMPTS = 3  # per point: neighbours first, then cold
TASK_RETRIES = 3  # Ray's re-runs of a task whose worker died


@dataclass
class BuildSummary:
    planned: int  # points finished by this build
    failed: int  # of which failed
    skipped: int  # points finished before it (resumed)
    total: int
    wall_time: float  # s, Ray's start included
    iterations: int  # IPOPT iterations of this build's attempts
    ray_start: float = 0.0  # s, starting Ray or joining its cluster


Progress = Callable[[str], None]


def print_progress(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def seed_points(grid: Grid, count: int, candidates: list[tuple[int, ...]]) -> list[tuple[int, ...]]:
    """`count` points of `candidates` spread over the grid: the first the centre-most, each
    next the farthest (in indices, max norm) from those chosen (farthest-point sampling)."""
    if not candidates:
        return []
    centre = [(n - 1) / 2 for n in grid.shape]
    chosen = [min(candidates, key=lambda i: max(abs(a - c) for a, c in zip(i, centre)))]
    while len(chosen) < min(count, len(candidates)):
        chosen.append(max((i for i in candidates if i not in chosen),
                          key=lambda i: min(max(abs(a - b) for a, b in zip(i, c))
                                            for c in chosen)))
    return chosen


def check_address(address: str, timeout: float = 5.0) -> None:
    """LibraryError if nothing answers at a Ray cluster's HOST:PORT within `timeout` s
    (Ray itself waits minutes before it gives up); other forms ("auto", ray://) are left
    to Ray."""
    host, sep, port = address.rpartition(":")
    if not sep or not port.isdigit() or "/" in address:
        return
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as err:
        raise LibraryError(f"no Ray cluster answers at {address} ({err}); start one with "
                           f"'ray start --head' or leave out --address for a local one") from None


def _init_ray(workers: int | None, address: str | None):
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")  # a local, private instance
    import ray

    if address:
        ray.init(address=address, include_dashboard=False, log_to_driver=False)
    else:
        ray.init(num_cpus=workers or os.cpu_count(), include_dashboard=False,
                 log_to_driver=False)
    return ray


def build_library(folder: str | Path, manifest: Manifest, *, workers: int | None = None,
                  address: str | None = None, seeds: int | None = None,
                  continuation: bool = True,
                  progress: Progress = print_progress) -> BuildSummary:
    """Plan every point of manifest.grid into `folder` (module docstring) that is not
    finished yet. workers: local Ray worker processes (None: one per core); address: an
    existing Ray cluster instead; seeds: cold points to start from (None: one per worker);
    continuation False: every point cold and on its own (independent plans, e.g. to
    compare). LibraryError if the folder holds another library; GridError for a bad grid."""
    folder = Path(folder)
    grid = parse_grid(manifest.grid)
    if address:
        check_address(address)
    manifest = dataclasses.replace(manifest, grid=grid.text())  # one spelling per grid
    folder.mkdir(parents=True, exist_ok=True)
    write_manifest(folder, manifest)
    remove_stale_temporaries(folder / PLANS)
    index = LibraryIndex(folder)
    finished = {row.name: row for row in index.rows()}
    names = {grid.name(i): i for i in grid.indices()}
    converged = {name for name, row in finished.items() if row.status == "ok"}
    todo = [i for i in grid.indices() if grid.name(i) not in finished]
    start, skipped = time.perf_counter(), len(finished)
    summary = BuildSummary(0, 0, skipped, len(names), 0.0, 0)
    if not todo:
        progress(f"library: all {len(names)} points already finished")
        return summary
    ray = _init_ray(workers, address)
    summary.ray_start = time.perf_counter() - start
    try:
        task = ray.remote(num_cpus=1, max_retries=TASK_RETRIES)(_plan_point)
        capacity = max(1, int(ray.cluster_resources().get("CPU", 1)))
        tried: dict[str, list[str | None]] = {grid.name(i): [] for i in todo}
        last: dict[str, PlanRow] = {}  # a point's latest failed attempt
        running: dict = {}  # ObjectRef -> (index, start)
        waiting = list(todo)  # neither finished nor running

        def neighbour_start(i) -> str | None:
            """A finished neighbour point i has not been continued from yet (None without
            continuation)."""
            if not continuation:
                return None
            return next((grid.name(j) for j in grid.neighbours(i)
                         if grid.name(j) in converged and grid.name(j) not in tried[grid.name(i)]),
                        None)

        def submit(i, start_from: str | None) -> None:
            name = grid.name(i)
            if i in waiting:
                waiting.remove(i)
            tried[name].append(start_from)
            ref = task.remote(str(folder), manifest, name, grid.values(i), start_from,
                              len(tried[name]))
            running[ref] = (i, start_from)

        def record_failure(i) -> None:
            if i in waiting:
                waiting.remove(i)
            index.add(last[grid.name(i)])
            summary.planned += 1
            summary.failed += 1

        def fill() -> None:
            """Start waiting points from finished neighbours (without continuation: cold,
            once) while workers are free; when nothing runs, seed the waiting points that
            have not been tried cold, and record the rest as failed."""
            for i in list(waiting):
                if len(running) >= capacity:
                    return
                start_from = neighbour_start(i) if continuation else None
                if start_from is not None or not (continuation or tried[grid.name(i)]):
                    submit(i, start_from)
            if running or not waiting:
                return
            fresh = [i for i in waiting if None not in tried[grid.name(i)]]
            for i in seed_points(grid, seeds or capacity, fresh):
                submit(i, None)
            if not running:
                for i in list(waiting):
                    record_failure(i)

        fill()
        while running:
            (ref,), _ = ray.wait(list(running), num_returns=1)
            i, start_from = running.pop(ref)
            name = grid.name(i)
            try:
                row = ray.get(ref)
            except ray.exceptions.RayError as err:
                row = PlanRow(name=name, request=grid.values(i), status="failed",
                              reason=f"the worker failed: {str(err).splitlines()[0]}",
                              cost=None, duration=None, sigma=[], iterations=0, solve_time=0.0,
                              certificate="", checks="", start=start_from or "cold",
                              attempts=len(tried[name]), mcap="")
            summary.iterations += row.iterations
            if row.status == "ok":
                converged.add(name)
                summary.planned += 1
            else:
                last[name] = row
                if len(tried[name]) >= MAX_ATTEMPTS:
                    record_failure(i)
                elif neighbour_start(i) is None and None not in tried[name]:
                    submit(i, None)  # no other neighbour to continue from: cold
                else:
                    waiting.insert(0, i)
            fill()
            _report(progress, summary, len(running), start)
    finally:
        ray.shutdown()
        index.close()
    summary.wall_time = time.perf_counter() - start
    return summary


def _report(progress: Progress, s: BuildSummary, running: int, start: float) -> None:
    done = s.planned + s.skipped
    elapsed = time.perf_counter() - start
    left = s.total - done
    eta = f", about {elapsed / s.planned * left / 60:.1f} min left" if s.planned and left else ""
    progress(f"library: {done}/{s.total} points done ({s.failed} failed, {running} running)"
             f"{eta}")


def _plan_point(*args):
    """The Ray task (imported in the worker, not pickled with the driver's state)."""
    from gait_planner.gaitlib.worker import plan_point

    return plan_point(*args)

