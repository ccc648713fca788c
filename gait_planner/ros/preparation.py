"""The node's background preparation (parameter prepare_scenes): each scene that the cache
does not mark prepared (`gait_planner.ocp.prepared`) is prepared by a child process,
``gait-planner prepare SCENE`` at low priority (nice 10), one scene after another, from a
thread of its own, so that the node serves requests meanwhile. Each line the child prints
(a problem built, an anchor planned) is logged and is where its scene stands; `status`
answers what is ready and what is not yet (the service /gait_planner/preparation).

A request meanwhile is planned as ever: a problem the cache lacks is built, and compiled,
for it (`gait_planner.ocp.solve.Planner`; the compiled libraries are written atomically, so
the child and the node may compile the same one side by side). Stopping the node ends the
child (its process group: the C compilers it runs too).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from gait_planner.model.loader import SCENE_PATH_ENV, scene_dirs
from gait_planner.model.scene import Scene
from gait_planner.ocp.prepared import is_prepared

# the child: this interpreter's `gait-planner` (not the console script, which a source
# checkout may lack)
COMMAND = ("nice", "-n", "10", sys.executable, "-c",
           "import sys; from gait_planner.cli import main; sys.exit(main())", "prepare")
QUEUED = "queued"
FAILED = "failed"


@dataclass(frozen=True)
class Status:
    """What is prepared: done (every scene), the scenes ready, the others each with where
    it stands, and one line for people."""

    done: bool
    ready: tuple[str, ...]
    pending: tuple[str, ...]
    message: str


class BackgroundPreparation:
    """Prepare `scenes` (each named by its file's name) one after another in a child
    process; `log` takes each line of progress (from the preparation's thread);
    `folders` are the node's scene_dirs, searched by the child first as by the node."""

    def __init__(self, scenes: Sequence[Scene], log: Callable[[str], None],
                 folders: Sequence[str] = ()):
        self._scenes = list(scenes)
        self._log = log
        self._folders = list(folders)
        self._where = {scene.name: QUEUED for scene in self._scenes}
        self._lock = threading.Lock()
        self._closed = threading.Event()
        self._child: subprocess.Popen | None = None
        self._thread = threading.Thread(target=self._run, name="gait_planner_prepare",
                                        daemon=True)

    def start(self) -> None:
        """Begin preparing in the background."""
        self._thread.start()

    def ready(self, name: str) -> bool:
        """Whether the scene `name` is one this node prepares and it is prepared (a
        scene it does not prepare: True, nothing is pending for it)."""
        scene = next((s for s in self._scenes if s.name == name), None)
        return scene is None or is_prepared(scene)

    def status(self) -> Status:
        """What is ready and what is not yet, from the cache's markers and the child's
        progress."""
        ready = tuple(s.name for s in self._scenes if is_prepared(s))
        with self._lock:
            pending = tuple(f"{s.name}: {self._where[s.name]}" for s in self._scenes
                            if s.name not in ready)
        if not self._scenes:
            message = "no scene is prepared in the background (parameter prepare_scenes)"
        else:
            message = (f"ready: {', '.join(ready) or 'none'}"
                       + (f"; not yet: {'; '.join(pending)}" if pending else ""))
        return Status(not pending, ready, pending, message)

    def close(self) -> None:
        """Stop preparing: end the child, if one runs, and its compilers."""
        self._closed.set()
        child = self._child
        if child is not None and child.poll() is None:
            try:
                os.killpg(child.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass

    def _set(self, name: str, where: str) -> None:
        with self._lock:
            self._where[name] = where

    def _run(self) -> None:
        env = {**os.environ, SCENE_PATH_ENV: os.pathsep.join(
            str(d) for d in scene_dirs(self._folders))}
        for scene in self._scenes:
            if self._closed.is_set():
                return
            if is_prepared(scene):
                continue
            self._set(scene.name, "preparing")
            self._log(f"preparing {scene.name} in the background (gait-planner prepare)")
            last = ""
            try:
                child = subprocess.Popen(  # noqa: S603  (our own command)
                    [*COMMAND, scene.name], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                    stdin=subprocess.DEVNULL, text=True, env=env, start_new_session=True)
            except OSError as err:
                self._set(scene.name, f"{FAILED} ({err})")
                self._log(f"could not prepare {scene.name}: {err}")
                continue
            self._child = child
            for line in child.stdout:
                last = line.strip()
                if last:
                    self._set(scene.name, last.removeprefix(f"{scene.name}: "))
                    self._log(f"prepare: {last}")
            status = child.wait()
            if self._closed.is_set():
                return
            if status != 0 or not is_prepared(scene):
                self._set(scene.name, f"{FAILED} (exit status {status}: {last})")
                self._log(f"preparing {scene.name} failed (exit status {status}): {last}")
        if self._scenes:
            self._log("background preparation ended: " + self.status().message)
