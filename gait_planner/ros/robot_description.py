"""The robot on ``/robot_description``: its URDF drafted into a scene the node plans for.

`RobotScenes` is the node's scene lookup (`gait_planner.problem.SceneLookup`): the scene
``robot_description`` — or the name the draft declares — is the scene drafted from the last
URDF received (`gait_planner.model.urdf_import.draft_scene`), every other name a scene file
(`gait_planner.model.loader.load_scene` in the node's scene_dirs). The node feeds it the
``std_msgs/String`` of ``/robot_description`` (transient local, as robot_state_publisher
publishes it) and its ``robot_description`` parameter. Each new description is drafted and
written, with a copy of the URDF beside it, to
``<output_dir>/robot_description/<name>/<name>.yaml`` and ``robot.urdf`` (the scene's ``robot:``
section names the copy), so the user can read what is planned and
plan it again with ``gait-planner plan --scene``. A description that cannot be planned
(`UrdfError`) leaves the previous robot in place; requests for it then say why. No ROS here:
the node (`gait_planner.ros.node`) wires the topic and the parameter.
"""

from __future__ import annotations

import hashlib
import threading
from pathlib import Path
from typing import Callable, Sequence

from gait_planner.atomic import atomic_target
from gait_planner.model.loader import SceneError, load_scene_file
from gait_planner.model.scene import Scene
from gait_planner.model.urdf_errors import UrdfError

__all__ = ["ROBOT_SCENE", "RobotScenes"]

ROBOT_SCENE = "robot_description"  # the scene name a request gives for the described robot
URDF_FILE = "robot.urdf"  # the copy of the description beside its drafted scene


class RobotScenes:
    """Scene lookup with the described robot (module docstring); thread-safe."""

    def __init__(self, files: Callable[[str], Scene], folder: Callable[[], Path],
                 package_dirs: Sequence[str] = (), mirror_tolerance: float | None = None):
        self._files, self._folder, self._package_dirs = files, folder, list(package_dirs)
        self._options = {} if mirror_tolerance is None else {"mirror_tolerance": mirror_tolerance}
        self._lock = threading.Lock()
        self._scene: Scene | None = None
        self._digest = ""
        self._error = "no URDF received yet on /robot_description (nor in the node's " \
                      "robot_description parameter): is robot_state_publisher running?"

    def describe(self, urdf: str) -> str | None:
        """Draft `urdf` (a URDF text) as the described robot; the log line saying what was
        drafted, or None if it is the description already drafted. UrdfError/SceneError/
        OSError say why it cannot be planned (the previous robot stays)."""
        from gait_planner.model.urdf_import import draft_scene

        digest = hashlib.sha256(urdf.encode()).hexdigest()
        if digest == self._digest:
            return None
        try:
            draft = draft_scene(urdf, package_dirs=self._package_dirs, urdf_file=URDF_FILE,
                                robot_dirs=[str(Path(d).resolve()) for d in self._package_dirs],
                                **self._options)
        except UrdfError as error:
            with self._lock:
                self._error = f"the robot on /robot_description cannot be planned: {error}"
            raise
        folder = self._folder() / ROBOT_SCENE / draft.name
        folder.mkdir(parents=True, exist_ok=True)
        scene_path = folder / f"{draft.name}.yaml"
        with atomic_target(folder / URDF_FILE) as tmp:
            tmp.write_text(urdf, encoding="utf-8")
        with atomic_target(scene_path) as tmp:
            tmp.write_text(draft.yaml, encoding="utf-8")
        scene = load_scene_file(scene_path)
        with self._lock:
            self._scene, self._digest = scene, digest
        return (f"robot_description: drafted scene {draft.name!r} ({len(draft.joints)} joints "
                f"planned, {len(draft.locked)} locked) into {scene_path}; plan it with "
                f"scene {ROBOT_SCENE!r} (its first request builds its problem)")

    def __call__(self, name: str) -> Scene:
        with self._lock:
            scene, error = self._scene, self._error
        if name == ROBOT_SCENE or (scene is not None and name == scene.name):
            if scene is None:
                raise SceneError(error)
            return scene
        return self._files(name)
