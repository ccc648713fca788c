"""Scene files: find them, read them, validate them, return frozen `Scene`s.

Configuration enters here once: `load_scene(name)` (a bare name, looked up in
`scene_dirs()`), `find_scene(name_or_path)` (also a path to a .yaml file: the command
line's --scene) or `load_scene_file(path)` returns a `gait_planner.model.scene.Scene` whose
every field has been checked, or raises `SceneError` naming the file, the key path and the
reason, e.g. ``walker3d.yaml: bodies[2].mass: must be a positive number, got -1.0``. The
bodies, joints, contacts and initial pose are parsed in `gait_planner.model.scene_parts`,
the gait block in `gait_planner.model._validate`.
A scene's warnings are logged once per process; what the file itself acknowledges (a
non-physical inertia under ``allow_nonphysical_inertia: true``) is logged at INFO level only,
so that commands do not repeat it to a user who chose it.

YAML layout (exactly these keys; unknown keys are errors)::

    name: walker3d                    # the scene's name in recordings and messages; the
                                      # file name is what a bare name looks up
    description: "..."                # optional
    gravity: 9.81                     # optional, >= 0
    allow_nonphysical_inertia: false  # optional; true accepts E_i < 0 (noted at INFO level)
    root: {body: torso, type: free}   # free | planar
    bodies:                           # order kept
      - {name: torso, mass: 33.99, inertia: [J1, J2, J3], length: 0.66,  # length optional
         points: {hip_r: [x, y, z]},  # body-fixed, from the COM, director components
         collision: [[x, y, z, r]]}   # optional spheres containing the body (not in a
                                      # planar scene): the legs' clearance rows measure
                                      # them (gait_planner.ocp.legs)
    joints:                           # reordered depth-first from the root
      - {name: hip_r, type: spherical, parent: torso, parent_point: hip_r,
         child: thigh_r, child_point: hip}
      - {name: knee_r, type: revolute, axis: [0, 1, 0], ...}   # axis normalised, in the
                                      # parent's directors; optional reference_rpy:
                                      # [r, p, y] rad, the child's directors in the parent's
                                      # at zero angle (URDF rpy; default aligned)
                                      # a spherical joint's angles are <name>_pitch,
                                      # _roll, _yaw, or its optional angle_names: [p, r, y]
    contacts:
      - {name: foot_r_heel, body: foot_r, point: heel}
    initial_pose:
      root_position: [x, y, z]        # root COM, m
      root_angles: [yaw, pitch, roll] # optional, rad
      joint_angles: {knee_r: [0.1]}   # optional; 3 (pitch, roll, yaw) or 1 angle
    gait:                             # optional
      step_length: 0.6338             # > 0
      base_time_step: 0.01            # > 0
      scaling_bounds: [0.5, 1.5]      # 0 < lower <= upper
      friction_coefficient: 0.8       # > 0
      cost: kinetic_energy            # optional
      mirror: {thigh_r: thigh_l}      # optional; one way suffices, unnamed bodies -> selves
      phases:
        - {name: right_full, contacts: [foot_r_heel], scaling: 0, intervals: 8}
      start:                          # optional: a start from standing, before the first
        - {name: stand, contacts: [...], intervals: 8}   # half cycle (ocp.transition)
      stop:                           # optional: a stop after a half cycle, ending at rest
        - {name: stand, contacts: [...], intervals: 8}
      options: {}                     # optional; passed through to the optimiser, but its
                                      # posture entries (joint_limits, torso_lean_max, in
                                      # degrees) are checked here (gait_planner.model.posture)
    gaits:                            # optional: other gaits, each a change of `gait:`
      run:                            # a request's gait "run" (`gait:` is "walk")
        phases: [...]                 # keys given replace the gait block's; options are
        options: {...}                # merged entry by entry (`with_gait`)
    robot: {urdf: robot.urdf, links: {...}}  # optional: the URDF drafted from
                                      # (`gait_planner.model.robot_source`)

Planar scenes (root type planar) move in the x-z plane: every joint is revolute about
(0, 1, 0), and the initial root angles have yaw = roll = 0.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import re
from pathlib import Path
from typing import Any, Sequence

import yaml

from gait_planner.model._validate import Checker, SceneError, check_gait, join, parse_yaml
from gait_planner.model.posture import PostureError, check_posture
from gait_planner.model.robot_source import check_robot
from gait_planner.model.scene import Root, RootType, Scene
from gait_planner.model.scene_parts import (parse_bodies, parse_contacts, parse_initial_pose,
                                            parse_joints)

__all__ = ["SceneError", "available_scenes", "find_scene", "load_scene", "load_scene_file",
           "scene_from_text",
           "scene_dirs"]

_log = logging.getLogger("gait_planner.model")

SCENE_PATH_ENV = "GAIT_PLANNER_SCENE_PATH"
SCENE_NAME_PATTERN = re.compile(r"[A-Za-z0-9_-]+")
DEFAULT_GAIT = "walk"  # the name of a scene's `gait:` block (`with_gait`)
# what a gait of `gaits:` may change of the `gait:` block (the mirror pairs stay)
_GAIT_CHANGES = ("phases", "step_length", "base_time_step", "scaling_bounds",
                 "friction_coefficient", "cost", "options", "start", "stop")
SCENE_SUFFIXES = (".yaml", ".yml")  # a --scene ending so is a path, anything else a name
_warned: set[str] = set()  # the scene warnings logged so far (each once per process)


# ---------------------------------------------------------------------------- finding files


def scene_dirs(extra: Sequence[str | os.PathLike] = ()) -> tuple[Path, ...]:
    """The folders scenes are loaded from, first match wins.

    The `extra` folders (the node's parameter scene_dirs) first, then the directories in
    $GAIT_PLANNER_SCENE_PATH (os.pathsep separated), then the repository's `config/scenes`
    (next to this package, for source and editable installs), then
    `<share>/gait_planner/config/scenes` if ament_index finds the installed package.
    Only existing directories are listed, each once.
    """
    candidates = [Path(p) for p in extra]
    candidates += [Path(p) for p in os.environ.get(SCENE_PATH_ENV, "").split(os.pathsep) if p]
    candidates.append(Path(__file__).resolve().parents[2] / "config" / "scenes")
    try:
        from ament_index_python.packages import get_package_share_directory

        candidates.append(Path(get_package_share_directory("gait_planner")) / "config" / "scenes")
    except Exception:  # not importable, no AMENT_PREFIX_PATH, or package not installed
        pass
    dirs: list[Path] = []
    for candidate in candidates:
        resolved = candidate.expanduser().resolve()
        if resolved.is_dir() and resolved not in dirs:
            dirs.append(resolved)
    return tuple(dirs)


def available_scenes(extra: Sequence[str | os.PathLike] = ()) -> list[str]:
    """Sorted names of the scenes in `scene_dirs(extra)` (files `<name>.yaml`)."""
    names = {
        p.stem
        for d in scene_dirs(extra)
        for p in d.glob("*.yaml")
        if p.is_file() and SCENE_NAME_PATTERN.fullmatch(p.stem)
    }
    return sorted(names)


_cache: dict[Path, tuple[tuple[int, int], Scene]] = {}


def load_scene(name: str, extra: Sequence[str | os.PathLike] = ()) -> Scene:
    """The scene `name` (a bare name such as "walker3d": the file `<name>.yaml`) from the
    first of `scene_dirs(extra)` holding it.

    Parsed scenes are cached per file and reloaded when the file's mtime or size changes.
    """
    if not isinstance(name, str) or not SCENE_NAME_PATTERN.fullmatch(name):
        raise SceneError(
            f"scene names are bare names (letters, digits, '_' and '-', no path), got {name!r}; "
            f"for a scene file in another folder, add the folder to {SCENE_PATH_ENV} (or to "
            f"the node's parameter scene_dirs) and give the file's name without .yaml; "
            f"available scenes: {_listing(available_scenes(extra))}"
        )
    for directory in scene_dirs(extra):
        path = directory / f"{name}.yaml"
        if path.is_file():
            return _cached(path)
    raise SceneError(f"unknown scene {name!r}; available scenes: "
                     f"{_listing(available_scenes(extra))} (the files NAME.yaml in "
                     f"{', '.join(map(str, scene_dirs(extra))) or 'no scene folder'})")


def find_scene(name_or_path: str) -> Scene:
    """The scene of a command line's --scene: a path to a scene file if it ends in .yaml
    or .yml (relative to the working folder), else a bare name (`load_scene`)."""
    if not str(name_or_path).endswith(SCENE_SUFFIXES):
        if not SCENE_NAME_PATTERN.fullmatch(str(name_or_path)):
            raise SceneError(
                f"scenes are bare names (letters, digits, '_' and '-', no path) or paths to "
                f"a scene file ending in .yaml or .yml, got {name_or_path!r}; "
                f"available scenes: {_listing(available_scenes())}")
        return load_scene(name_or_path)
    path = Path(name_or_path).expanduser()
    if not path.is_file():
        raise SceneError(f"no such scene file ({'a folder' if path.is_dir() else 'not found'}"
                         f" at {path.resolve()})", file=str(name_or_path))
    try:
        return _cached(path.resolve())
    except SceneError as error:  # name the file as it was given, not only its name
        raise SceneError(error.reason, file=str(name_or_path), key=error.key) from None


def _cached(path: Path) -> Scene:
    stat = path.stat()
    stamp = (stat.st_mtime_ns, stat.st_size)
    cached = _cache.get(path)
    if cached is not None and cached[0] == stamp:
        return cached[1]
    scene = load_scene_file(path)
    _cache[path] = (stamp, scene)
    return scene


def _listing(names: list[str]) -> str:
    return ", ".join(names) if names else "none (no scene folder found)"


def load_scene_file(path: str | os.PathLike) -> Scene:
    """Read, validate and build the scene in the YAML file `path` (not cached)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(f"cannot be read: {error}", file=str(path)) from None
    return scene_from_text(text, path.name, path.parent)


def scene_from_text(text: str, file: str, folder: str | os.PathLike | None = None) -> Scene:
    """Validate and build the scene whose YAML is `text`; `file` names it in errors (e.g. a
    recording's scene attachment); `folder` resolves the relative paths of its ``robot:``
    section (None: its URDF is not read, `RobotSource.urdf` is "")."""
    return _build_scene(parse_yaml(text, file), file, text,
                        None if folder is None else Path(folder))


# ---------------------------------------------------------------------------- the schema


def _build_scene(data: Any, file: str, source: str, folder: Path | None = None) -> Scene:
    c = Checker(file)
    top = c.mapping(
        data,
        "",
        required=("name", "root", "bodies", "joints", "contacts", "initial_pose"),
        optional=("description", "gravity", "allow_nonphysical_inertia", "gait", "gaits",
                  "robot"),
    )
    name = c.string(top["name"], "name")
    if not SCENE_NAME_PATTERN.fullmatch(name):  # it starts the file names of recordings
        c.fail("name", f"must be letters, digits, '_' and '-' (it names recordings), got {name!r}")
    description = c.string(top.get("description", ""), "description")
    gravity = c.number(top.get("gravity", 9.81), "gravity", minimum=0.0)
    allow = c.boolean(top.get("allow_nonphysical_inertia", False), "allow_nonphysical_inertia")

    bodies = parse_bodies(c, top["bodies"], allow)
    root_map = c.mapping(top["root"], "root", required=("body", "type"))
    root_body = c.name(root_map["body"], "root.body")
    c.known(root_body, "root.body", [b.name for b in bodies], "body")
    root = Root(body=root_body, type=c.choice(root_map["type"], "root.type", RootType))
    for i, body in enumerate(bodies):
        if body.collision and root.type is RootType.PLANAR:
            c.fail(join(join("bodies", i), "collision"),
                   "a planar scene's legs move in one plane, one drawn over the other: a "
                   "clearance between them is meaningless, and the planner keeps none")
    joints = parse_joints(c, top["joints"], bodies, root)
    contacts = parse_contacts(c, top["contacts"], bodies)
    pose = parse_initial_pose(c, top["initial_pose"], joints, root)
    gait = check_gait(c, top["gait"], bodies, contacts) if "gait" in top else None
    robot = check_robot(c, top["robot"], bodies, folder) if "robot" in top else None
    scene = Scene(
        name=name,
        bodies=bodies,
        joints=joints,
        root=root,
        contacts=contacts,
        initial_pose=pose,
        gravity=gravity,
        gait=gait,
        description=description,
        source=source,
        gaits=_other_gaits(c, data, file),
        robot=robot,
    )
    if gait is not None:
        try:
            check_posture(scene, gait.options)
        except PostureError as err:
            c.fail(join("gait.options", err.option), err.reason)
    for level, messages in ((logging.WARNING, c.warnings), (logging.INFO, c.notes)):
        for message in messages:
            if message not in _warned:  # once per process: a scene is loaded by several parts
                _warned.add(message)
                _log.log(level, "%s", message)
    return scene


def _other_gaits(c: Checker, data: dict, file: str) -> tuple[str, ...]:
    """The names of the scene's `gaits:` (each validated as the scene it makes,
    `with_gait`); () without them."""
    if "gaits" not in data:
        return ()
    if "gait" not in data:
        c.fail("gaits", "needs a gait block to change: declare `gait:` first")
    names = c.mapping(data["gaits"], "gaits")
    for name in names:
        if not isinstance(name, str) or not SCENE_NAME_PATTERN.fullmatch(name) \
                or name == DEFAULT_GAIT:
            c.fail(join("gaits", str(name)), f"a gait's name is letters, digits, '_' and '-', "
                   f"not {DEFAULT_GAIT!r} (the `gait:` block's)")
        c.mapping(names[name], join("gaits", name), optional=_GAIT_CHANGES)
        _build_scene(_gait_data(data, name), f"{file} (gait {name})", "")
    return tuple(names)


def _gait_data(data: dict, gait: str) -> dict:
    """The scene `data` with its `gait:` block changed by `gaits: {gait: ...}`: each key
    given replaces the block's, `options` entry by entry; named "<name>_<gait>", without
    `gaits:`."""
    change = data["gaits"][gait]
    block = dict(data["gait"])
    for key, value in change.items():
        block[key] = ({**(block.get("options") or {}), **(value or {})} if key == "options"
                      else value)
    out = {key: value for key, value in data.items() if key != "gaits"}
    out.update(name=f"{data['name']}_{gait}", gait=block)
    return out


def with_gait(scene: Scene, gait: str) -> Scene:
    """`scene` with its gait `gait`: itself for "" or "walk" (its `gait:` block), else the
    scene its `gaits: {gait: ...}` make (`_gait_data`), whose source is that scene's YAML
    (what a recording of it carries). SceneError naming the scene's gaits otherwise."""
    if gait in ("", DEFAULT_GAIT):
        return scene
    if gait not in scene.gaits:
        raise SceneError(f"scene {scene.name!r} has no gait {gait!r}; its gaits: "
                         f"{', '.join((DEFAULT_GAIT,) + scene.gaits)}")
    data = _gait_data(parse_yaml(scene.source, scene.name), gait)
    source = (f"# scene {scene.name!r} with its gait {gait!r} "
              f"(gait_planner.model.loader.with_gait)\n"
              + yaml.safe_dump(_plain(data), sort_keys=False, width=100))
    return dataclasses.replace(_build_scene(data, f"{scene.name} (gait {gait})", source),
                               robot=scene.robot)


def _plain(value: Any) -> Any:
    """Parsed YAML as plain dicts and lists (the loader's mappings track duplicates)."""
    if isinstance(value, dict):
        return {key: _plain(v) for key, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value
