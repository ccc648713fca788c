"""A scene's ``robot:`` section: the URDF it was drafted from (`gait_planner.model.urdf_import`).

YAML layout (written by ``gait-planner scene from-urdf``; every key checked)::

    robot:
      urdf: g1_29dof_rev_1_0.urdf     # the original URDF; relative: to the scene file
      package_dirs: [../share]        # optional: folders for its package:// paths
      locked: {waist_yaw_joint: 0.0}  # optional: joints held fixed, rad
      holds:                          # optional: locked joints whose effort is bounded
        waist_yaw_joint: {body: pelvis, side: 1, effort: 88.0, axis: [..], point: [..],
                          mass: 15.2, com: [..], inertia: [ixx, iyy, izz, ixy, ixz, iyz]}
      links:                          # every body: its URDF link frame in the body's frame
        pelvis: [x, y, z, roll, pitch, yaw]   # m, rad (origin: the body's centre of mass,
                                      # axes: its directors)

The planner reads only its ``holds`` (`gait_planner.model.urdf_holds`: the rows that keep a
locked joint's holding effort within its limit); the problem is the scene's bodies and
joints. The outputs read the rest:
/robot_description is this URDF, /tf its frames, the JointTrajectory names its locked joints
too, and the continuous-dynamics certificate runs on it (`gait_planner.verify.robot`).
"""

from __future__ import annotations

from pathlib import Path
from types import MappingProxyType
from typing import Any

from gait_planner.model._validate import Checker, join
from gait_planner.model.scene import Body, Hold, RobotSource

__all__ = ["check_robot"]


def check_robot(c: Checker, value: Any, bodies: tuple[Body, ...],
                folder: Path | None) -> RobotSource:
    """The ``robot:`` section; its URDF is read from `folder` (the scene file's), or left
    "" when `folder` is None (a scene rebuilt from a recording's attachment)."""
    r = c.mapping(value, "robot", required=("urdf", "links"),
                  optional=("package_dirs", "locked", "holds"))
    urdf_file = c.string(r["urdf"], "robot.urdf")
    links_map = c.mapping(r["links"], "robot.links")
    names = [b.name for b in bodies]
    links = {}
    for body, pose in links_map.items():
        key = join("robot.links", body)
        c.known(body, key, names, "body")
        v = c.vector(pose, key, 6)
        links[body] = (v[:3], v[3:])
    missing = [n for n in names if n not in links]
    if missing:
        c.fail("robot.links", f"every body needs its link frame; missing: {', '.join(missing)}")
    locked_map = c.mapping(r.get("locked", {}), "robot.locked")
    locked = {k: c.number(v, join("robot.locked", k)) for k, v in locked_map.items()}
    dirs = tuple(c.string(d, join("robot.package_dirs", i))
                 for i, d in enumerate(c.sequence(r.get("package_dirs", []), "robot.package_dirs")))
    text = ""
    resolved = urdf_file if Path(urdf_file).is_absolute() else ""  # (read or not)
    if folder is not None:
        path = folder / urdf_file
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            c.fail("robot.urdf", f"the robot's URDF {str(path)!r} cannot be read: {error}")
        dirs, resolved = tuple(str((folder / d).resolve()) for d in dirs), str(path.resolve())
    holds = _holds(c, r.get("holds", {}), names, locked)
    return RobotSource(urdf_file, text, MappingProxyType(links), MappingProxyType(locked), dirs,
                       resolved, holds)


def _holds(c: Checker, value: Any, bodies: list[str], locked: dict) -> tuple[Hold, ...]:
    """``robot.holds``: each entry a locked joint's held part (`Hold`), every key checked."""
    out = []
    for name, entry in c.mapping(value, "robot.holds").items():
        key = join("robot.holds", name)
        c.known(name, key, locked, "locked joint")
        h = c.mapping(entry, key, required=("body", "side", "effort", "axis", "point",
                                            "mass", "com", "inertia"))
        side = c.integer(h["side"], join(key, "side"), minimum=-1)
        if side not in (-1, 1):
            c.fail(join(key, "side"), f"must be 1 (the joint's subtree) or -1 (the rest of "
                                      f"the body), got {side}")
        axis = c.vector(h["axis"], join(key, "axis"))
        if abs(sum(a * a for a in axis) - 1.0) > 1e-6:
            c.fail(join(key, "axis"), f"must be a unit vector, got {list(axis)}")
        out.append(Hold(name, c.known(c.string(h["body"], join(key, "body")), join(key, "body"),
                                      bodies, "body"),
                        side, c.number(h["effort"], join(key, "effort"), positive=True), axis,
                        c.vector(h["point"], join(key, "point")),
                        c.number(h["mass"], join(key, "mass"), positive=True),
                        c.vector(h["com"], join(key, "com")),
                        c.vector(h["inertia"], join(key, "inertia"), 6)))
    return tuple(out)
