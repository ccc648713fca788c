"""The requests `gait-planner prepare` (make setup) plans besides the default: one of each
problem shape a scene's requests may take (`form_requests`: building them compiles every
element a request within the scene's ranges needs) and the scene's warm-start anchors
(`anchor_requests`: plans a later request is continued from, `gait_planner.parameter_path`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

from gait_planner.model.scene import Scene
from gait_planner.ocp.settings import (ANCHORS_OPTION, GaitSettings, SettingsError, check_ground,
                                       check_speed, speed_range)

__all__ = ["FORM_STAIR", "anchor_requests", "form_requests"]

_ANCHOR_FIELDS = ("slope", "step_height", "speed", "step_length", "friction_coefficient")


def anchor_requests(scene: Scene) -> list[dict]:
    """The scene's warm-start anchors (gait option `warm_start_anchors`: a list of
    requests, each a mapping of some of slope, step_height, speed, step_length and
    friction_coefficient): planned by `gait-planner prepare` so that a request is continued
    from a near plan (`gait_planner.parameter_path`). [] if the scene declares none;
    SettingsError naming what is wrong with the list."""
    anchors = (scene.gait.options.get(ANCHORS_OPTION) or []) if scene.gait else []
    if not isinstance(anchors, (list, tuple)):
        raise SettingsError(f"{ANCHORS_OPTION} must be a list of requests, got {anchors!r}")
    for anchor in anchors:
        if not isinstance(anchor, Mapping) or not anchor or set(anchor) - set(_ANCHOR_FIELDS) \
                or not all(isinstance(v, (int, float)) and math.isfinite(v)
                           for v in anchor.values()):
            raise SettingsError(f"{ANCHORS_OPTION}: {anchor!r} is not a request (a mapping "
                                f"of numbers, its keys among {', '.join(_ANCHOR_FIELDS)})")
    return [dict(anchor) for anchor in anchors]


# A small stair (m) standing for every stair height of its sign in `form_requests`
FORM_STAIR = 0.02


def form_requests(scene: Scene, s: GaitSettings) -> list[GaitSettings]:
    """One request of each problem shape that requests like `s` on `scene` may take
    (`ocp.transcription.shape_of`): level ground with free durations, at a speed (the
    middle of `speed_range`), on stairs up, on stairs down, and the stairs-down start with
    the edge margin instead of the segment rows (`gait_planner.strategies.stair_start`); the
    shapes `scene` refuses (`check_ground`, `check_speed`) left out. Building these
    compiles everything any request of the scene within its ranges needs
    (`gait-planner prepare`)."""
    out = [dataclasses.replace(s, slope=0.0, step_height=0.0, speed=0.0)]
    slow, fast = speed_range(out[0])
    candidates = [dataclasses.replace(out[0], speed=0.5 * (slow + fast))]
    candidates += [dataclasses.replace(out[0], step_height=h) for h in (FORM_STAIR, -FORM_STAIR)]
    candidates.append(dataclasses.replace(out[0], step_height=-FORM_STAIR,
                                          stair_segment_rows=False))
    for candidate in candidates:
        try:
            check_ground(candidate, scene)
            check_speed(candidate, scene.name)
        except SettingsError:
            continue
        out.append(candidate)
    return out
