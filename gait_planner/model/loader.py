"""Scene files: find them, read them, validate them, return frozen `Scene`s.

Configuration enters here once: `load_scene(name)` (a bare name, looked up in
`scene_dirs()`), `find_scene(name_or_path)` (also a path to a .yaml file: the command
line's --scene) or `load_scene_file(path)` returns a `gait_planner.model.scene.Scene` whose
every field has been checked, or raises `SceneError` naming the file, the key path and the
reason, e.g. ``walker3d.yaml: bodies[2].mass: must be a positive number, got -1.0``.
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
         points: {hip_r: [x, y, z]}}  # body-fixed, from the COM, director components
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
import math
import os
import re
from pathlib import Path
from types import MappingProxyType
from typing import Any, Sequence

import yaml

from gait_planner.model._validate import Checker, SceneError, check_gait, join, parse_yaml
from gait_planner.model.posture import PostureError, check_posture
from gait_planner.model.robot_source import check_robot
from gait_planner.model.scene import (
    Body,
    Contact,
    InitialPose,
    Joint,
    JointType,
    Root,
    RootType,
    Scene,
)

__all__ = ["SceneError", "available_scenes", "find_scene", "load_scene", "load_scene_file",
           "scene_from_text",
           "scene_dirs"]

_log = logging.getLogger("gait_planner.model")

SCENE_PATH_ENV = "GAIT_PLANNER_SCENE_PATH"
SCENE_NAME_PATTERN = re.compile(r"[A-Za-z0-9_-]+")
DEFAULT_GAIT = "walk"  # the name of a scene's `gait:` block (`with_gait`)
# what a gait of `gaits:` may change of the `gait:` block (the mirror pairs stay)
_GAIT_CHANGES = ("phases", "step_length", "base_time_step", "scaling_bounds",
                 "friction_coefficient", "cost", "options")
_SPHERICAL_ANGLES = ("pitch", "roll", "yaw")  # the order of gait_planner.model.angles
_MIN_AXIS_NORM = 1e-9
_PLANAR_AXIS = (0.0, 1.0, 0.0)
_INERTIA_TOLERANCE = 1e-12  # relative round-off allowed in E_i >= 0
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

    bodies = _bodies(c, top["bodies"], allow)
    root_map = c.mapping(top["root"], "root", required=("body", "type"))
    root_body = c.name(root_map["body"], "root.body")
    c.known(root_body, "root.body", [b.name for b in bodies], "body")
    root = Root(body=root_body, type=c.choice(root_map["type"], "root.type", RootType))
    joints = _joints(c, top["joints"], bodies, root)
    contacts = _contacts(c, top["contacts"], bodies)
    pose = _initial_pose(c, top["initial_pose"], joints, root)
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


def _bodies(c: Checker, value: Any, allow_nonphysical: bool) -> tuple[Body, ...]:
    items = c.named_list(value, "bodies", "body")
    if not items:
        c.fail("bodies", "must list at least one body")
    bodies = []
    for i, item in enumerate(items):
        key = join("bodies", i)
        b = c.mapping(item, key, ("name", "mass", "inertia"), ("length", "points"))
        points = c.mapping(b.get("points", {}), join(key, "points"))
        for point in points:
            c.name(point, join(join(key, "points"), point))
        body = Body(
            name=b["name"],
            mass=c.number(b["mass"], join(key, "mass"), positive=True),
            inertia=tuple(
                c.number(v, join(join(key, "inertia"), k), positive=True)
                for k, v in enumerate(c.sequence(b["inertia"], join(key, "inertia"), 3))
            ),
            points=MappingProxyType(
                {p: c.vector(v, join(join(key, "points"), p)) for p, v in points.items()}
            ),
            length=c.number(b.get("length", 0.0), join(key, "length"), minimum=0.0),
        )
        _check_inertia(c, body, join(key, "inertia"), allow_nonphysical)
        bodies.append(body)
    return tuple(bodies)


def _check_inertia(c: Checker, body: Body, key: str, allow_nonphysical: bool) -> None:
    """Refuse (or, when allowed, warn about) an inertia violating J_i <= J_j + J_k."""
    if min(body.euler_tensor) >= -_INERTIA_TOLERANCE * sum(body.inertia):
        return  # realisable, up to round-off (E_i = 0: a body flat along d_i)
    i = min(range(3), key=lambda k: body.euler_tensor[k])
    j, k = [n for n in range(3) if n != i]
    inertia = body.inertia
    reason = (
        f"body {body.name!r} has a physically non-realisable inertia {inertia}: "
        f"J{i + 1} = {inertia[i]:.6g} > J{j + 1} + J{k + 1} = {inertia[j] + inertia[k]:.6g}, "
        f"so its Euler-tensor value E{i + 1} = {body.euler_tensor[i]:.4g} < 0 and its director "
        f"mass matrix is indefinite (no mass distribution has these moments)"
    )
    if not allow_nonphysical:
        c.fail(key, reason + "; fix the inertia or set allow_nonphysical_inertia: true")
    c.notes.append(f"{c.file}: {key}: {reason}; loading it because "
                      f"allow_nonphysical_inertia is true")


def _joints(c: Checker, value: Any, bodies: tuple[Body, ...], root: Root) -> tuple[Joint, ...]:
    items = c.named_list(value, "joints", "joint")
    by_name = {b.name: b for b in bodies}
    joints, angle_owner = [], {}
    for i, item in enumerate(items):
        key = join("joints", i)
        j = c.mapping(
            item,
            key,
            required=("name", "type", "parent", "parent_point", "child", "child_point"),
            optional=("axis", "reference_rpy", "angle_names"),
        )
        kind = c.choice(j["type"], join(key, "type"), JointType)
        ends = {}
        for end in ("parent", "child"):
            body = c.known(c.name(j[end], join(key, end)), join(key, end), by_name, "body")
            point = c.point(j[f"{end}_point"], join(key, f"{end}_point"), by_name[body])
            ends[end], ends[f"{end}_point"] = body, point
        if ends["parent"] == ends["child"]:
            c.fail(join(key, "child"), f"a joint cannot connect body {ends['child']!r} to itself")
        axis = _joint_axis(c, j, key, kind, root)
        reference = (0.0, 0.0, 0.0)
        if "reference_rpy" in j:
            if kind is not JointType.REVOLUTE:
                c.fail(join(key, "reference_rpy"), "only a revolute joint takes a zero-angle "
                       "reference (a spherical joint's angles are about its parent's directors)")
            reference = c.vector(j["reference_rpy"], join(key, "reference_rpy"))
        name = j["name"]
        angles = (name,) if kind is JointType.REVOLUTE else tuple(
            f"{name}_{a}" for a in _SPHERICAL_ANGLES
        )
        if "angle_names" in j:
            nkey = join(key, "angle_names")
            if kind is not JointType.SPHERICAL:
                c.fail(nkey, "only a spherical joint names its angles (a revolute joint's "
                       "angle is named as the joint)")
            angles = tuple(c.name(a, join(nkey, k))
                           for k, a in enumerate(c.sequence(j["angle_names"], nkey, 3)))
            if len(set(angles)) < 3:
                c.fail(nkey, f"its three angles (pitch, roll, yaw) need three names, got "
                       f"{list(angles)}")
        for angle in angles:
            if angle in angle_owner:
                c.fail(join(key, "name"), f"its angle name {angle!r} clashes with an angle of "
                                          f"joint {angle_owner[angle]!r}")
            angle_owner[angle] = name
        joints.append(Joint(name=name, type=kind, axis=axis, angle_names=angles,
                            reference_rpy=reference, **ends))
    return _tree_order(c, joints, bodies, root)


def _joint_axis(c: Checker, j: dict, key: str, kind: JointType, root: Root):
    akey = join(key, "axis")
    if kind is JointType.SPHERICAL:
        if "axis" in j:
            c.fail(akey, "a spherical joint takes no axis")
        if root.type is RootType.PLANAR:
            c.fail(join(key, "type"), "a planar scene allows only revolute joints about (0, 1, 0)")
        return None
    if "axis" not in j:
        c.fail(akey, "a revolute joint needs an axis (a body-fixed 3-vector)")
    raw = c.vector(j["axis"], akey)
    norm = math.sqrt(sum(v * v for v in raw))
    if norm < _MIN_AXIS_NORM:
        c.fail(akey, f"must not have (near) zero length, got {raw}")
    axis = tuple(v / norm for v in raw)
    if root.type is RootType.PLANAR and max(abs(a - b) for a, b in zip(axis, _PLANAR_AXIS)) > 1e-12:
        c.fail(akey, f"a planar scene allows only revolute joints about (0, 1, 0), got {raw}")
    return axis


def _tree_order(c: Checker, joints: list[Joint], bodies: tuple[Body, ...], root: Root):
    """Check that the joints form one tree on the bodies; return them depth-first."""
    parent_joint: dict[str, int] = {}
    for i, joint in enumerate(joints):
        if joint.child == root.body:
            c.fail(join(join("joints", i), "child"),
                   f"the root body {root.body!r} cannot be a joint's child")
        if joint.child in parent_joint:
            first = joints[parent_joint[joint.child]].name
            c.fail(join(join("joints", i), "child"),
                   f"body {joint.child!r} is already the child of joint {first!r}; "
                   f"each body has one parent joint")
        parent_joint[joint.child] = i
    for body in bodies:
        if body.name != root.body and body.name not in parent_joint:
            c.fail("joints", f"body {body.name!r} is not connected: no joint has it as child")

    def children(body: str) -> list[Joint]:
        return [j for j in joints if j.parent == body]

    ordered: list[Joint] = []
    stack = children(root.body)[::-1]
    while stack:
        joint = stack.pop()
        ordered.append(joint)
        stack.extend(children(joint.child)[::-1])
    if len(ordered) < len(joints):
        body = next(j.child for j in joints if j not in ordered)
        loop, seen = [], set()
        while body not in seen:
            seen.add(body)
            loop.append(body)
            body = joints[parent_joint[body]].parent
        loop = loop[loop.index(body):] + [body]
        c.fail("joints", f"the joints form a loop not connected to the root "
                         f"{root.body!r}: {' -> '.join(reversed(loop))}")
    return tuple(ordered)


def _contacts(c: Checker, value: Any, bodies: tuple[Body, ...]) -> tuple[Contact, ...]:
    items = c.named_list(value, "contacts", "contact")
    by_name = {b.name: b for b in bodies}
    contacts = []
    for i, item in enumerate(items):
        key = join("contacts", i)
        entry = c.mapping(item, key, required=("name", "body", "point"))
        body = c.known(c.name(entry["body"], join(key, "body")), join(key, "body"), by_name, "body")
        point = c.point(entry["point"], join(key, "point"), by_name[body])
        contacts.append(Contact(name=entry["name"], body=body, point=point))
    return tuple(contacts)


def _initial_pose(c: Checker, value: Any, joints: tuple[Joint, ...], root: Root) -> InitialPose:
    key = "initial_pose"
    pose = c.mapping(value, key, required=("root_position",),
                     optional=("root_angles", "joint_angles"))
    position = c.vector(pose["root_position"], join(key, "root_position"))
    angles = c.vector(pose.get("root_angles", [0.0, 0.0, 0.0]), join(key, "root_angles"))
    if root.type is RootType.PLANAR:
        for index, label in ((0, "yaw"), (2, "roll")):
            if angles[index] != 0.0:
                c.fail(join(join(key, "root_angles"), index), f"a planar root turns only "
                       f"about y (pitch): {label} must be 0, got {angles[index]}")
    by_name = {j.name: j for j in joints}
    akey = join(key, "joint_angles")
    joint_angles = {}
    for name, values in c.mapping(pose.get("joint_angles", {}), akey).items():
        jkey = join(akey, name)
        c.known(name, jkey, by_name, "joint")
        joint = by_name[name]
        items = c.sequence(values, jkey)
        if len(items) != joint.dof:
            c.fail(jkey, f"{joint.type.value} joint {name!r} takes {joint.dof} "
                         f"angle{'s' if joint.dof > 1 else ''} {list(joint.angle_names)}, "
                         f"got {len(items)}")
        joint_angles[name] = c.vector(items, jkey, joint.dof)
    return InitialPose(root_position=position, root_angles=angles,
                       joint_angles=MappingProxyType(joint_angles))

