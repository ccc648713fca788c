"""Walks by re-planning against walks of one plan (issue #63): from standing, N half cycles,
stop, stand 2 s, in MuJoCo (`gait_planner.walk.replan.walk_replanned`).

Usage: .venv/bin/python benchmarks/replan_walk.py [--scenes walker2d walker3d]
       [--half-cycles 10] [--deadline 0.75] [--moving] [--model-error SEEDS]
       [--cases NAME ...] [--json NAME]

For each scene two rows, each in a fresh Planner with the warm-start store (derivatives
compiled; the gait from the store, as `gait-planner walk --replan` and the API meet it):
"re-planned" (a transition from the walker's
measured state at every strike, its wall time on this machine charged to the simulated
clock) and "one plan" (the start plan carries every half cycle; only the stop is planned
during the walk). Each row: half cycles walked, why it ended, whether it stood still at the
end, the re-plans (converged of asked, median iterations and wall time), the feedback share,
unplanned touches, the largest slide. `--model-error SEEDS`: each row walked SEEDS times
with every model error at once (masses and inertias x U[0.9, 1.1], friction 0.5, a contact
time constant of 2-10 ms, a 50 ms torque delay: `model_error.py`'s last row, its seeds), the
plans made for the nominal model. `--cases`: walker3d's hard requests of `hard_cases.py` by
name (e.g. "mu 0.2"; each a request of its scene, in its gait), instead of the defaults;
their gait and the start are planned with a time limit of `CASE_TIME_LIMIT` s each.
Wall times depend on the machine and its load (the
load is printed): they decide when a plan takes over, so two runs differ. Threads: one
(OPENBLAS_NUM_THREADS=1, the package's default).
"""

from __future__ import annotations

import argparse
import os
import platform
import time

from gait_planner.model.loader import load_scene, with_gait
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.ocp.warm_starts import WarmStartStore
from gait_planner.walk.replan import DEADLINE, walk_replanned
from hard_cases import Case, cases, settings_of
from model_error import perturbations

CASE_TIME_LIMIT = 300.0  # s, a hard case's gait, and the start (walk.py's plans: 120)


def row(name: str, replan: bool, half_cycles: int, standing: bool, deadline: float,
        error=None, case: Case | None = None) -> dict:
    scene = load_scene(name)
    if case is None:
        settings = settings_for(scene, compiled=True)
    else:
        scene = with_gait(scene, case.gait)
        settings = settings_of(scene, case, CASE_TIME_LIMIT)
    began = time.perf_counter()
    r = walk_replanned(Planner(library=WarmStartStore()), scene, settings, half_cycles,
                       replan=replan, standing=standing, deadline=deadline,
                       model_error=error)
    slides = r.get("foot_slide") or {}
    return {"scene": name, "case": case.name if case else "default",
            "mode": "re-planned" if replan else "one plan",
            "deadline": deadline,
            "model_error": r.get("model_error", {}).get("differences", "none"),
            "start": "standing" if standing else "moving",
            "half_cycles_walked": r["half_cycles_walked"], "stopped": r["stopped"],
            "stood": r.get("stood", False), "replans": r.get("replans", 0),
            "replans_converged": r.get("replans_converged", 0),
            "replan_iterations_median": r.get("replan_iterations_median"),
            "replan_wall_median_s": r.get("replan_wall_median_s"),
            "feedback_share": r.get("feedback_share"),
            "feedback_share_by_part": r.get("feedback_share_by_part"),
            "touches": len(r.get("unplanned_touches", [])),
            "largest_slide_mm": slides.get("slide_mm"),
            "plans": r["plans"], "run_s": round(time.perf_counter() - began, 1)}


def _number(x) -> str:
    return "-" if x is None else f"{x:.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["walker2d", "walker3d"])
    parser.add_argument("--half-cycles", type=int, default=10)
    parser.add_argument("--deadline", type=float, default=DEADLINE,
                        help=f"a re-plan's time limit in half cycles (default {DEADLINE})")
    parser.add_argument("--moving", action="store_true",
                        help="begin moving at the gait's first node, not from standing")
    parser.add_argument("--model-error", type=int, metavar="SEEDS", default=0,
                        help="walk each row SEEDS times with every model error at once")
    parser.add_argument("--cases", nargs="+", default=[], metavar="NAME",
                        help="walker3d's hard requests of hard_cases.py by name")
    parser.add_argument("--json", metavar="NAME",
                        help="also write the rows to benchmarks/results/NAME.json")
    args = parser.parse_args()
    print(f"# {platform.node()} {platform.processor() or platform.machine()} "
          f"{time.strftime('%Y-%m-%d %H:%M')}, load {os.getloadavg()[0]:.2f}, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")
    named = {c.name: c for c in cases(load_scene("walker3d"))}
    unknown = [n for n in args.cases if n not in named]
    if unknown:
        parser.error(f"no hard case {', '.join(map(repr, unknown))}; the cases: "
                     f"{', '.join(map(repr, named))}")
    runs = ([("walker3d", named[n]) for n in args.cases] if args.cases
            else [(name, None) for name in args.scenes])
    print("| scene | case | mode | half cycles | ended | stood | re-plans converged | median it "
          "| median wall s | feedback | touches | model error |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    errors = perturbations(args.model_error)[-1][1] if args.model_error else [None]
    rows = []
    for name, case in runs:
        for replan, error in ((r, e) for r in (True, False) for e in errors):
            x = row(name, replan, args.half_cycles, not args.moving, args.deadline, error,
                    case)
            rows.append(x)
            print(f"| {name} | {x['case']} | {x['mode']} | {x['half_cycles_walked']} | "
                  f"{x['stopped'][:60]} | {x['stood']} | "
                  f"{x['replans_converged']}/{x['replans']} | "
                  f"{x['replan_iterations_median']} | {x['replan_wall_median_s']} | "
                  f"{_number(x['feedback_share'])} | {x['touches']} | {x['model_error']} |",
                  flush=True)
            if not x["plans"][0]["success"]:
                print(f"  the start: {x['plans'][0]['message']}")
    if args.json:
        from results_io import write_results

        print(write_results(args.json, rows, {"half_cycles": args.half_cycles,
                                              "model_error_seeds": args.model_error,
                                              "deadline": args.deadline,
                                              "start": "moving" if args.moving else "standing"}))


if __name__ == "__main__":
    main()
