"""Scene loading: the shipped scenes, every validation rule, scene lookup and caching."""

from __future__ import annotations

import copy
import dataclasses
import logging
import math
import os
import re
import tempfile
from pathlib import Path
from types import MappingProxyType

import pytest
import yaml
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from gait_planner.model import loader
from gait_planner.model.loader import (SceneError, available_scenes, find_scene, load_scene,
                                       load_scene_file, scene_dirs)
from gait_planner.model.scene import JointType, RootType

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"


class _Delete:
    """The value that deletes a key (`set_path`); its repr names the test case stably."""

    def __repr__(self) -> str:
        return "DELETE"


DELETE = _Delete()
_YAML_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_YAML_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
_PARSED: dict[str, dict] = {}


def scene_data(name: str = "walker3d") -> dict:
    """A fresh copy of a shipped scene file's parsed YAML without its other gaits (they
    are test_gaits.py's), to break and dump."""
    if name not in _PARSED:
        _PARSED[name] = yaml.load((SCENES / f"{name}.yaml").read_text(), Loader=_YAML_LOADER)
        _PARSED[name].pop("gaits", None)
    return copy.deepcopy(_PARSED[name])


def write(directory: Path, data, name: str = "walker3d") -> Path:
    path = Path(directory) / f"{name}.yaml"
    path.write_text(yaml.dump(data, Dumper=_YAML_DUMPER, sort_keys=False))
    return path


def set_path(data, path: str, value) -> None:
    """Set (DELETE: remove) the entry at a key path such as "bodies[2].inertia[0]";
    a callable `value` edits the whole scene instead."""
    if callable(value):
        return value(data)
    *parents, last = [int(t[1:-1]) if t[0] == "[" else t
                      for t in re.findall(r"\[\d+\]|[^.\[]+", path)]
    for step in parents:
        data = data[step]
    if value is DELETE:
        del data[last]
    else:
        data[last] = value


def error_of(directory: Path, data, name: str = "walker3d") -> str:
    with pytest.raises(SceneError) as info:
        load_scene_file(write(directory, data, name))
    return str(info.value)


# ---------------------------------------------------------------------------- shipped scenes


def upright_world_points(scene) -> dict[tuple[str, str], tuple[float, ...]]:
    """Forward kinematics of the upright pose: every body's directors = world axes."""
    pose = scene.initial_pose
    assert pose.root_angles == (0.0, 0.0, 0.0) and not pose.joint_angles
    com = {scene.root.body: pose.root_position}
    for joint in scene.joints:  # tree order: the parent's COM is known
        rho_p = scene.body(joint.parent).points[joint.parent_point]
        rho_c = scene.body(joint.child).points[joint.child_point]
        com[joint.child] = tuple(p + a - b for p, a, b in zip(com[joint.parent], rho_p, rho_c))
    return {(b.name, point): tuple(c + x for c, x in zip(com[b.name], vec))
            for b in scene.bodies for point, vec in b.points.items()}


@pytest.mark.parametrize("name, bodies, joints, contacts, phases, dof", [
    ("walker3d", 7, 6, 4, 5, 20), ("walker2d", 7, 6, 4, 5, 9), ("compass", 2, 1, 2, 2, 4)])
def test_shipped_scene(name, bodies, joints, contacts, phases, dof):
    scene = load_scene(name)
    assert scene.name == name and scene.source == (SCENES / f"{name}.yaml").read_text()
    assert (len(scene.bodies), len(scene.joints), len(scene.contacts)) == (bodies, joints, contacts)
    assert len(scene.gait.phases) == phases
    assert scene.root.dof + sum(j.dof for j in scene.joints) == dof
    placed = {scene.root.body}  # joints in tree order: each parent placed before its child
    for joint in scene.joints:
        assert joint.parent in placed and joint.child not in placed
        placed.add(joint.child)
    assert placed == {b.name for b in scene.bodies}
    world = upright_world_points(scene)  # the initial pose stands on the ground
    for contact in scene.contacts:
        assert world[(contact.body, contact.point)][2] == pytest.approx(0.0, abs=1e-12)
    assert min(point[2] for point in world.values()) > -1e-12
    for joint in scene.joints:  # the joint points coincide
        assert world[(joint.parent, joint.parent_point)] == pytest.approx(
            world[(joint.child, joint.child_point)], abs=1e-12)


def test_walker3d_matches_the_paper():
    scene = load_scene("walker3d")
    assert [b.name for b in scene.bodies] == [
        "torso", "thigh_r", "calf_r", "foot_r", "thigh_l", "calf_l", "foot_l"]
    assert scene.root.body == "torso" and scene.root.type is RootType.FREE
    assert scene.body("thigh_l").mass == 6.5233
    assert scene.body("torso").inertia == (1.6194, 1.0876, 0.3785)
    assert scene.body("foot_r").points["ankle"] == (-0.0644, 0.0, 0.0502)
    assert [c.name for c in scene.contacts] == [
        "foot_r_heel", "foot_r_forefoot", "foot_l_heel", "foot_l_forefoot"]
    world = upright_world_points(scene)
    assert world[("foot_r", "ankle")] == pytest.approx((0.0, -0.0936, 0.0635), abs=1e-12)
    assert world[("foot_l", "heel")] == pytest.approx((-0.1030 + 0.0644, 0.0936, 0.0), abs=1e-12)
    assert world[("thigh_r", "hip")][2] == pytest.approx(0.8970, abs=1e-12)
    gait = scene.gait
    assert [(p.name, p.contacts, p.scaling, p.intervals) for p in gait.phases] == [
        ("right_full", ("foot_r_heel", "foot_r_forefoot"), 0, 8),
        ("right_forefoot", ("foot_r_forefoot",), 1, 8),
        ("double_heel", ("foot_r_forefoot", "foot_l_heel"), 2, 8),
        ("double_full", ("foot_r_forefoot", "foot_l_heel", "foot_l_forefoot"), 3, 8),
        ("left_full", ("foot_l_heel", "foot_l_forefoot"), 0, 8),
    ]
    assert gait.n_scalings == 4
    assert (gait.step_length, gait.base_time_step) == (0.6338, 0.01)
    assert gait.scaling_bounds == (0.5, 1.5)
    assert (gait.friction_coefficient, gait.cost) == (0.8, "kinetic_energy")
    # the posture the paper does not state: declared path constraints, mirror-symmetric
    assert gait.options["torso_lean_max"] == 5  # degrees, like the joint ranges
    limits = gait.options["joint_limits"]
    assert len(limits) == 14
    for name, bounds in limits.items():
        side, other = ("_r_", "_l_") if "_r_" in name or name.endswith("_r") else ("_l_", "_r_")
        partner = (name + "_").replace(side, other)[:-1]
        assert tuple(limits[partner]) == tuple(bounds)
    pairs = {"torso": "torso", "thigh_r": "thigh_l", "calf_r": "calf_l", "foot_r": "foot_l"}
    assert dict(gait.mirror) == {**pairs, **{v: k for k, v in pairs.items()}}


def test_joint_types_and_angle_names():
    w3, w2, compass = load_scene("walker3d"), load_scene("walker2d"), load_scene("compass")
    spherical, revolute = JointType.SPHERICAL, JointType.REVOLUTE
    assert [j.type for j in w3.joints] == [spherical, revolute, spherical] * 2
    assert w3.joints[0].angle_names == ("hip_r_pitch", "hip_r_roll", "hip_r_yaw")
    assert w3.joints[1].angle_names == ("knee_r",) and w3.joints[1].axis == (0.0, 1.0, 0.0)
    assert w3.joints[0].axis is None
    assert all(j.type is revolute and j.axis == (0.0, 1.0, 0.0) for j in w2.joints)
    assert [j.angle_names for j in w2.joints] == [(j.name,) for j in w2.joints]
    assert w2.planar and compass.planar and not w3.planar
    assert compass.joints[0].angle_names == ("hip",)


def test_every_walking_scene_declares_its_posture():
    """Upright in every scene: the walkers keep the torso within 5 deg of vertical and the
    knees bent or straight, never hyperextended; the compass (no torso, no knees) bounds
    its hip. Every range is a valid one of the scene (the loader checked it)."""
    for name in ("walker3d", "walker2d"):
        scene = load_scene(name)
        options = scene.gait.options
        assert options["torso_lean_max"] == 5
        limits = options["joint_limits"]
        for knee in ("knee_r", "knee_l"):
            assert tuple(limits[knee]) == (0, 75)
        for side in ("r", "l"):  # the sagittal ranges agree between the scenes
            suffix = "_pitch" if name == "walker3d" else ""
            assert tuple(limits[f"hip_{side}{suffix}"]) == (-45, 25)
            assert tuple(limits[f"ankle_{side}{suffix}"]) == (-30, 45)
        assert set(limits) == {n for j in scene.joints for n in j.angle_names}
    compass = load_scene("compass").gait.options
    assert "torso_lean_max" not in compass and tuple(compass["joint_limits"]["hip"]) == (-60, 60)


def test_joints_are_reordered_depth_first(tmp_path):
    data = scene_data()
    data["joints"] = [data["joints"][i] for i in (5, 2, 4, 1, 3, 0)]
    scene = load_scene_file(write(tmp_path, data))
    assert [j.name for j in scene.joints] == [
        "hip_l", "knee_l", "ankle_l", "hip_r", "knee_r", "ankle_r"]  # children in file order
    assert [b.name for b in scene.bodies][:2] == ["torso", "thigh_r"]  # body order kept


def test_scene_is_frozen_and_converted(tmp_path):
    data = scene_data()
    data["bodies"][1]["inertia"] = [1, 1, 1]
    data["bodies"][4]["inertia"] = [1, 1, 1]
    data["joints"][1]["axis"] = [0, 2, 0]
    data["initial_pose"]["joint_angles"] = {"knee_r": [0.1], "hip_l": [0, 0.2, 0.3]}
    data["gait"]["options"] = {"weights": {"torque": 1e-3}, "knee_range": [0, 2], "on": True}
    del data["gravity"], data["description"], data["gait"]["cost"]
    scene = load_scene_file(write(tmp_path, data))
    assert scene.bodies[1].inertia == (1.0, 1.0, 1.0)
    assert all(type(v) is float for v in scene.bodies[1].inertia)
    assert scene.joints[1].axis == (0.0, 1.0, 0.0)
    assert scene.initial_pose.joint_angles == {"knee_r": (0.1,), "hip_l": (0.0, 0.2, 0.3)}
    assert (scene.gravity, scene.description, scene.gait.cost) == (9.81, "", "kinetic_energy")
    options = scene.gait.options
    assert isinstance(options, MappingProxyType)
    assert isinstance(options["weights"], MappingProxyType)
    assert options["knee_range"] == (0, 2) and options["on"] is True
    for mapping in (scene.bodies[0].points, scene.initial_pose.joint_angles, scene.gait.mirror):
        with pytest.raises(TypeError):
            mapping["x"] = (0.0, 0.0, 0.0)  # type: ignore[index]
    with pytest.raises(dataclasses.FrozenInstanceError):
        scene.bodies[0].mass = 1.0  # type: ignore[misc]
    del data["gait"]
    assert load_scene_file(write(tmp_path, data)).gait is None


# ---------------------------------------------------------------------------- inertia


def test_non_realisable_torso_is_refused_without_opt_in(tmp_path):
    data = scene_data()
    data["allow_nonphysical_inertia"] = False
    message = error_of(tmp_path, data)
    assert message.startswith("walker3d.yaml: bodies[0].inertia: body 'torso'")
    assert "non-realisable" in message and "E1 = -0.07665 < 0" in message
    assert "allow_nonphysical_inertia: true" in message
    del data["allow_nonphysical_inertia"]  # the default is to refuse
    assert "non-realisable" in error_of(tmp_path, data)


def test_non_realisable_torso_is_noted_with_opt_in_once_per_process(tmp_path, caplog,
                                                                   monkeypatch):
    monkeypatch.setattr(loader, "_warned", set())  # as in a new process
    with caplog.at_level(logging.INFO, logger="gait_planner.model"):
        scene = load_scene_file(write(tmp_path, scene_data()))
        load_scene_file(tmp_path / "walker3d.yaml")  # read again, e.g. by another part
        monkeypatch.setenv("GAIT_PLANNER_SCENE_PATH", str(tmp_path))
        load_scene("walker3d")
    assert scene.body("torso").euler_tensor[0] == pytest.approx(-0.07665)
    records = [r for r in caplog.records if r.name == "gait_planner.model"]
    # the file chose it: an INFO note (not repeated by every command), once per process
    assert len(records) == 1 and records[0].levelno == logging.INFO
    assert "'torso'" in records[0].getMessage() and "E1 = -0.07665" in records[0].getMessage()


@settings(max_examples=60, deadline=None)
@given(mass=st.floats(1e-3, 1e3), j2=st.floats(1e-4, 10.0), j3=st.floats(1e-4, 10.0),
       t=st.floats(0.0, 1.0), order=st.permutations([0, 1, 2]))
def test_any_realisable_inertia_loads(mass, j2, j3, t, order):
    j1 = abs(j2 - j3) + t * (j2 + j3 - abs(j2 - j3))  # |J2 - J3| <= J1 <= J2 + J3
    assume(j1 > 0.0)
    inertia = [[j1, j2, j3][i] for i in order]
    data = scene_data()
    data["allow_nonphysical_inertia"] = False
    data["bodies"][0].update(mass=mass, inertia=inertia)
    with tempfile.TemporaryDirectory() as directory:
        torso = load_scene_file(write(Path(directory), data)).body("torso")
    assert torso.mass == mass and torso.inertia == tuple(inertia)


# ---------------------------------------------------------------------------- validation rules

def _swap_hip_r(data):  # torso becomes the child of thigh_r
    data["joints"][0].update(parent="thigh_r", parent_point="hip", child="torso",
                             child_point="hip_r")


def _loop(data):  # thigh_l hangs from foot_l: thigh_l -> calf_l -> foot_l -> thigh_l
    data["joints"][3].update(parent="foot_l", parent_point="heel")


# (key path, new value or DELETE, expected "key path: reason" fragment)
SET_CASES = [
    ("bodies", DELETE, "bodies: required key is missing"),
    ("colour", "red", "colour: unknown key"),
    ("bodies[2].masss", 1.0, "bodies[2].masss: unknown key (allowed keys: name, mass, inertia"),
    ("bodies[1].inertia", DELETE, "bodies[1].inertia: required key is missing"),
    ("bodies[2].mass", -1.0, "walker3d.yaml: bodies[2].mass: must be a positive number, got -1.0"),
    ("bodies[2].mass", 0, "bodies[2].mass: must be a positive number, got 0.0"),
    ("bodies[2].mass", True, "bodies[2].mass: must be a number, got true (a boolean)"),
    ("bodies[1].inertia[2]", 0.0, "bodies[1].inertia[2]: must be a positive number"),
    ("bodies[1].inertia", [1.0, 1.0], "bodies[1].inertia: must be a list of 3 numbers, got 2"),
    ("bodies[1].points.knee", [0.0, 0.0], "bodies[1].points.knee: must be a list of 3 numbers"),
    ("bodies[1].length", -0.1, "bodies[1].length: must be a number >= 0.0, got -0.1"),
    ("bodies[1].name", "thigh r", "bodies[1].name: must be a name"),
    ("bodies[4].name", "thigh_r", "bodies[4].name: duplicate body name 'thigh_r'"),
    ("bodies", [], "bodies: must list at least one body"),
    ("gravity", -9.81, "gravity: must be a number >= 0.0"),
    ("name", 3, "name: must be a string"),
    ("name", "../walker", "name: must be letters, digits, '_' and '-' (it names recordings), "
                          "got '../walker'"),
    ("allow_nonphysical_inertia", "yes", "allow_nonphysical_inertia: must be true or false"),
    ("root.body", "pelvis", "root.body: unknown body 'pelvis' (known: torso"),
    ("root.type", "floating", "root.type: must be one of free, planar, got 'floating'"),
    ("joints[4].name", "hip_r", "joints[4].name: duplicate joint name 'hip_r'"),
    ("joints[1].name", "hip_r_pitch", "joints[1].name: its angle name 'hip_r_pitch' clashes"),
    ("joints[0].type", "hinge", "joints[0].type: must be one of spherical, revolute"),
    ("joints[1].child", "shin_r", "joints[1].child: unknown body 'shin_r'"),
    ("joints[1].parent_point", "kne", "joints[1].parent_point: body 'thigh_r' has no point 'kne'"),
    ("joints[1].axis", DELETE, "joints[1].axis: a revolute joint needs an axis"),
    ("joints[1].axis", [0, 0, 0], "joints[1].axis: must not have (near) zero length"),
    ("joints[1].axis", [1e-12, 0, 0], "joints[1].axis: must not have (near) zero length"),
    ("joints[0].axis", [0, 1, 0], "joints[0].axis: a spherical joint takes no axis"),
    ("joints[2].limit", 1.0, "joints[2].limit: unknown key"),
    ("joints[5]", DELETE, "joints: body 'foot_l' is not connected: no joint has it as child"),
    ("joints[1].child", "thigh_r", "joints[1].child: a joint cannot connect body 'thigh_r' to"),
    ("joints[3].child", "thigh_r", "joints[3].child: body 'thigh_r' is already the child of joint"),
    ("", _swap_hip_r, "joints[0].child: the root body 'torso' cannot be a joint's child"),
    ("", _loop, "joints: the joints form a loop not connected to the root 'torso': "
                "thigh_l -> calf_l -> foot_l -> thigh_l"),
    ("contacts[1].name", "foot_r_heel", "contacts[1].name: duplicate contact name"),
    ("contacts[0].body", "shoe_r", "contacts[0].body: unknown body 'shoe_r'"),
    ("contacts[0].point", "toe", "contacts[0].point: body 'foot_r' has no point 'toe'"),
    ("initial_pose.root_position", [0, 1.1], "initial_pose.root_position: must be a list of 3"),
    ("initial_pose.joint_angles", {"elbow": [0]}, "joint_angles.elbow: unknown joint 'elbow'"),
    ("initial_pose.joint_angles", {"knee_r": [0, 0]},
     "initial_pose.joint_angles.knee_r: revolute joint 'knee_r' takes 1 angle ['knee_r'], got 2"),
    ("initial_pose.joint_angles", {"hip_r": [0]}, "hip_r: spherical joint 'hip_r' takes 3 angles"),
    ("gait.step_length", 0.0, "gait.step_length: must be a positive number"),
    ("gait.base_time_step", -0.01, "gait.base_time_step: must be a positive number"),
    ("gait.scaling_bounds", [0.0, 1.5], "gait.scaling_bounds[0]: the lower scaling bound must be"),
    ("gait.scaling_bounds", [1.5, 0.5], "gait.scaling_bounds[1]: the upper scaling bound must be"),
    ("gait.scaling_bounds", [1.0], "gait.scaling_bounds: must be a list of 2 numbers"),
    ("gait.friction_coefficient", 0, "gait.friction_coefficient: must be a positive number"),
    ("gait.phases", [], "gait.phases: must list at least one phase"),
    ("gait.phases", DELETE, "gait.phases: required key is missing"),
    ("gait.cost", 3, "gait.cost: must be a string, got 3"),
    ("gait.phases[1].name", "right_full", "gait.phases[1].name: duplicate phase name"),
    ("gait.phases[1].contacts[0]", "toe", "gait.phases[1].contacts[0]: unknown contact 'toe'"),
    ("gait.phases[3].contacts[1]", "foot_r_forefoot", "gait.phases[3].contacts[1]: duplicate"),
    ("gait.phases[0].intervals", 0, "gait.phases[0].intervals: must be an integer >= 1, got 0"),
    ("gait.phases[0].intervals", 2.5, "gait.phases[0].intervals: must be an integer, got 2.5"),
    ("gait.phases[0].scaling", -1, "gait.phases[0].scaling: must be an integer >= 0, got -1"),
    ("gait.phases[0].scaling", 1.0, "gait.phases[0].scaling: must be an integer, got 1.0"),
    ("gait.phases[3].scaling", 5,
     "gait.phases: the phase scaling indices must use every index from 0 to 5; index 3 is unused"),
    ("gait.phases[2].dwell", 1, "gait.phases[2].dwell: unknown key"),
    ("gait.mirror", {"thigh_r": "shin_l"}, "gait.mirror.thigh_r: unknown body 'shin_l'"),
    ("gait.mirror", {"arm_r": "thigh_l"}, "gait.mirror.arm_r: unknown body 'arm_r'"),
    ("gait.mirror", {"thigh_r": "thigh_l", "calf_r": "thigh_l"},
     "gait.mirror.calf_r: body 'thigh_l' cannot mirror onto both 'thigh_r' and 'calf_r'"),
    ("bodies[4].mass", 7.0, "gait.mirror.thigh_r: mirror images need equal mass and inertia"),
    ("bodies[6].inertia[0]", 0.0035, "gait.mirror.foot_r: mirror images need equal mass"),
    ("gait.options", {"w": None}, "gait.options.w: must be a finite number, string, boolean"),
    ("gait.options", {"a": {"b": [1, math.nan]}}, "gait.options.a.b[1]: must be a finite number"),
    ("gait.options", [1], "gait.options: must be a mapping, got a list of 1"),
    ("gait", [1], "gait: must be a mapping, got a list of 1"),
    # posture options (gait_planner.model.posture), in degrees, checked when the scene loads
    ("gait.options.torso_lean_max", 90,
     "walker3d.yaml: gait.options.torso_lean_max: must be in [0, 90) degrees, got 90.0"),
    ("gait.options.torso_lean_max", -5, "gait.options.torso_lean_max: must be in [0, 90) deg"),
    ("gait.options.torso_lean_max", "5 deg",
     "gait.options.torso_lean_max: must be a number of degrees, got '5 deg'"),
    ("gait.options.joint_limits.knee_r", [75, 0],
     "walker3d.yaml: gait.options.joint_limits.knee_r: need finite lower < upper within 180 "
     "deg, got [75.0, 0.0]"),
    ("gait.options.joint_limits.knee_r", [-100, 100], "joint_limits.knee_r: need finite lower"),
    ("gait.options.joint_limits.knee_r", [170, 200],
     "gait.options.joint_limits.knee_r: bounds must lie in [-180, 180] deg, got [170.0, 200.0]"),
    ("gait.options.joint_limits.knee_r", [0, True], "joint_limits.knee_r: need [lower, upper]"),
    ("gait.options.joint_limits.knee_r", [0, 10, 20], "joint_limits.knee_r: need [lower, upper]"),
    ("gait.options.joint_limits.knee_r", "straight", "joint_limits.knee_r: need [lower, upper]"),
    ("gait.options.joint_limits.hip_r_roll", [-95, 10],
     "gait.options.joint_limits.hip_r_roll: a roll range must lie in [-90, 90] deg"),
    ("gait.options.joint_limits.elbow", [0, 10],
     "gait.options.joint_limits: 'elbow' is not a joint angle of scene 'walker3d'; known: "
     "hip_r_pitch"),
    ("gait.options.joint_limits", [0, 75], "gait.options.joint_limits: need a mapping"),
    ("bodies[2].collision[0]", [0, 0, 0],
     "walker3d.yaml: bodies[2].collision[0]: must be a list of 4 numbers, got 3 entries"),
    ("bodies[2].collision[1]", [0, 0, 0, -0.01],
     "walker3d.yaml: bodies[2].collision[1][3]: must be a positive number, got -0.01"),
    ("bodies[2].collision", {"x": 1}, "walker3d.yaml: bodies[2].collision: must be a list"),
]


@pytest.mark.parametrize("path, value, expected", SET_CASES,
                         ids=[f"{p}={getattr(v, '__name__', v)!r}"[:60] for p, v, _ in SET_CASES])
def test_validation_rule(tmp_path, path, value, expected):
    data = scene_data()
    set_path(data, path, value)
    assert expected in error_of(tmp_path, data)


@pytest.mark.parametrize("path, value, expected", [
    ("joints[0].type", "spherical", "joints[0].type: a planar scene allows only revolute"),
    ("joints[1].axis", [1, 0, 0], "joints[1].axis: a planar scene allows only revolute joints"),
    ("initial_pose.root_angles", [0.1, 0, 0], "initial_pose.root_angles[0]: a planar root turns"),
    ("initial_pose.root_angles", [0, 0, 0.1], "initial_pose.root_angles[2]: a planar root turns"),
    ("gait.options.joint_limits.hip_r_pitch", [-45, 25],
     "walker2d.yaml: gait.options.joint_limits: 'hip_r_pitch' is not a joint angle of scene "
     "'walker2d'; known: hip_r, knee_r, ankle_r, hip_l, knee_l, ankle_l"),
    ("gait.options.joint_limits.knee_l", [0, 180], "joint_limits.knee_l: need finite lower"),
    ("gait.options.torso_lean_max", 100,
     "torso_lean_max: must be in [0, 90) degrees, got 100.0"),
    ("bodies[2].collision", [[0.0, 0.0, 0.0, 0.05]],
     "walker2d.yaml: bodies[2].collision: a planar scene's legs move in one plane"),
])
def test_planar_rules(tmp_path, path, value, expected):
    data = scene_data("walker2d")
    set_path(data, path, value)
    if value == "spherical":
        del data["joints"][0]["axis"]
    assert expected in error_of(tmp_path, data, "walker2d")


@pytest.mark.parametrize("old, new, expected", [
    ("hip: [0.0, 0.0, 0.1779], knee:", "hip: [0.0, 0.0, 0.1779], hip: [0, 0, 0.2], knee:",
     "walker3d.yaml: bodies[1].points.hip: is given more than once"),
    ("gravity: 9.81", "gravity: 9.81\ngravity: 9.8", "walker3d.yaml: gravity: is given more"),
    ("root: {body: torso", "root: {body: [torso", "walker3d.yaml: is not valid YAML"),
])
def test_text_level_errors(tmp_path, old, new, expected):
    text = (SCENES / "walker3d.yaml").read_text()
    assert old in text
    path = tmp_path / "walker3d.yaml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(SceneError, match=re.escape(expected)):
        load_scene_file(path)


def test_top_level_must_be_a_mapping(tmp_path):
    assert "walker3d.yaml: (top level): must be a mapping" in error_of(tmp_path, [1, 2])
    assert "(top level): must be a mapping, got null" in error_of(tmp_path, None)


def numeric_paths(data, path: str = "") -> list[str]:
    if isinstance(data, dict):
        items = [(f"{path}.{k}" if path else k, v) for k, v in data.items()]
    elif isinstance(data, list):
        items = [(f"{path}[{i}]", v) for i, v in enumerate(data)]
    else:
        return [path] if isinstance(data, (int, float)) and not isinstance(data, bool) else []
    return [p for sub, value in items for p in numeric_paths(value, sub)]


def data_with_options() -> dict:
    data = scene_data()
    data["initial_pose"]["joint_angles"] = {"knee_r": [0.1], "hip_l": [0.0, 0.1, 0.2]}
    data["gait"]["options"] = {"torque_weight": 1e-3, "knee": {"range": [0.0, 2.0]}}
    return data


NUMERIC_PATHS = numeric_paths(data_with_options())
assert {"gravity", "bodies[6].points.forefoot[2]", "joints[1].axis[1]", "gait.phases[4].intervals",
        "initial_pose.joint_angles.hip_l[2]", "gait.options.knee.range[1]"} <= set(NUMERIC_PATHS)


@settings(max_examples=80, deadline=None)
@given(path=st.sampled_from(NUMERIC_PATHS),
       value=st.sampled_from([math.nan, math.inf, -math.inf]))
def test_non_finite_numbers_are_refused_naming_the_key(path, value):
    data = data_with_options()
    set_path(data, path, value)
    with tempfile.TemporaryDirectory() as directory:
        message = error_of(Path(directory), data)
    assert f"walker3d.yaml: {path}: " in message


# ---------------------------------------------------------------------------- finding scenes


def test_scene_dirs_and_available_scenes(monkeypatch, tmp_path):
    monkeypatch.delenv("GAIT_PLANNER_SCENE_PATH", raising=False)
    assert SCENES.resolve() in scene_dirs()
    assert {"walker3d", "walker2d", "compass"} <= set(available_scenes())
    first, second = tmp_path / "a", tmp_path / "b"
    first.mkdir(), second.mkdir()
    monkeypatch.setenv("GAIT_PLANNER_SCENE_PATH",
                       f"{first}{os.pathsep}{tmp_path / 'missing'}{os.pathsep}{second}")
    dirs = scene_dirs()
    assert dirs[:2] == (first.resolve(), second.resolve()) and SCENES.resolve() in dirs
    data = scene_data("compass")
    data["name"] = "tiny_compass"
    write(second, data, "tiny_compass")
    assert "tiny_compass" in available_scenes()
    assert load_scene("tiny_compass").name == "tiny_compass"
    shadow = scene_data("compass")
    shadow["description"] = "shadowed"
    write(first, shadow, "compass")  # earlier folders win
    assert load_scene("compass").description == "shadowed"


def test_load_scene_caches_by_mtime(monkeypatch, tmp_path):
    monkeypatch.setenv("GAIT_PLANNER_SCENE_PATH", str(tmp_path))
    path = write(tmp_path, scene_data("compass"), "compass")
    scene = load_scene("compass")
    assert load_scene("compass") is scene
    data = scene_data("compass")
    data["description"] = "changed"
    write(tmp_path, data, "compass")
    stat = path.stat()
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))
    assert load_scene("compass").description == "changed"


@pytest.mark.parametrize("name", ["", "..", "../walker3d", "walker3d.yaml", "config/walker3d",
                                  "/etc/passwd", " walker3d", "walker3d\n"])
def test_scene_names_must_be_bare(name):
    with pytest.raises(SceneError, match="bare names") as info:
        load_scene(name)
    assert "walker3d" in str(info.value).split("available scenes:")[1]
    # how to plan a scene file from elsewhere by name (the node's requests)
    assert "GAIT_PLANNER_SCENE_PATH" in str(info.value) and "scene_dirs" in str(info.value)


def test_unknown_scene_lists_the_available_ones():
    with pytest.raises(SceneError, match=r"unknown scene 'nope'; available scenes: .*walker3d"):
        load_scene("nope")


@settings(max_examples=150, deadline=None)
@given(name=st.one_of(st.text(max_size=30), st.from_regex(r"[A-Za-z0-9_-]{1,12}", fullmatch=True),
                      st.sampled_from(["walker3d", "compass", "walker2d", "../compass"])))
def test_junk_scene_names_are_refused_unless_available(name):
    if name in available_scenes():
        assert load_scene(name).name == name
    else:
        with pytest.raises(SceneError):
            load_scene(name)


# ---------------------------------------------------------------------------- scenes from anywhere


def test_a_copied_scene_loads_under_any_file_name_and_keeps_its_name(tmp_path):
    """No name-stem rule: the file name finds a scene, `name` names it (in recordings)."""
    data = scene_data("compass")
    data["gravity"] = 9.0
    scene = load_scene_file(write(tmp_path, data, "my copy"))
    assert scene.name == "compass" and scene.gravity == 9.0


def test_scenes_named_alike_never_share_a_problem_or_a_library_entry(tmp_path):
    """The planner's problems and the warm-start store are keyed by the scene's text, so a copy
    named like a shipped scene but changed gets its own (the compiled cache is keyed by the
    Functions themselves, `ocp.compile`)."""
    from gait_planner.ocp.warm_starts import WarmStartStore
    from gait_planner.ocp.settings import settings_for
    from gait_planner.ocp.solve import _key

    data = scene_data("compass")
    data["gravity"] = 9.0
    copy_ = load_scene_file(write(tmp_path, data, "lighter"))
    shipped = load_scene("compass")
    assert copy_.name == shipped.name
    settings = settings_for(shipped)
    assert _key(copy_, settings) != _key(shipped, settings)
    assert WarmStartStore.key(copy_.source, settings, 1, 1) != WarmStartStore.key(
        shipped.source, settings, 1, 1)


def test_find_scene_takes_a_path_or_a_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    data = scene_data("compass")
    data["description"] = "from a path"
    write(tmp_path, data, "elsewhere")
    (tmp_path / "short.yml").write_text((tmp_path / "elsewhere.yaml").read_text())
    assert find_scene(str(tmp_path / "elsewhere.yaml")).description == "from a path"
    assert find_scene("elsewhere.yaml").description == "from a path"  # relative
    assert find_scene("short.yml").description == "from a path"
    assert find_scene("compass") is load_scene("compass")


@pytest.mark.parametrize("given, words", [
    ("missing.yaml", "missing.yaml: no such scene file (not found at "),
    ("folder.yaml", "folder.yaml: no such scene file (a folder at "),
    ("broken.yaml", "broken.yaml: gravity: must be a number >= 0.0"),
    ("../compass", "scenes are bare names (letters, digits, '_' and '-', no path) or paths "
                   "to a scene file ending in .yaml or .yml, got '../compass'"),
    ("nope", "unknown scene 'nope'; available scenes: "),
])
def test_find_scene_errors_name_the_file_and_the_rule(tmp_path, monkeypatch, given, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder.yaml").mkdir()
    data = scene_data("compass")
    data["gravity"] = -1.0
    write(tmp_path, data, "broken")
    with pytest.raises(SceneError) as info:
        find_scene(given)
    assert str(info.value).startswith(words) or words in str(info.value), str(info.value)


def test_extra_scene_folders_come_first(tmp_path, monkeypatch):
    """The node's scene_dirs: searched before GAIT_PLANNER_SCENE_PATH and config/scenes;
    missing folders are skipped."""
    env = tmp_path / "env"
    env.mkdir()
    monkeypatch.setenv("GAIT_PLANNER_SCENE_PATH", str(env))
    extra = tmp_path / "extra"
    extra.mkdir()
    data = scene_data("compass")
    data["description"] = "extra"
    write(extra, data, "compass")
    write(extra, data, "only_extra")
    data["description"] = "env"
    write(env, data, "compass")
    folders = [str(tmp_path / "missing"), str(extra)]
    assert scene_dirs(folders)[:2] == (extra.resolve(), env.resolve())
    assert load_scene("compass", folders).description == "extra"
    assert load_scene("compass").description == "env"
    assert "only_extra" in available_scenes(folders) and "only_extra" not in available_scenes()
    with pytest.raises(SceneError, match="unknown scene 'only_extra'"):
        load_scene("only_extra")
