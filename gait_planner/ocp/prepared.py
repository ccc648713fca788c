"""Which scenes `gait-planner prepare` has prepared in full: every ground form and gait built
(their derivative elements compiled into the cache), the default request and the warm-start
anchors planned into the warm-start store.

A marker per scene, `<cache folder>/prepared/<scene name>.json`, holds the digest of what
the preparation depended on: the scene file's text and the source of the model, dynamics
and transcription code (`warm_starts.code_digest`). A changed scene or code makes the
marker stale, and the scene is prepared again (`make prepare`, the node's background
preparation: `gait_planner.ros.preparation`).
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

from gait_planner.atomic import atomic_target
from gait_planner.model.scene import Scene
from gait_planner.ocp.compile import cache_folder
from gait_planner.ocp.warm_starts import code_digest

__all__ = ["is_prepared", "mark_prepared", "marker_path"]


def marker_path(scene: Scene) -> Path:
    """The scene's marker file in the cache folder."""
    return cache_folder() / "prepared" / f"{scene.name}.json"


def _digest(scene: Scene) -> str:
    return hashlib.sha256((scene.source + "\n" + code_digest()).encode()).hexdigest()


def is_prepared(scene: Scene) -> bool:
    """Whether `scene` was prepared in full by this code from this scene text."""
    try:
        return json.loads(marker_path(scene).read_text()).get("digest") == _digest(scene)
    except (OSError, ValueError, AttributeError):
        return False


def mark_prepared(scene: Scene, seconds: float) -> None:
    """Record that `scene` is prepared in full (it took `seconds`); an unwritable cache
    folder is not an error: the scene is then prepared again next time."""
    path = marker_path(scene)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_target(path) as tmp:
            tmp.write_text(json.dumps({
                "digest": _digest(scene), "seconds": round(seconds, 1),
                "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}) + "\n")
    except OSError:
        pass
