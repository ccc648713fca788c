"""A plan's progress on the terminal (stderr): IPOPT's iterations and the stages a plan
enters, as `Planner`'s `progress` and `stage` callbacks (`gait_planner.ocp.solve`)."""

from __future__ import annotations

import sys


def print_iteration(iteration: int, cost: float, violation: float, seconds: float) -> None:
    """Every tenth iteration: its number, cost, constraint violation and seconds so far."""
    if iteration % 10 == 0:
        if iteration == 0:
            print(f"{'iter':>6} {'cost':>14} {'violation':>10} {'time s':>8}", file=sys.stderr)
        print(f"{iteration:6d} {cost:14.6g} {violation:10.2e} {seconds:8.1f}", file=sys.stderr,
              flush=True)


def print_stage(name: str) -> None:
    """The stage a plan enters (building, cold stage 1, refining the grid, ...)."""
    print(f"-- {name}", file=sys.stderr, flush=True)
