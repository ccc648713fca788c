"""A robot's own URDF made ready for the MuJoCo walk of a plan drafted from it
(`gait_planner.model.urdf_import`).

`simulation_urdf(robot, planned, feet)` rewrites the URDF text of a `RobotUrdf` for
MuJoCo's compiler:

* **Locked joints welded.** Every joint the draft locked (`RobotUrdf.locked`, name -> angle
  rad or m, as `UrdfDraft.locked`) becomes a fixed joint at that angle (its origin composed
  with the rotation about, or the shift along, its axis). The plan merged these links into
  their parent as one rigid body; welded links are that body exactly, with no dof, gain or
  time-step limit of their own (a stiff position loop would add both and simulate a robot
  the plan did not make). A moving joint neither planned nor locked is refused.
* **Only the feet collide.** The plan's only contacts are the feet's: the collision
  geometry of the `feet` links (and of links fixed below them) is kept, its mesh files
  resolved in `RobotUrdf.package_dirs` (``package://PKG/path`` -> ``DIR/PKG/path``); every
  other ``<collision>`` and every ``<visual>`` is dropped (the walk draws nothing from
  MuJoCo, and other links' meshes need not exist on this machine).
* **MuJoCo's compiler options.** Every link stays a body of its own (``fusestatic``
  false), masses and inertias are the URDF's ``<inertial>`` (``inertiafromgeom`` false),
  mesh paths are kept as resolved (``strippath`` false).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np

from gait_planner.model.rotations import matrix_rpy, rot_axis, rpy_matrix

__all__ = ["RobotUrdf", "simulation_urdf"]

_MOVING = ("revolute", "continuous", "prismatic")


@dataclass(frozen=True)
class RobotUrdf:
    """A drafted robot's original URDF: its `text`, the folders of its ``package://`` paths
    (`package_dirs`) and the angles of the joints the draft locked (`locked`: name -> rad,
    or m for a prismatic joint; `UrdfDraft.locked`)."""

    text: str
    package_dirs: tuple[str, ...] = ()
    locked: Mapping[str, float] = field(default_factory=dict)


def simulation_urdf(robot: RobotUrdf, planned: Iterable[str], feet: Iterable[str]) -> str:
    """The URDF text of the module docstring; `planned` the joints the plan moves, `feet`
    the links carrying its contact points. ValueError naming the joint, link or mesh."""
    try:
        root = ET.fromstring(robot.text)
    except ET.ParseError as error:
        raise ValueError(f"the robot's URDF is not well-formed XML: {error}") from None
    planned = set(planned)
    for joint in root.findall("joint"):
        name, kind = joint.get("name"), joint.get("type")
        if name in robot.locked:
            _weld(joint, robot.locked[name])
        elif kind in _MOVING and name not in planned:
            raise ValueError(f"joint {name!r} ({kind}) of the URDF is neither planned nor "
                             f"locked by the draft")
    colliding = _fixed_below(root, set(feet))
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            link.remove(visual)
        for collision in link.findall("collision"):
            if link.get("name") not in colliding:
                link.remove(collision)
            else:
                for mesh in collision.iter("mesh"):
                    mesh.set("filename", _resolve(mesh.get("filename", ""), link.get("name"),
                                                  robot.package_dirs))
    for old in root.findall("mujoco"):
        root.remove(old)
    ET.SubElement(ET.SubElement(root, "mujoco"), "compiler", fusestatic="false",
                  inertiafromgeom="false", strippath="false", discardvisual="true")
    return ET.tostring(root, encoding="unicode")


def _weld(joint: ET.Element, value: float) -> None:
    """Make a moving joint fixed at `value` (rad about, or m along, its axis)."""
    kind = joint.get("type")
    if kind not in _MOVING:
        raise ValueError(f"joint {joint.get('name')!r} is locked but is a {kind} joint: only "
                         f"revolute, continuous and prismatic joints can be welded")
    axis_el = joint.find("axis")
    axis = np.array([float(v) for v in (axis_el.get("xyz", "1 0 0") if axis_el is not None
                                        else "1 0 0").split()])
    axis /= np.linalg.norm(axis)
    origin = joint.find("origin")
    if origin is None:
        origin = ET.SubElement(joint, "origin")
    xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
    R = rpy_matrix([float(v) for v in origin.get("rpy", "0 0 0").split()])
    if kind == "prismatic":
        xyz = xyz + R @ axis * value
    else:
        R = R @ rot_axis(axis, value)
    origin.set("xyz", " ".join(repr(float(v)) for v in xyz))
    origin.set("rpy", " ".join(repr(float(v)) for v in matrix_rpy(R)))
    joint.set("type", "fixed")
    for tag in ("axis", "limit", "dynamics", "mimic", "safety_controller", "calibration"):
        for child in joint.findall(tag):
            joint.remove(child)


def _fixed_below(root: ET.Element, feet: set[str]) -> set[str]:
    """The `feet` links and every link fixed below one of them (after welding)."""
    children: dict[str, list[str]] = {}
    for joint in root.findall("joint"):
        if joint.get("type") == "fixed":
            children.setdefault(joint.find("parent").get("link"), []).append(
                joint.find("child").get("link"))
    links = {link.get("name") for link in root.findall("link")}
    missing = sorted(feet - links)
    if missing:
        raise ValueError(f"the URDF has no link {missing[0]!r}, a foot of the plan")
    out, todo = set(), list(feet)
    while todo:
        link = todo.pop()
        out.add(link)
        todo += children.get(link, [])
    return out


def _resolve(filename: str, link: str, package_dirs: Iterable[str]) -> str:
    """The absolute path of a foot's collision mesh; ValueError naming it if not found."""
    if filename.startswith("package://"):
        rest = filename[len("package://"):]
        for folder in package_dirs:
            path = Path(folder) / rest
            if path.is_file():
                return str(path.resolve())
    elif filename.startswith("file://") or Path(filename).is_absolute():
        path = Path(filename.removeprefix("file://"))
        if path.is_file():
            return str(path)
    raise ValueError(f"the collision mesh {filename!r} of foot link {link!r} is not found "
                     f"(package folders: {list(package_dirs) or 'none'}); the walk needs the "
                     f"feet's own contact geometry")
