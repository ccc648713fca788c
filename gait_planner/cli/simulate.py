"""``gait-planner simulate``: free motion of a scene and its structure-preservation report.

`simulate` runs `gait_planner.dynamics.free_motion.run_free_motion` on a scene (a name or a
scene file's path, `gait_planner.model.loader.find_scene`) and
returns plain JSON-ready data; `add_simulate_parser` registers the command line::

    gait-planner simulate --scene NAME --steps N --dt H [--gravity | --no-gravity]
                          [--torques zero|random] [--seed S] [--pin CONTACT] [--json]

Without --json it prints a short table. Bad input (unknown scene or contact, steps < 1,
dt <= 0 or not finite) and a failed step end in one error line, never a traceback.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from typing import Any

from gait_planner.cli.arguments import integer_from
from gait_planner.cli.errors import CliError

# The numerics (CasADi) are imported when a simulation runs, so that registering the command
# keeps `gait-planner --help` fast.

TORQUES = ("zero", "random")


def simulate(scene_name: str, steps: int, dt: float, gravity: bool = True,
             torques: str = "zero", seed: int = 0, pin: str | None = None) -> dict[str, Any]:
    """Simulate `steps` steps of `dt` s of the scene `scene_name` from its initial pose with
    seeded random rates (and torques) and report the errors.

    Returns a JSON-ready dict: ``scene``, every `FreeMotionReport` field (steps, dt,
    gravity, torques, seed, energy_error_max, linear_momentum_error_max,
    angular_momentum_error_max, linear_momentum_scale, angular_momentum_scale,
    constraint_violation_max, newton_iterations_mean, wall_time_s) and ``pinned`` (the
    held contact's name, or None).

    Raises ValueError (`SceneError` for scenes) on bad input and `SimulationError` if a step
    has no solution (e.g. dt too large for the motion).
    """
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not math.isfinite(dt) \
            or dt <= 0:
        raise ValueError(f"dt must be a finite number > 0 (seconds), got {dt!r}")
    if torques not in TORQUES:
        raise ValueError(f"torques must be one of {', '.join(TORQUES)}, got {torques!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
    from gait_planner.dynamics.free_motion import run_free_motion
    from gait_planner.model.loader import find_scene

    scene = find_scene(scene_name)
    _, report = run_free_motion(scene, steps=steps, dt=float(dt), gravity=bool(gravity),
                                torques=torques, seed=seed, pin=pin)
    return {"scene": scene.name, **dataclasses.asdict(report), "pinned": pin}


def format_table(result: dict[str, Any]) -> str:
    """A short human-readable summary of a `simulate` result."""
    r = result
    head = (f"{r['scene']}: {r['steps']} steps of {r['dt']:g} s, gravity "
            f"{'on' if r['gravity'] else 'off'}, torques {r['torques']}, seed {r['seed']}, "
            f"pinned {r['pinned'] or 'none'}")
    rows = [
        ("energy error (max |E-E0| / max T)", f"{r['energy_error_max']:.3e}"),
        ("linear momentum error (kg m/s)",
         f"{r['linear_momentum_error_max']:.3e}  (scale {r['linear_momentum_scale']:.3g})"),
        ("angular momentum error (kg m^2/s)",
         f"{r['angular_momentum_error_max']:.3e}  (scale {r['angular_momentum_scale']:.3g})"),
        ("constraint violation (max |g|)", f"{r['constraint_violation_max']:.3e}"),
        ("Newton iterations (mean)", f"{r['newton_iterations_mean']:.2f}"),
        ("wall time (s)", f"{r['wall_time_s']:.2f}"),
    ]
    width = max(len(name) for name, _ in rows)
    lines = [head] + [f"  {name:<{width}}  {value}" for name, value in rows]
    if r["pinned"] or r["gravity"]:
        lines.append("  (momentum is conserved only without gravity and pin)")
    return "\n".join(lines)


_positive_int = integer_from(1)
_seed = integer_from(0)


def _positive_seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text!r}")
    return value


def add_simulate_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``simulate`` on `subparsers`; its handler is ``args.handler(args) -> int``."""
    parser = subparsers.add_parser(
        "simulate",
        help="simulate free motion and report energy/momentum/constraint errors",
        description="Simulate a scene from its initial pose with seeded random rates "
        "(free-floating, or with one contact point pinned) using the variational "
        "integrator, and report the structure-preservation errors.",
    )
    parser.add_argument("--scene", required=True, metavar="NAME|FILE.yaml",
                        help="a scene: a name (config/scenes/NAME.yaml or a folder of "
                        "GAIT_PLANNER_SCENE_PATH) or the path to a scene file (.yaml, .yml)")
    parser.add_argument("--steps", required=True, type=_positive_int, metavar="N",
                        help="number of time steps (>= 1)")
    parser.add_argument("--dt", required=True, type=_positive_seconds, metavar="H",
                        help="time step in s (> 0)")
    parser.add_argument("--gravity", action=argparse.BooleanOptionalAction, default=True,
                        help="with gravity (default) or without")
    parser.add_argument("--torques", choices=TORQUES, default="zero",
                        help="joint torques: zero (passive, default) or seeded random")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S",
                        help="seed of the random rates and torques (default 0)")
    parser.add_argument("--pin", metavar="CONTACT", default=None,
                        help="hold this contact point at its initial position")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    parser.set_defaults(handler=_simulate_command)
    return parser


def _simulate_command(args: argparse.Namespace) -> int:
    from gait_planner.dynamics.forward import SimulationError

    try:
        result = simulate(args.scene, args.steps, args.dt, args.gravity, args.torques,
                          args.seed, pin=args.pin)
    except SimulationError as error:
        raise CliError(f"simulation failed: {error}") from error
    except ValueError as error:
        raise CliError(str(error)) from error
    print(json.dumps(result, indent=2) if args.json else format_table(result))
    return 0
