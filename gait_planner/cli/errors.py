"""The command line's one error type, in a module of its own so that every command module
can raise it without importing the parser (`gait_planner.cli`)."""


class CliError(Exception):
    """A failure the user can act on; its message is printed as one line (exit code 2)."""
