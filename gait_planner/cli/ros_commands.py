"""``gait-planner node`` and ``gait-planner call``: the ROS 2 node, and a client of it.

`add_node_parser` runs `gait_planner.ros.node.main` with a parameters file and ROS arguments;
`add_call_parser` sends one request (service or action goal) through
`gait_planner.ros.client` and prints the answer. rclpy is imported when a command runs (or
`call --help` shows the node's defaults), so that registering them keeps `--help` fast.
"""

from __future__ import annotations

import argparse
import sys

from gait_planner.cli.errors import CliError

# `plan`, `run` and `call` --speed (GaitSettings.speed, ocp.settings.speed_range)
SPEED_HELP = ("mean forward speed of the half cycle, m/s: step length / duration, held by the "
              "phase durations (default 0: durations free). Reachable: the step length over "
              "the half cycle's nominal length times sigma's scaling bounds, up to the "
              "gait's speed_max, e.g. at the 0.6338 m step walker2d 1.083 to 3.250 m/s, "
              "walker3d 0.542 to 3.000 m/s (sigma up to 3.0 at a speed; its walk's "
              "speed_max); a speed outside is refused with its range")


# `plan`, `run` and `call` --slope and --step-height (gait_planner.model.ground)
SLOPE_HELP = ("ramp along the walking direction, degrees, uphill positive (default 0: level); "
              "refused if tan |slope| exceeds the friction coefficient")
STEP_HEIGHT_HELP = ("stairs: the rise per step, m, up (> 0) or down (< 0), treads as deep as "
                    "the step length (default 0: none); refused beyond the legs' reach")


GAIT_HELP = ("a gait the scene declares: walk (default) or one of its gaits (walker2d and "
             "walker3d: toe_first, landing forefoot first; run)")


def add_node_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "node", help="run the ROS 2 node (service and action /gait_planner/plan_gait)",
        description="Run the gait_planner node until SIGINT or SIGTERM. ROS arguments "
        "(--ros-args -p output_dir:=runs ...) follow; values given there override the "
        "parameters file.")
    parser.add_argument("--params-file", metavar="YAML",
                        help="node parameters in the ROS 2 format, e.g. "
                        "config/gait_planner.yaml")
    parser.add_argument("ros_args", nargs=argparse.REMAINDER, help="arguments for rclpy")
    parser.set_defaults(handler=_node)


def _node_arguments(argv: list[str]) -> tuple[str | None, list[str]]:
    """Split what follows ``node`` into the parameters file (``--params-file F`` or
    ``--params-file=F`` before any ROS argument) and the ROS arguments, kept in order."""
    params_file, rest = None, list(argv)
    if rest and rest[0].startswith("--params-file="):
        params_file, rest = rest[0].partition("=")[2], rest[1:]
    elif rest[:1] == ["--params-file"]:
        if len(rest) < 2:
            raise CliError("--params-file needs a file name")
        params_file, rest = rest[1], rest[2:]
    return params_file, rest


def _node(args: argparse.Namespace) -> int:
    from pathlib import Path

    params_file, ros_args = _node_arguments(args.ros_args)
    if params_file is not None:
        if not Path(params_file).is_file():
            raise CliError(f"--params-file {params_file!r} is not a file")
        # a ROS argument section of its own ("--" ends it); -p values override the file
        ros_args = ["--ros-args", "--params-file", params_file, "--", *ros_args]
    from rclpy.exceptions import ParameterException

    from gait_planner.ros.node import main as node_main

    try:
        return node_main(args=[sys.argv[0], *ros_args])
    except ParameterException as error:
        raise CliError(f"a node parameter was refused: {error}") from None


class _NodeDefault:
    """The default of a node parameter (`gait_planner.ros.parameters`), looked up when a help
    text shows it (``%(node_default)s`` in `call`'s options): that module loads rclpy, which
    the other commands do not need."""

    def __init__(self, name: str):
        self.name = name

    def __str__(self) -> str:
        from gait_planner.ros.parameters import DECLARATIONS

        value = DECLARATIONS[self.name][0]
        return f"{value:g}" if isinstance(value, float) else str(value)


def add_call_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "call", help="ask a running node for a plan (ros2cli is not on PyPI)",
        description="Send one request to a running node (the service /gait_planner/plan_gait, "
        "or with --action a goal of its action) and print the answer. The options are the "
        "request's fields (PlanGait.srv); 0 or empty means the default (the node's or the "
        "scene's), a negative, NaN or infinite number is refused before anything is sent, "
        "with the node's message. A request that gives no plan prints one line STATUS: REASON "
        "(refused, failed, rejected, aborted or canceled) and exits with 1. With --action, "
        "feedback lines (phase, iteration, cost, constraint violation) go to stderr as they "
        "arrive and Ctrl-C cancels the goal. A node that stops or dies before it answers ends "
        "the call with an error within a few seconds.")
    scene = parser.add_argument(
        "--scene", default="", metavar="NAME", help="scene name (default: the node's parameter "
        "default_scene, %(node_default)s unless set)")
    scene.node_default = _NodeDefault("default_scene")
    parser.add_argument("--step-length", type=float, default=0.0, metavar="M",
                        help="m, > 0 (default 0: the scene's)")
    parser.add_argument("--cost", default="",
                        help="kinetic_energy | torque_squared (default: the scene's)")
    parser.add_argument("--friction-coefficient", type=float, default=0.0, metavar="MU",
                        help="Coulomb friction mu0, > 0 (default 0: the scene's)")
    parser.add_argument("--intervals-per-phase", type=int, default=0, metavar="N",
                        help="time intervals per gait phase, > 0 (default 0: the scene's); the "
                        "half cycle keeps its length")
    limit = parser.add_argument(
        "--max-solve-time", type=float, default=0.0, metavar="S",
        help="solver time limit in s, > 0 (default 0: the node's parameter max_solve_time, "
        "%(node_default)s s unless set)")
    limit.node_default = _NodeDefault("max_solve_time")
    parser.add_argument("--output-name", default="", metavar="STEM",
                        help="file stem of the recording (default: scene and time)")
    parser.add_argument("--cold-start", action="store_true",
                        help="start from the scene's initial guess, ignore stored plans")
    parser.add_argument("--steps", type=int, default=0, metavar="N",
                        help="half cycles in the answer, joined by the mirror, 1 to 100 "
                        "(default 0: 1)")
    parser.add_argument("--posture", default="", choices=("", "paper", "human"),
                        help="paper: the scene's ranges; human: also a stance knee of at most "
                        "20 deg in single support (default: the scene's)")
    parser.add_argument("--speed", type=float, default=0.0, metavar="M/S", help=SPEED_HELP)
    parser.add_argument("--slope", type=float, default=0.0, metavar="DEG", help=SLOPE_HELP)
    parser.add_argument("--gait", default="", metavar="NAME", help=GAIT_HELP)
    parser.add_argument("--step-height", type=float, default=0.0, metavar="M",
                        help=STEP_HEIGHT_HELP)
    parser.add_argument("--action", action="store_true",
                        help="use the action: print feedback, Ctrl-C cancels")
    parser.add_argument("--timeout", type=float, default=900.0, metavar="S",
                        help="s to wait for the answer (default 900)")
    parser.add_argument("--preparation", action="store_true",
                        help="ask what the node has prepared instead (/gait_planner/"
                        "preparation): exit status 0 once every scene is ready")
    parser.add_argument("--json", action="store_true", help="print the answer as JSON")
    parser.set_defaults(handler=_call)


def _call(args: argparse.Namespace) -> int:
    import json
    import math

    from gait_planner.request import FIELDS, RequestError
    from gait_planner.ros.client import (CallError, ask_preparation, call_plan_gait,
                                         call_plan_gait_action)

    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise CliError(f"--timeout must be > 0 s, got {args.timeout}")
    if args.preparation:
        try:
            status = ask_preparation(timeout=args.timeout)
        except CallError as err:
            raise CliError(str(err)) from None
        print(json.dumps(status, indent=2) if args.json else status["message"])
        return 0 if status["done"] else 1
    fields = {name: getattr(args, name) for name in FIELDS}
    try:
        answer = (call_plan_gait_action if args.action else call_plan_gait)(
            fields, timeout=args.timeout)
    except (RequestError, CallError) as err:
        raise CliError(str(err)) from None
    if not answer["success"]:  # no plan: its status and reason, no record of zeros
        answer = {key: answer[key] for key in ("status", "success", "message")}
    if args.json:
        print(json.dumps(answer, indent=2))
    elif answer["success"]:
        print("\n".join(f"{k}: {v}" for k, v in answer.items()))
    else:
        print(f"{answer['status']}: {answer['message']}")
    return 0 if answer["success"] else 1
