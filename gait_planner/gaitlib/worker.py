"""One grid point of a gait library, planned where a Ray worker runs it.

`plan_point` plans the point's request (`gait_planner.pipeline.plan_and_record`: the
certificate, refinements and the recording as for any plan) cold, or warm from the optimum
of a finished neighbour (its seed), verifies the recording
(`gait_planner.verify`), and on success writes the point's files and then its index row
(`gaitlib.index`). A failed attempt writes nothing: the driver decides whether to try
again from elsewhere and records the failure itself. Each worker process keeps one
`Planner`, so problems it has built serve its later points.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from gait_planner.gaitlib.index import (PLANS, LibraryIndex, Manifest, PlanRow, load_start,
                                        save_start, start_path)
from gait_planner.model.loader import find_scene
from gait_planner.ocp.solve import Planner
from gait_planner.pipeline import plan_and_record
from gait_planner.problem import resolve
from gait_planner.request import plan_request

_PLANNER: Planner | None = None  # this worker process's planner


def planner() -> Planner:
    global _PLANNER
    if _PLANNER is None:
        _PLANNER = Planner()
    return _PLANNER


def point_request(manifest: Manifest, name: str, values: dict, *, cold: bool):
    """The plan request of a grid point: the manifest's scene, gait and fixed fields, the
    point's values, compiled derivatives, the point's name as the output name."""
    return plan_request(scene=manifest.scene, gait=manifest.gait, output_name=name,
                        cold_start=cold, compiled=True, **{**manifest.request, **values})


def plan_point(folder: str, manifest: Manifest, name: str, values: dict,
               start_from: str | None, attempt: int = 1) -> PlanRow:
    """Plan grid point `name` (request fields `values`) of the library in `folder`, cold
    (start_from None) or from the optimum of the finished point `start_from`; attempt:
    how many times the point has been tried, this one included. Returns its row (status
    "ok": written to the index with the point's files; "failed": nothing written)."""
    began = time.perf_counter()
    folder_path = Path(folder)
    problem = resolve(point_request(manifest, name, values, cold=start_from is None), find_scene)
    scene, settings = problem.scene, problem.settings
    work = planner()
    seed = None
    if start_from is not None:
        seed = load_start(start_path(folder_path, start_from))
        work.fits(scene, settings, seed)
    outcome = plan_and_record(work, problem, folder_path / PLANS, rrd=False, seed=seed)
    result = outcome.result
    row = dict(name=name, request=values, iterations=int(result.stats.iterations),
               solve_time=time.perf_counter() - began, start=start_from or "cold", attempts=attempt)
    if not result.success:
        return PlanRow(status="failed", reason=result.message, cost=None, duration=None,
                       sigma=[], certificate="", checks="", mcap="", **row)
    from gait_planner.verify import verify_recording

    report = verify_recording(outcome.mcap_path)
    save_start(start_path(folder_path, name), work.stored_plans(scene, settings)[-1])
    out = PlanRow(status="ok", reason="", cost=float(result.cost_value),
                  duration=float(result.duration),
                  sigma=[float(v) for v in result.phase_scaling],
                  certificate=result.settings.get("continuous_dynamics", ""),
                  checks="pass" if report.ok else json.dumps(list(report.failures)),
                  mcap=outcome.mcap_path.name, **row)
    index = LibraryIndex(folder_path)
    try:
        index.add(out)
    finally:
        index.close()
    return out
