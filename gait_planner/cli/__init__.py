"""Command line of gait_planner: ``gait-planner <command> [options]``.

Adding a command takes two small functions and one line:

* ``_add_<name>(commands)`` registers the sub-parser, its options and its handler
  (``parser.set_defaults(handler=_<name>)``);
* ``_<name>(args) -> int`` does the work and returns the exit code; it raises `CliError`
  with one sentence for anything the user has to fix;
* ``_add_<name>`` is appended to `COMMANDS` (larger commands live in modules of their
  own: `ros_commands`, `simulate`, `walk`, `robot`, `library`, `prepare`; `terminal` prints
  a plan's progress).

Every error reaches the user as one line ``gait-planner: error: ...`` on stderr with exit
code 2, never as a traceback (``--traceback`` shows it, for debugging).
"""

from __future__ import annotations

import argparse
import sys
from importlib import metadata
from typing import Callable, NoReturn, Sequence

from gait_planner.cli.errors import CliError
from gait_planner.cli.library import add_library_parser
from gait_planner.cli.prepare import add_prepare_parser
from gait_planner.cli.robot import URDF_HELP, add_scene_parser, add_urdf_options
from gait_planner.cli.ros_commands import (GAIT_HELP, SLOPE_HELP, SPEED_HELP, STEP_HEIGHT_HELP,
                                          add_call_parser, add_node_parser)
from gait_planner.cli.simulate import add_simulate_parser
from gait_planner.cli.terminal import print_iteration, print_stage
from gait_planner.cli.walk import add_walk_parser

PROG = "gait-planner"
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are one line naming the program, exit code 2."""

    def error(self, message: str) -> NoReturn:
        _print_error(f"{message} (see '{PROG} --help')")
        raise SystemExit(EXIT_USAGE)


def _print_error(message: str) -> None:
    print(f"{PROG}: error: {message}", file=sys.stderr)


def _version() -> str:
    try:
        return metadata.version("gait_planner")
    except metadata.PackageNotFoundError:
        return "unknown (not installed)"


# --- commands ----------------------------------------------------------------------------

SCENE_HELP = ("a scene: a name (the file NAME.yaml in config/scenes or in a folder of "
              "GAIT_PLANNER_SCENE_PATH) or the path to a scene file ending in .yaml or .yml")


def _add_plan_options(parser: argparse.ArgumentParser, scene_default: str | None) -> None:
    parser.add_argument("--scene", default=scene_default, required=False,
                        metavar="NAME|FILE.yaml", help=SCENE_HELP)
    parser.add_argument("--step-length", type=float, help="m (default: the scene's)")
    parser.add_argument("--speed", type=float, metavar="M/S", help=SPEED_HELP)
    parser.add_argument("--slope", type=float, default=0.0, metavar="DEG", help=SLOPE_HELP)
    parser.add_argument("--gait", default="", metavar="NAME", help=GAIT_HELP)
    parser.add_argument("--step-height", type=float, default=0.0, metavar="M",
                        help=STEP_HEIGHT_HELP)
    parser.add_argument("--cost", help="kinetic_energy | torque_squared (default: the scene's)")
    # the request's field names (as `call` has them), and the short names of earlier releases
    parser.add_argument("--intervals-per-phase", "--intervals", dest="intervals", type=int,
                        metavar="N", help="intervals per phase (default: the scene's); the "
                        "half cycle keeps its length")
    parser.add_argument("--friction-coefficient", "--mu", dest="mu", type=float, metavar="MU",
                        help="friction coefficient (default: the scene's)")
    parser.add_argument("--steps", type=int, default=1,
                        help="half cycles to record, joined by the mirror (default 1)")
    parser.add_argument("--posture", default="", choices=("", "paper", "human"),
                        help="paper: the scene's ranges; human: also a stance knee of at most "
                        "20 deg in single support (default: the scene's)")
    parser.add_argument("--max-solve-time", "--max-time", dest="max_time", type=float,
                        metavar="S", help="solver time limit, s (default: the scene's "
                        "max_solve_time option, 600 s unless set)")
    parser.add_argument("--walk", type=int, default=0, metavar="K",
                        help="then walk the recorded plan K half cycles in MuJoCo with the "
                        "reference controller (as `walk RUN.mcap --steps K`; config/walk.yaml) "
                        "and print the walk's summary, with --json under \"walk\"; a fall "
                        "leaves the exit status 0 (default 0: no walk)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("--no-rrd", action="store_true", help="do not write the rerun .rrd")
    parser.add_argument("--compile", action=argparse.BooleanOptionalAction, default=True,
                        help="compile the derivatives to C, cached in ~/.cache/gait_planner "
                        "or $GAIT_PLANNER_CACHE (default; `make setup` compiles the shipped "
                        "scenes, another scene's first plan compiles for up to a minute); "
                        "without a C compiler and the scene's cache: CasADi's derivatives, "
                        "with a note. --no-compile: CasADi's derivatives (slower to build "
                        "and to solve)")


def _add_plan(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "plan", help="plan a half-cycle gait and record it (MCAP + rerun .rrd)",
        description="Plan one half cycle with DMOCC + IPOPT, print progress and a summary, "
        "write OUT (MCAP, ROS 2 profile) and OUT with .rrd.")
    _add_plan_options(parser, None)
    parser.add_argument("--out", required=True, help="the recording, e.g. runs/walk.mcap")
    parser.add_argument("--cold-start", action="store_true",
                        help="plan from the scene's guess, without the warm-start store "
                        "(default: as the node, from the nearest plan kept in "
                        "~/.cache/gait_planner/plans: `make setup`'s default plans and "
                        "warm-start anchors, and earlier plans of the same problem; the "
                        "plan is kept there for later ones)")
    parser.add_argument("--urdf", metavar="ROBOT.urdf", help=URDF_HELP + "; the drafted "
                        "scene is written beside --out as NAME.yaml and planned")
    parser.add_argument("--from", dest="start", metavar="standing|RUN.mcap[:TIME]",
                        help="begin standing still (the scene's pose and start phases) or at "
                        "the state of a recording of this robot (at TIME s from its start; "
                        "default its first node): the answer is the transition from it onto "
                        "the gait, then --steps of the gait's half cycles")
    parser.add_argument("--to", dest="stop", choices=("standing",),
                        help="end standing at rest, both feet flat (the scene's stop phases), "
                        "after --transition-half-cycles (from --from's state or the gait's "
                        "first node) instead of walking on")
    parser.add_argument("--transition-half-cycles", dest="halves", type=int, default=None,
                        metavar="K", help="half cycles of the transition --from a state "
                        "(1 to 4; default 2: one cannot mend every start; with --to "
                        "standing 1)")
    add_urdf_options(parser)
    parser.set_defaults(handler=_plan)


def _plan_and_print(args: argparse.Namespace, out: str) -> dict:
    import json
    from pathlib import Path

    from gait_planner.model.loader import find_scene
    from gait_planner.ocp.solve import Planner
    from gait_planner.ocp.warm_starts import WarmStartStore
    from gait_planner.pipeline import plan_and_record, summary
    from gait_planner.problem import resolve
    from gait_planner.ocp.transition import StartError
    from gait_planner.request import PlanRequest, RequestError

    target = Path(out)
    if target.suffix != ".mcap":
        raise CliError(f"--out must name a .mcap file, got {out!r}")
    if args.walk < 0:
        raise CliError(f"--walk must be a number of half cycles >= 0 (0: no walk), "
                       f"got {args.walk}")
    if getattr(args, "urdf", None):
        from gait_planner.cli.robot import draft_of, write_draft
        draft = draft_of(args, target.parent)  # beside the recording (its name checked there)
        args.scene = str(write_draft(draft, target.parent / f"{draft.name}.yaml"))
    elif args.scene is None:
        raise CliError("plan needs --scene or --urdf")
    request = PlanRequest(scene=args.scene, step_length=args.step_length, cost=args.cost,
                          friction_coefficient=args.mu, intervals_per_phase=args.intervals,
                          max_solve_time=args.max_time, output_name=target.stem,
                          compiled=args.compile, steps=args.steps, posture=args.posture,
                          speed=args.speed, slope=args.slope, step_height=args.step_height,
                          gait=args.gait, cold_start=args.cold_start)
    # `plan` starts, as the node does, from the store's nearest plan (a request planned cold
    # can stall where the store's anchors plan it in seconds: walker3d's stairs at 0.10 m,
    # benchmarks/HISTORY.md 2026-11-30); --cold-start and `run` neither read nor write it
    store = None if args.cold_start else WarmStartStore()
    print(f"planning {args.scene} ...", file=sys.stderr, flush=True)
    try:  # a compile cache miss is announced by the stage "compiling (...)"
        planner = Planner(progress=print_iteration, stage=print_stage, library=store)
        problem = resolve(request, find_scene)
        start = _start_of(getattr(args, "start", None), problem.scene)
        outcome = plan_and_record(planner, problem, target.parent if str(target.parent) else ".",
                                  rrd=not args.no_rrd, start=start,
                                  halves=getattr(args, "halves", None),
                                  stop=getattr(args, "stop", None) == "standing")
    except (RequestError, StartError) as err:
        raise CliError(str(err)) from None
    data = summary(outcome)
    if not args.json:
        width = max(len(k) for k in data)
        for key, value in data.items():
            print(f"{key:<{width}}  {value}")
    if args.walk and data["success"]:
        data["walk"] = _walk_plan(data["mcap"], args.walk, printed=not args.json)
    if args.json:
        print(json.dumps(data, indent=2))
    return data


def _start_of(text: str | None, scene):
    """The start state of --from standing|RUN.mcap[:TIME] (None without it)."""
    if not text:
        return None
    from gait_planner.ocp.transition import standing_start
    from gait_planner.transitions import start_of_recording

    if text == "standing":
        return standing_start(scene)

    path, _, time = text.rpartition(":") if ":" in text else (text, "", "")
    try:
        seconds = float(time) if time else None
    except ValueError:
        path, seconds = text, None
    return start_of_recording(scene, path or text, seconds)


def _walk_plan(mcap: str, steps: int, printed: bool) -> dict:
    """Walk the recorded plan `steps` half cycles in MuJoCo (--walk) and return the walk's
    summary (`gait_planner.walk.walk_plan.walk`), `printed` as `gait-planner walk` prints it."""
    from gait_planner.cli.walk import print_progress
    from gait_planner.walk.walk_plan import walk
    from gait_planner.walk.summary import format_summary

    print(f"walking the plan {steps} half cycles in MuJoCo ...", file=sys.stderr, flush=True)
    try:
        walked = walk(mcap, steps, progress=print_progress)
    except ValueError as error:
        raise CliError(f"--walk: cannot walk the recorded plan: {error}") from None
    if printed:
        print(format_summary(walked))
    return walked


def _plan(args: argparse.Namespace) -> int:
    data = _plan_and_print(args, args.out)
    return 0 if data["success"] else 1


def _add_run(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "run", help="plan the paper's gait, record it and show it (what `make run` calls)",
        description="Plan walker3d with the paper's step length and minimal kinetic energy, "
        "write runs/walker3d.mcap and .rrd, compare with the paper and open rerun if a "
        "display is available.")
    _add_plan_options(parser, "walker3d")
    parser.add_argument("--out", default="runs/walker3d.mcap", help="the recording")
    parser.add_argument("--no-viewer", action="store_true", help="do not open rerun")
    # the paper's gait solved from the scene's guess, not re-planned from the store's optimum
    parser.set_defaults(handler=_run, cold_start=True)


def _run(args: argparse.Namespace) -> int:
    import os
    import shutil
    import subprocess

    from gait_planner.viz.figures import plot_recording

    data = _plan_and_print(args, args.out)
    if not data["success"]:
        return 1
    print(f"figure: {plot_recording(data['mcap'], os.path.splitext(data['mcap'])[0] + '.png')}")
    sigma = ", ".join(f"{x:.4f}" for x in data["phase_scaling"])
    print(f"\nthis plan: J = {data['cost_value']:.4f} J s (2 J = {2 * data['cost_value']:.4f}), "
          f"half cycle {data['duration']:.4f} s, sigma = {sigma}")
    print("the paper (Koch & Leyendecker 2015): J = 41.2256 J s, half cycle 0.5988 s, "
          "sigma = 1.5000, 1.5000, 1.4889, 1.4724")
    print("(docs/results.md, \"The paper's gait\": the paper's J is close to our 2 J; its "
          "grid, bounds and path constraints are unknown)")
    viewer = shutil.which("rerun") or os.path.join(os.path.dirname(sys.executable), "rerun")
    shown = data["rrd"] or data["mcap"]
    if not args.no_viewer and os.environ.get("DISPLAY") and os.path.exists(viewer):
        subprocess.Popen([viewer, shown], start_new_session=True)  # noqa: S603
        print(f"opened rerun on {shown}")
    else:
        print(f"no display: view it with `.venv/bin/rerun {shown}` (or `rerun {data['mcap']}` "
              "for the standard ROS 2 view: URDF moved by /tf)")
    return 0


def _add_report(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "report", help="draw a recorded plan (PNG) and check it independently",
        description="Read RUN.mcap, draw the walker, its phase schedule, ground forces, "
        "joint angles and torques per joint and leg, energies and the continuous-dynamics "
        "certificate into a PNG, run the independent "
        "verifier (gait_planner.verify) on it and print its report: every check grouped, with "
        "its value, unit, limit and mark, then a verdict line (exit status 0: all checks "
        "passed, 1: a check failed).")
    parser.add_argument("mcap", help="a recording written by plan/run/node")
    parser.add_argument("--png", help="the figure (default: RUN.png beside the recording)")
    parser.set_defaults(handler=_report)


def _report(args: argparse.Namespace) -> int:
    from pathlib import Path

    from gait_planner.viz.figures import plot_recording
    from gait_planner.verify import verify_recording

    source = Path(args.mcap)
    if source.suffix != ".mcap" or not source.is_file():
        raise CliError(f"{args.mcap!r} is not an existing .mcap file")
    # the figure first: it is drawn even from a recording the verifier cannot read
    png = plot_recording(source, args.png or source.with_suffix(".png"))
    print(f"figure: {png}")
    report = verify_recording(source)
    print(report.summary())  # grouped, with units and limits; its last line is the verdict
    return 0 if report.ok else 1


def _add_urdf(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "urdf", help="write a scene's URDF (what /robot_description holds)",
        description="Write the URDF of SCENE: one link per body (the scene's masses, centres "
        "of mass and inertias; a non-realisable inertia is replaced by the nearest realisable "
        "one, with a comment), joints named after the joint angles; it loads in MuJoCo and "
        "Pinocchio. To stdout unless --out is given.")
    parser.add_argument("scene", metavar="NAME|FILE.yaml", help=SCENE_HELP)
    parser.add_argument("--out", help="the file to write (default: stdout)")
    parser.set_defaults(handler=_urdf)


def _urdf(args: argparse.Namespace) -> int:
    from pathlib import Path

    from gait_planner.io.urdf import realisable_inertia, scene_to_urdf
    from gait_planner.model.loader import SceneError, find_scene

    try:
        scene = find_scene(args.scene)
    except SceneError as error:
        raise CliError(str(error)) from None
    text = scene_to_urdf(scene)
    for body in scene.bodies:
        written = realisable_inertia(body.inertia)
        if written != tuple(body.inertia):
            print(f"note: {body.name}'s inertia {tuple(body.inertia)} is not realisable; the "
                  f"URDF holds the nearest realisable {written} (see its comment)",
                  file=sys.stderr)
    if args.out is None:
        sys.stdout.write(text)
        return 0
    try:
        Path(args.out).write_text(text, encoding="utf-8")
    except OSError as error:
        raise CliError(f"cannot write {args.out!r}: {error.strerror or error}") from None
    print(f"urdf: {args.out}")
    return 0


COMMANDS: tuple[Callable[[argparse._SubParsersAction], None], ...] = (
    _add_run, _add_plan, _add_report, add_node_parser, add_call_parser, add_simulate_parser,
    add_walk_parser,
    _add_urdf, add_scene_parser, add_prepare_parser, add_library_parser)


# --- entry point -------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    """The parser with every command of `COMMANDS` registered."""
    parser = _Parser(
        prog=PROG,
        description="Plan human-like walking gaits by structure-preserving optimal control.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    parser.add_argument(
        "--traceback", action="store_true", help="show the full traceback of an error"
    )
    commands = parser.add_subparsers(
        title="commands", dest="command", metavar="COMMAND", parser_class=_Parser
    )
    commands.required = True
    for add_command in COMMANDS:
        add_command(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``gait-planner`` with `argv` (default: sys.argv[1:]); returns the exit code."""
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args, extra = parser.parse_known_args(argv)
        if args.command == "node":
            # everything after `node` is the node's, in order ("--ros-args -p a:=b": argparse's
            # REMAINDER does not take arguments that start with '-')
            args.ros_args = argv[argv.index("node") + 1:]
        elif extra:
            parser.error(f"unrecognized arguments: {' '.join(extra)}")
    except SystemExit as exit_:  # --help, --version and usage errors
        return exit_.code if isinstance(exit_.code, int) else EXIT_USAGE
    try:
        return int(args.handler(args))
    except KeyboardInterrupt:
        _print_error("interrupted")
        return EXIT_INTERRUPTED
    except Exception as error:  # noqa: BLE001  (one line for the user, never a traceback)
        if args.traceback:
            raise
        message = str(error) if isinstance(error, CliError) else f"{type(error).__name__}: {error}"
        _print_error(" ".join(message.split()) or type(error).__name__)
        return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
