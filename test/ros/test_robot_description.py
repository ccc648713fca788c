"""The node's scene lookup with the robot on /robot_description (`RobotScenes`), without ROS:
a URDF is drafted and written beside a copy of itself, requests name it "robot_description"
or by its name, a description that cannot be planned leaves the previous robot and says why."""

from __future__ import annotations

import pytest

from gait_planner.model.loader import SceneError
from gait_planner.model.urdf_errors import UrdfError
from gait_planner.ros.robot_description import ROBOT_SCENE, RobotScenes
from urdf_bipeds import biped


def _files(name: str):
    raise SceneError(f"no scene file {name!r}")


def test_a_description_is_drafted_written_and_looked_up(tmp_path):
    scenes = RobotScenes(_files, lambda: tmp_path)
    with pytest.raises(SceneError, match="no URDF received yet"):
        scenes(ROBOT_SCENE)
    urdf = biped()
    note = scenes.describe(urdf)
    assert "drafted scene 'biped' (8 joints planned, 1 locked)" in note
    folder = tmp_path / ROBOT_SCENE / "biped"
    assert (folder / "robot.urdf").read_text() == urdf
    scene = scenes(ROBOT_SCENE)
    assert scene is scenes("biped") and scene.robot.urdf == urdf
    assert scene.source == (folder / "biped.yaml").read_text()
    assert scenes.describe(urdf) is None  # the same description again: nothing to do
    with pytest.raises(SceneError, match="no scene file 'walker3d'"):
        scenes("walker3d")


def test_an_unplannable_description_keeps_the_previous_robot(tmp_path):
    scenes = RobotScenes(_files, lambda: tmp_path)
    with pytest.raises(UrdfError, match="knee"):
        scenes.describe(biped(knee_type="prismatic"))
    with pytest.raises(SceneError, match="cannot be planned.*knee"):
        scenes(ROBOT_SCENE)
    scenes.describe(biped())
    with pytest.raises(UrdfError):
        scenes.describe("<robot name='broken'>")
    assert scenes(ROBOT_SCENE).name == "biped"


def test_the_mirror_tolerance_is_the_nodes(tmp_path):
    """A right knee 8 % heavier than the left is refused at the default and drafted at 0.1."""
    urdf = biped(right_knee_mass=1.08)
    with pytest.raises(UrdfError, match="mirror"):
        RobotScenes(_files, lambda: tmp_path).describe(urdf)
    scenes = RobotScenes(_files, lambda: tmp_path, mirror_tolerance=0.1)
    assert "drafted scene 'biped'" in scenes.describe(urdf)
