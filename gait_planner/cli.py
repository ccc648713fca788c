"""Command line of gait_planner: ``gait-planner <command> [options]``.

Adding a command takes two small functions and one line:

* ``_add_<name>(commands)`` registers the sub-parser, its options and its handler
  (``parser.set_defaults(handler=_<name>)``);
* ``_<name>(args) -> int`` does the work and returns the exit code; it raises `CliError`
  with one sentence for anything the user has to fix;
* ``_add_<name>`` is appended to `COMMANDS`.

Every error reaches the user as one line ``gait-planner: error: ...`` on stderr with exit
code 2, never as a traceback (``--traceback`` shows it, for debugging).
"""

from __future__ import annotations

import argparse
import sys
from importlib import metadata
from typing import Callable, NoReturn, Sequence

PROG = "gait-planner"
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


class CliError(Exception):
    """A failure the user can act on; its message is printed as one line (exit code 2)."""


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


def _add_run(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "run",
        help="plan the default gait (what `make run` calls)",
        description="Plan the default gait. Until gait_planner.ocp provides the planner, "
        "this only says so.",
    )
    parser.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    try:
        from gait_planner.ocp import plan  # noqa: F401  (only probing that it exists)
    except ImportError as error:
        if error.name in ("gait_planner.ocp", "gait_planner.ocp.plan"):
            print("the planner is not implemented yet")
            return 0
        raise CliError(f"cannot import the planner: {error}") from error
    raise CliError("the planner exists but `run` is not wired to it yet")


COMMANDS: tuple[Callable[[argparse._SubParsersAction], None], ...] = (_add_run,)


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
    try:
        args = parser.parse_args(argv)
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
