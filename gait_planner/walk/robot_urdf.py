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
  geometry of the `feet` links (and of links fixed below them; a foot without any: its
  visual geometry, as the draft reads it) is kept, its mesh files resolved in
  `RobotUrdf.package_dirs` (``package://PKG/path`` -> ``DIR/PKG/path``); every other
  ``<collision>`` and every ``<visual>`` is dropped (the walk draws nothing from MuJoCo,
  and other links' meshes need not exist on this machine). A foot mesh MuJoCo does not
  read (Collada, iCub's) is left out of the text and given by `foot_meshes` as the
  vertices the draft read.
* **Missing inertias.** A link whose <inertia> is zero (iCub's right leg links and
  ankles in example-robot-data: the URDF lacks them) takes the draft's body (its twin's
  mirrored inertia, `gait_planner.model.urdf_mirror`), as the certificate does
  (`gait_planner.verify.robot`), when that body is the link alone; else (a link whose
  fixed children carry the mass, iCub's ankle_2) a point mass's POINT_INERTIA: MuJoCo
  refuses a body without a positive inertia.
* **MuJoCo's compiler options.** Every link stays a body of its own (``fusestatic``
  false), masses and inertias are the URDF's ``<inertial>`` (``inertiafromgeom`` false),
  a non-physical one (principal moments A + B < C: Romeo's welded RShoulderYawLink; the
  draft refuses one in a leg) made physical by MuJoCo (``balanceinertia``) rather than
  refused, mesh paths are kept as resolved (``strippath`` false).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np

from gait_planner.model.rotations import matrix_rpy, rot_axis, rpy_matrix
from gait_planner.model.urdf_mirror import MISSING_INERTIA

__all__ = ["FootMesh", "RobotUrdf", "foot_meshes", "simulation_urdf"]

_MOVING = ("revolute", "continuous", "prismatic")
MUJOCO_MESHES = (".stl", ".obj", ".msh")  # the mesh files MuJoCo's compiler reads
POINT_INERTIA = 1e-9  # kg m^2: a point mass's moments in MuJoCo (1 g at 1 mm, 1 kg at 30 um)


@dataclass(frozen=True)
class FootMesh:
    """A foot mesh given to MuJoCo as vertices: on `link`, at `pos` (3,) m and turned by `R`
    (3, 3) in the link's frame, `vertices` (n, 3) m in its own frame."""

    link: str
    pos: np.ndarray
    R: np.ndarray
    vertices: np.ndarray


@dataclass(frozen=True)
class RobotUrdf:
    """A drafted robot's original URDF: its `text`, the folders of its ``package://`` paths
    (`package_dirs`) and the angles of the joints the draft locked (`locked`: name -> rad,
    or m for a prismatic joint; `UrdfDraft.locked`)."""

    text: str
    package_dirs: tuple[str, ...] = ()
    locked: Mapping[str, float] = field(default_factory=dict)


def simulation_urdf(robot: RobotUrdf, planned: Iterable[str], feet: Iterable[str],
                    drafted: Mapping[str, tuple] | None = None) -> str:
    """The URDF text of the module docstring; `planned` the joints the plan moves, `feet`
    the links carrying its contact points, `drafted` the draft's bodies (link -> (mass kg,
    COM (3,) m, inertia (3, 3) kg m^2 at the COM, in the link's frame)) for the links the
    URDF gives no inertia. ValueError naming the joint, link or mesh."""
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
    shapes = _foot_shapes(root, feet)
    for link in root.findall("link"):
        _complete(root, link, (drafted or {}).get(link.get("name")))
    for link in root.findall("link"):
        for element in link.findall("visual") + link.findall("collision"):
            link.remove(element)
        for shape in shapes.get(link.get("name"), []):
            mesh = shape.find("geometry/mesh")
            if mesh is not None:
                path = _resolve(mesh.get("filename", ""), link.get("name"), robot.package_dirs)
                if Path(path).suffix.lower() not in MUJOCO_MESHES:
                    continue  # added from its vertices: foot_meshes
                mesh.set("filename", path)
            shape.tag = "collision"
            link.append(shape)
    for old in root.findall("mujoco"):
        root.remove(old)
    ET.SubElement(ET.SubElement(root, "mujoco"), "compiler", fusestatic="false",
                  inertiafromgeom="false", balanceinertia="true", strippath="false",
                  discardvisual="true")
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


def _complete(root: ET.Element, link: ET.Element, drafted: tuple | None) -> None:
    """A link without an inertia (its <inertia> zero) takes the draft's body when the body
    is the link alone (nothing with mass fixed below it), else a point mass's
    POINT_INERTIA: MuJoCo refuses a body without a positive inertia."""
    inertia = link.find("inertial/inertia")
    keys = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    if inertia is None or any(abs(float(inertia.get(k, "0"))) > MISSING_INERTIA for k in keys):
        return
    alone = all(_mass(root, name) == 0 for name in _fixed_below(root, {link.get("name")})
                if name != link.get("name"))
    if drafted is not None and alone:
        mass, com, tensor = drafted
        inertial = link.find("inertial")
        _set_inertial(inertial, mass, com, tensor)
        return
    for k in keys:
        inertia.set(k, repr(POINT_INERTIA) if k in keys[:3] else "0")


def _set_inertial(inertial: ET.Element, mass: float, com, tensor) -> None:
    for old in list(inertial):
        inertial.remove(old)
    ET.SubElement(inertial, "origin", xyz=" ".join(repr(float(v)) for v in com), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(float(mass)))
    ET.SubElement(inertial, "inertia", **{k: repr(float(tensor[i, j])) for k, (i, j) in (
        ("ixx", (0, 0)), ("iyy", (1, 1)), ("izz", (2, 2)), ("ixy", (0, 1)), ("ixz", (0, 2)),
        ("iyz", (1, 2)))})


def _mass(root: ET.Element, name: str) -> float:
    mass = root.find(f"link[@name='{name}']/inertial/mass")
    return 0.0 if mass is None else float(mass.get("value", "0"))


def foot_meshes(robot: RobotUrdf, feet: Iterable[str]) -> list[FootMesh]:
    """The feet's meshes MuJoCo's compiler does not read (Collada), which
    `simulation_urdf` leaves out, as their vertices (read as the draft reads them,
    `gait_planner.model.urdf_contacts.read_mesh`)."""
    from gait_planner.model.urdf_contacts import read_mesh  # noqa: PLC0415 - coal on demand

    out = []
    for link, shapes in _foot_shapes(ET.fromstring(robot.text), feet).items():
        for shape in shapes:
            mesh = shape.find("geometry/mesh")
            if mesh is None:
                continue
            path = _resolve(mesh.get("filename", ""), link, robot.package_dirs)
            if Path(path).suffix.lower() in MUJOCO_MESHES:
                continue
            origin = shape.find("origin")
            xyz, rpy = (("0 0 0", "0 0 0") if origin is None else
                        (origin.get("xyz", "0 0 0"), origin.get("rpy", "0 0 0")))
            scale = [float(v) for v in mesh.get("scale", "1 1 1").split()]
            out.append(FootMesh(link, np.array([float(v) for v in xyz.split()]),
                                rpy_matrix([float(v) for v in rpy.split()]),
                                read_mesh(path, scale)))
    return out


def _foot_shapes(root: ET.Element, feet: Iterable[str]) -> dict[str, list[ET.Element]]:
    """link -> the <collision> elements of each foot's links (the foot and the links fixed
    below it), or their <visual> ones for a foot without any collision geometry (as the
    draft reads them, `gait_planner.model.urdf_contacts`)."""
    links = {link.get("name"): link for link in root.findall("link")}
    out: dict[str, list[ET.Element]] = {}
    for foot in feet:
        group = _fixed_below(root, {foot})
        kind = "collision" if any(links[n].findall("collision") for n in group) else "visual"
        for name in group:
            out[name] = links[name].findall(kind)
    return out


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
