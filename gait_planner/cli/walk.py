"""``gait-planner walk RUN.mcap [--steps K] [--self-test] [--json] [--out WALK.mcap]
[--rrd WALK.rrd]``, ``gait-planner walk --replan SCENE [--steps K] [--deadline H]
[--json]``: walk a
recorded plan in MuJoCo with the reference controller
(`gait_planner.walk.walk_plan`): a line on stderr at each half cycle's end, the summary
(`gait_planner.walk.summary`) on stdout; --out records the walk
(`gait_planner.walk.recording`), --rrd draws it over the plan in rerun
(`gait_planner.viz.rerun_walk`). --self-test walks it again with the plan's torques scaled
by config/walk.yaml's self_test_scales (0 and 0.5) and says whether each did measurably worse
(fewer half cycles or a larger feedback share). --replan walks the scene from standing,
re-planned at every strike (`gait_planner.walk.replan`); exit status 1 if it did not
complete and stand.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from gait_planner.cli.arguments import integer_from
from gait_planner.cli.errors import CliError
from gait_planner.walk.summary import format_summary, half_cycles_done


def _deadline(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0.0 < value <= 10.0:  # nan fails too
        raise argparse.ArgumentTypeError(f"must be in (0, 10] half cycles, got {text}")
    return value


def self_test(path: str, steps: int, full: dict[str, Any],
              config: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    """The walks with the plan's torques scaled down (config's self_test_scales; None:
    config/walk.yaml); `worse` = fewer half cycles or more feedback than the full-torque
    walk `full`."""
    from gait_planner.walk.walk_plan import load_config, walk

    config = config or load_config()
    rows = []
    for scale in config["self_test_scales"]:
        r = walk(path, steps, scale=float(scale), config=config)
        worse = (r["half_cycles_walked"] < full["half_cycles_walked"]
                 or r["feedback_share"] > full["feedback_share"])
        rows.append({"torque_scale": scale, "half_cycles_walked": r["half_cycles_walked"],
                     "feedback_share": r["feedback_share"], "stopped": r["stopped"],
                     "worse": worse})
    return rows


def add_walk_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "walk", help="walk a recorded plan in MuJoCo with a reference controller",
        description="Load the recording's /robot_description into MuJoCo (floating base, "
        "feet with the plan's contact points), start from node 0 and walk K half cycles "
        "joined by the mirror with the plan's torques, joint PD and torso feedback "
        "(config/walk.yaml).")
    parser.add_argument("recording", metavar="RUN.mcap", nargs="?",
                        help="a plan's MCAP recording (not with --replan)")
    parser.add_argument("--replan", metavar="SCENE", default=None,
                        help="walk the scene's default request from standing instead, "
                        "re-planned at every strike from the walker's measured state (each "
                        "solve's wall time charged to the simulation), then stop and stand "
                        "2 s (gait_planner.walk.replan)")
    parser.add_argument("--steps", type=integer_from(1), default=10, metavar="K",
                        help="half cycles to walk (default 10)")
    parser.add_argument("--deadline", type=_deadline, default=None, metavar="H",
                        help="with --replan: a re-plan's time limit in half cycles of the "
                        "gait (default 0.75; a later plan is dropped; above 1 the plans "
                        "carry more of the gait and the stop is planned earlier)")
    parser.add_argument("--self-test", action="store_true",
                        help="also walk with the plan's torques x0 and x0.5 and check they do worse")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("--out", metavar="WALK.mcap", default=None,
                        help="record the walk: simulated joint states, feed-forward and "
                        "feedback torques, ground forces (200 Hz)")
    parser.add_argument("--config", metavar="WALK.yaml", default=None,
                        help="the controller's parameters (default: config/walk.yaml, whose "
                        "keys and units a file of your own must have)")
    parser.add_argument("--rrd", metavar="WALK.rrd", default=None,
                        help="draw the walk in rerun: the simulated walker over the planned "
                        "one, the ground forces of both, joint angles, torques and the errors "
                        "per half cycle (200 Hz)")
    parser.set_defaults(handler=_walk_command)
    return parser


def print_progress(walked: int, steps: int) -> None:
    """`walk`'s progress: a line on stderr at each half cycle's end (as `plan` prints its
    phases and iterations)."""
    print(f"-- walking ({half_cycles_done(walked, steps)})", file=sys.stderr, flush=True)


def _write(key: str, path: str, result: dict[str, Any]) -> None:
    """result[key] = the absolute path the walk was written to (`key` "out": MCAP, "rrd")."""
    if key == "out":
        from gait_planner.walk.recording import write_walk_mcap as writer
    else:
        from gait_planner.viz.rerun_walk import save_walk_rrd as writer
    try:
        result[key] = str(writer(result, path))
    except OSError as error:
        raise CliError(f"cannot write {path}: {error}") from error


def _replan_command(args: argparse.Namespace) -> int:
    from gait_planner.api import walk_replanned

    if args.recording or args.self_test or args.out or args.rrd or args.config:
        raise CliError("--replan walks a scene from standing: no RUN.mcap, --self-test, "
                       "--out, --rrd or --config with it")
    try:
        result = walk_replanned(args.replan, args.steps, deadline=args.deadline,
                                progress=lambda line: print(f"-- {line}", file=sys.stderr,
                                                            flush=True))
    except ValueError as error:  # RequestError, StartError: an unknown scene, no start
        raise CliError(str(error)) from error
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(f"{result['scene']}: {result['half_cycles_walked']} of {args.steps} half "
              f"cycles re-planned, {result['stopped']}; stood still at the end: "
              f"{result.get('stood', False)}; re-plans converged "
              f"{result.get('replans_converged', 0)} of {result.get('replans', 0)} (median "
              f"{result.get('replan_iterations_median')} iterations, "
              f"{result.get('replan_wall_median_s')} s); feedback share "
              f"{result.get('feedback_share', float('nan')):.2f}")
    return 0 if result["stopped"] == "completed" else 1


def _walk_command(args: argparse.Namespace) -> int:
    from gait_planner.walk.recording import output_path
    from gait_planner.walk.walk_plan import CONFIG, load_config, walk

    if args.replan is not None:
        return _replan_command(args)
    if args.recording is None:
        raise CliError("walk needs a recording RUN.mcap (or --replan SCENE)")
    if args.deadline is not None:
        raise CliError("--deadline is a re-plan's time limit: only with --replan SCENE")

    outputs = {k: v for k, v in (("out", args.out), ("rrd", args.rrd)) if v is not None}
    try:
        targets = [output_path(path) for path in outputs.values()]  # before the walk
        if len(set(targets)) < len(targets):
            raise ValueError(f"--out and --rrd name the same file {targets[0]}")
        try:
            config = load_config(args.config or CONFIG)
        except OSError as error:
            raise ValueError(f"cannot read {args.config}: {error}") from None
        result = walk(args.recording, args.steps, config=config, series=bool(outputs),
                      progress=print_progress)
        for key, path in outputs.items():
            _write(key, path, result)
        result.pop("series", None)
        if args.self_test:
            result["self_test"] = self_test(args.recording, args.steps, result, config)
    except ValueError as error:
        raise CliError(str(error)) from error
    print(json.dumps(result, indent=2) if args.json else format_summary(result))
    return 0
