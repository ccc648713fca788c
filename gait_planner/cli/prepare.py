"""``gait-planner prepare SCENE...``: compile the scenes' derivatives and plan their
defaults and warm-start anchors into the warm-start store (`make setup` runs it)."""

from __future__ import annotations

import argparse
import time

from gait_planner.cli.errors import CliError
from gait_planner.cli.terminal import print_stage


def add_prepare_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "prepare", help="compile the scenes' derivatives and plan their defaults now "
        "(make setup runs it)",
        description="Build each SCENE's problems with compiled derivatives (one per shape: "
        "level or ramp, a requested speed, stairs up, stairs down; for each of its gaits), so "
        "that the C libraries are in the cache (~/.cache/gait_planner or $GAIT_PLANNER_CACHE) "
        "and no request within the scene's ranges compiles, and plan its default request and "
        "its warm-start anchors into the warm-start store (gait_planner/ocp/warm_starts.py), "
        "from which the node's first request re-plans warm. The first time it compiles for "
        "minutes (walker3d's walk and anchors 6.3 min on 2 cores, its other gaits up to 4 "
        "more); cached, planning the anchors takes most of its 1-4 minutes.")
    parser.add_argument("scenes", nargs="+", metavar="NAME|FILE.yaml",
                        help="scenes: names or paths to scene files (see plan --help)")
    parser.set_defaults(handler=_prepare)


def _compile_note(stage: str) -> None:
    """`prepare`'s stage callback: only a compilation, or why there is none, is news."""
    if stage.startswith(("building: compiling", "building with")):
        print_stage(stage)


def _plan_anchors(planner, scene) -> list[bool]:
    """Plan the scene's warm-start anchors (`ocp.prepare_requests.anchor_requests`), each from the
    nearest plan kept, into the planner's warm-start store; whether each converged."""
    from gait_planner.ocp.prepare_requests import anchor_requests
    from gait_planner.ocp.settings import settings_for
    from gait_planner.strategies import plan_once

    out = []
    for anchor in anchor_requests(scene):
        result = plan_once(planner, scene, settings_for(scene, compiled=True, **anchor))
        out.append(result.success)
        if not result.success:
            print(f"{scene.name}: the warm-start anchor {anchor} failed: {result.message}",
                  flush=True)
    return out


def _prepare(args: argparse.Namespace) -> int:
    from gait_planner.model.loader import SceneError, find_scene, with_gait
    from gait_planner.ocp.warm_starts import WarmStartStore
    from gait_planner.ocp.prepare_requests import form_requests
    from gait_planner.ocp.settings import SettingsError, settings_for
    from gait_planner.ocp.solve import Planner
    from gait_planner.strategies import plan_once

    for name in args.scenes:
        start = time.perf_counter()
        try:
            scene = find_scene(name)
            settings = settings_for(scene, compiled=True)
            planner = Planner(library=WarmStartStore(), stage=_compile_note, pin=True)
            used = planner.prepare(scene, settings)
            result = plan_once(planner, scene, settings, warm_start=False)
            # every shape of the walk (the default's already built) and of its other gaits
            # (built, not planned)
            for gait in (scene, *(with_gait(scene, g) for g in scene.gaits)):
                for shape in form_requests(gait, settings_for(gait, compiled=True)):
                    planner.prepare(gait, shape)
            anchors = _plan_anchors(planner, scene) if result.success else []
        except (SceneError, SettingsError) as error:
            raise CliError(str(error)) from None
        kept = ("its default plan" + (f" and {sum(anchors)} of {len(anchors)} warm-start "
                                      "anchors" if anchors else "")
                + " kept in the warm-start store" if result.success
                else f"its default plan failed: {result.message}")
        gaits = f"; its gaits {', '.join(scene.gaits)} built" if scene.gaits else ""
        print(f"{name}: {used}; {kept}{gaits} ({time.perf_counter() - start:.1f} s)", flush=True)
    return 0
