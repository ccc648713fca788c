"""``gait-planner prepare SCENE...``: compile the scenes' derivatives and plan their
defaults, warm-start anchors, starts from standing and stops into the warm-start store
(`make prepare`; `make setup` runs ``prepare --default-only walker3d``, what `make run`'s
plan needs; the node prepares its `prepare_scenes` in the background by running this
command)."""

from __future__ import annotations

import argparse
import time

from gait_planner.cli.errors import CliError
from gait_planner.cli.terminal import print_stage


def add_prepare_parser(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "prepare", help="compile the scenes' derivatives and plan their defaults now "
        "(make prepare; make setup runs it --default-only for walker3d)",
        description="Build each SCENE's problems with compiled derivatives (one per shape: "
        "level or ramp, a requested speed, stairs up, stairs down; for each of its gaits), so "
        "that the C libraries are in the cache (~/.cache/gait_planner or $GAIT_PLANNER_CACHE) "
        "and no request within the scene's ranges compiles, and plan its default request and "
        "its warm-start anchors, its start from standing and its stop to standing into the "
        "warm-start store (gait_planner/ocp/warm_starts.py), from which the node's first "
        "request re-plans warm. A scene prepared in full is marked "
        "in the cache (gait_planner/ocp/prepared.py) and skipped the next time unless its file "
        "or the code changed. The first time it compiles for minutes (walker3d in full about "
        "4.5 min on 2 cores, walker2d 1.3, the compass seconds); --default-only builds only "
        "the default problem and plans the default (walker3d: about 1 min).")
    parser.add_argument("scenes", nargs="+", metavar="NAME|FILE.yaml",
                        help="scenes: names or paths to scene files (see plan --help)")
    parser.add_argument("--default-only", action="store_true",
                        help="only each scene's default problem and its default plan (what "
                        "`make run` needs; make setup runs it for walker3d)")
    parser.add_argument("--again", action="store_true",
                        help="prepare a scene even if the cache marks it prepared")
    parser.set_defaults(handler=_prepare)


def _compile_note(stage: str) -> None:
    """`prepare`'s stage callback: only a compilation, or why there is none, is news."""
    if stage.startswith(("building: compiling", "building with")):
        print_stage(stage)


def _plan_anchors(planner, scene) -> list[bool]:
    """Plan the scene's warm-start anchors (`ocp.prepare_requests.anchor_requests`), each from the
    nearest plan kept, into the planner's warm-start store, each reported as it ends; whether
    each converged."""
    from gait_planner.ocp.prepare_requests import anchor_requests
    from gait_planner.ocp.settings import settings_for
    from gait_planner.strategies import plan_once

    anchors, out = anchor_requests(scene), []
    for k, anchor in enumerate(anchors, 1):
        result = plan_once(planner, scene, settings_for(scene, compiled=True, **anchor))
        out.append(result.success)
        print(f"{scene.name}: warm-start anchor {k} of {len(anchors)} "
              + ("planned" if result.success else f"{anchor} failed: {result.message}"),
              flush=True)
    return out


def _plan_start_and_stop(planner, scene, settings) -> list[bool]:
    """Plan the scene's start from standing and its stop to standing from the gait's first
    node (`transitions.plan_transition`, the defaults of `plan --from standing` and `plan
    --to standing`), if it declares start and stop phases, into the warm-start store: a
    fresh process's first such plan begins where these ended and repeats them warm
    (`transitions.REPEATED_ATTEMPT`); each reported as it ends; whether each converged."""
    from gait_planner.ocp.transition import standing_start
    from gait_planner.transitions import plan_transition

    out = []
    for name, phases, stop in (("start from standing", scene.gait.start, False),
                               ("stop to standing", scene.gait.stop, True)):
        if not phases:
            continue
        result = plan_transition(planner, scene, settings,
                                 None if stop else standing_start(scene), stop=stop)
        out.append(result.success)
        print(f"{scene.name}: {name} " + ("planned" if result.success
                                          else f"failed: {result.message}"), flush=True)
    return out


def _build_forms(planner, scene) -> None:
    """Build every problem shape of the scene's walk and of its other gaits (not planned),
    each reported as it is built."""
    from gait_planner.model.loader import with_gait
    from gait_planner.ocp.prepare_requests import form_requests
    from gait_planner.ocp.settings import settings_for

    forms = [(gait, shape) for gait in (scene, *(with_gait(scene, g) for g in scene.gaits))
             for shape in form_requests(gait, settings_for(gait, compiled=True))]
    for k, (gait, shape) in enumerate(forms, 1):
        planner.prepare(gait, shape)
        print(f"{scene.name}: problem {k} of {len(forms)} built (ground forms and gaits)",
              flush=True)


def _prepare(args: argparse.Namespace) -> int:
    from gait_planner.model.loader import SceneError, find_scene
    from gait_planner.ocp.prepared import is_prepared, mark_prepared
    from gait_planner.ocp.settings import SettingsError, settings_for
    from gait_planner.ocp.solve import Planner
    from gait_planner.ocp.warm_starts import WarmStartStore
    from gait_planner.strategies import plan_once

    for name in args.scenes:
        start = time.perf_counter()
        try:
            scene = find_scene(name)
            if not (args.default_only or args.again) and is_prepared(scene):
                print(f"{name}: prepared already (--again prepares it anew)", flush=True)
                continue
            settings = settings_for(scene, compiled=True)
            planner = Planner(library=WarmStartStore(), stage=_compile_note, pin=True)
            used = planner.prepare(scene, settings)
            result = plan_once(planner, scene, settings, warm_start=False)
            print(f"{name}: default problem built and planned "
                  f"({time.perf_counter() - start:.1f} s)", flush=True)
            anchors, motions = [], []
            if not args.default_only:
                _build_forms(planner, scene)
                if result.success:
                    anchors = _plan_anchors(planner, scene)
                    motions = _plan_start_and_stop(planner, scene, settings)
        except (SceneError, SettingsError) as error:
            raise CliError(str(error)) from None
        kept = ("its default plan" + (f", {sum(anchors)} of {len(anchors)} warm-start "
                                      "anchors" if anchors else "")
                + (f", {sum(motions)} of {len(motions)} of its start and stop"
                   if motions else "")
                + " kept in the warm-start store" if result.success
                else f"its default plan failed: {result.message}")
        gaits = (f"; its gaits {', '.join(scene.gaits)} built"
                 if scene.gaits and not args.default_only else "")
        seconds = time.perf_counter() - start
        if result.success and not args.default_only:
            mark_prepared(scene, seconds)
        print(f"{name}: {used}; {kept}{gaits} ({seconds:.1f} s)", flush=True)
    return 0
