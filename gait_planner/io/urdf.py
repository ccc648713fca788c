"""The walker as a URDF, and the frame scheme that /tf, /tf_static and rerun share.

`scene_to_urdf(scene)` writes a URDF with primitive geometry; `kinematic_tree(scene)` is the
single description of its links and joints, used by `gait_planner.io.messages` to fill /tf
and /tf_static, so the URDF and the transforms can never disagree. `ground_boxes(ground, ...)`
is the solid ground a plan was made for (a slab under a ramp, a box per stair tread):
`ground_to_urdf` writes it as a URDF of its own, the MuJoCo walk and the rerun view build
their stairs from it.

Frame scheme (world x forward, y left, z up):

* Every body has a link of the same name whose axes are the body's directors (d1, d2, d3).
  The root body's link origin is its centre of mass; it hangs from frame ``world`` by a
  floating transform published on /tf (the URDF has no world link, as usual for mobile
  robots). Every other body's link origin is its joint point with its parent (the joint's
  ``child_point``), so the link frame sits at ``phi + D rho_child`` with rotation
  ``D = [d1 d2 d3]``; its centre of mass is at ``-rho_child`` in link coordinates.
* A spherical joint ``j`` (R_rel = Ry(pitch) Rx(roll) Rz(yaw), `gait_planner.model.angles`)
  becomes three revolute URDF joints named after its angles: ``j_pitch`` about y from the
  parent link to the massless link ``j_pitch_link``, whose origin is the joint point in the
  parent link; ``j_roll`` about x to the massless link ``j_roll_link``; ``j_yaw`` about z to the
  child body's link. Both intermediate links sit at the joint point, so the composed rotation
  is exactly R_rel and /tf is exact for any angles.
* A revolute joint becomes one revolute URDF joint named like the joint (= its angle name),
  about the scene's axis in the child's directors, its origin rotated by the joint's
  zero-angle reference (`rpy`).
* Every contact point is a massless link named like the contact (e.g. ``foot_r_heel``),
  fixed to its body's link (a fixed joint ``<contact>_fixed``, published on /tf_static).

All moving joints are ``continuous`` (the scene declares no limits; the roll angles stay in
[-pi/2, pi/2] by the angle convention). Geometry is for drawing only: bodies with two or
more contact points (feet) are boxes spanning their points (breadth `foot_breadth`); other
bodies are cylinders of the body's length along d3, starting at its lowest point, with the
radius of a solid cylinder of the body's mass and axial moment J3 (r = sqrt(2 J3 / m),
capped).

What simulators need (the URDF loads in MuJoCo's compiler and in Pinocchio, tested):

* Each body link carries the scene's mass, its centre of mass and its principal moments
  along the link axes (= the directors). A body whose moments violate J_i <= J_j + J_k (the
  paper's torso) gets the nearest realisable value `realisable_inertia` instead, with an
  XML comment giving the scene's value and why it is not realisable. Only the URDF changes:
  the planner keeps the scene's (the paper's) data.
* The two intermediate links of a spherical joint are massless in the model, but MuJoCo
  refuses a moving body whose mass or inertia is below mjMINVAL (1e-15): they carry
  `FRAME_LINK_MASS` and `FRAME_LINK_INERTIA` at the joint point (walker3d: 8 such links,
  8e-9 kg in all). Contact links stay massless (they are fixed).
* A ``<mujoco><compiler .../></mujoco>`` element (ignored by other URDF readers) keeps every
  link a body of its own (``fusestatic="false"``: the root and the contact frames keep their
  names), keeps the drawing geometry (``discardvisual="false"``, no collision) and takes
  masses and inertias from the ``<inertial>`` elements only (``inertiafromgeom="false"``).
  MuJoCo welds a URDF's root to the world; add a free joint to simulate the walker
  (``spec = mujoco.MjSpec.from_string(urdf); spec.body(root).add_freejoint()``). Pinocchio:
  ``pinocchio.buildModelFromXML(urdf, pinocchio.JointModelFreeFlyer())``.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from gait_planner.model.angles import configuration
from gait_planner.model.ground import Ground
from gait_planner.model.scene import Body, JointType, Scene

__all__ = ["BodyShape", "GroundBox", "KinematicJoint", "KinematicTree", "body_shapes",
           "ground_boxes", "ground_to_urdf", "kinematic_tree", "realisable_inertia",
           "scene_to_urdf", "FOOT_BREADTH", "FRAME_LINK_INERTIA", "FRAME_LINK_MASS",
           "GROUND_HALF_WIDTH", "GROUND_THICKNESS", "WORLD_FRAME"]

WORLD_FRAME = "world"
FOOT_BREADTH = 0.0915  # m, paper Table 2; drawing only (the scenes carry no breadth)
_SPHERICAL_AXES = ((0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0))  # pitch, roll, yaw
_MAX_RADIUS_FRACTION = 0.25  # cylinder radius at most this fraction of the body's length
_MIN_SIZE = 0.01  # m, smallest drawn extent
# The intermediate links of a spherical joint: massless in the model; MuJoCo needs mass and
# every principal moment above mjMINVAL = 1e-15 on a moving body. These are 6 and 3 orders
# above it and far below the data's precision (4 significant digits of kilograms).
FRAME_LINK_MASS = 1e-9  # kg
FRAME_LINK_INERTIA = 1e-12  # kg m^2, each principal moment
_MUJOCO_COMPILER = {"fusestatic": "false", "discardvisual": "false", "inertiafromgeom": "false"}
_COLORS = {"right": (0.85, 0.25, 0.2, 1.0), "left": (0.2, 0.4, 0.85, 1.0),
           "centre": (0.6, 0.6, 0.6, 1.0)}
GROUND_HALF_WIDTH = 1.5  # m, the ground's extent either side of y = 0 (as rerun's grid)
GROUND_THICKNESS = 0.05  # m, of a ramp's slab and below the lowest tread
_GROUND_COLOR = (0.75, 0.75, 0.72, 1.0)


@dataclass(frozen=True)
class KinematicJoint:
    """One URDF joint: the transform parent -> child is Trans(origin) Rot(rpy) Rot(axis,
    angle), `axis` in the child's link frame (URDF's convention); `rpy` is the scene joint's
    zero-angle reference (`gait_planner.model.scene.Joint.reference_rpy`).

    `angle_index` indexes `PlanResult.joint_angles` columns (= the joint angle names);
    None for fixed joints (contact frames), whose rotation is the identity.
    """

    name: str
    parent: str
    child: str
    origin: tuple[float, float, float]
    axis: tuple[float, float, float] | None
    angle_index: int | None
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def fixed(self) -> bool:
        return self.axis is None


@dataclass(frozen=True)
class KinematicTree:
    """Links and joints of the walker's URDF.

    Attributes:
        root: the root body's link (child of `WORLD_FRAME` via /tf).
        link_offsets: body name -> body-fixed position (from its COM, director components)
            of its link origin: zero for the root, the parent-joint point otherwise.
        joints: moving joints in the order of the joint angles, then the fixed joints.
        massless_links: intermediate and contact links (no inertia).
        root_pose: (position (3,), rotation (3, 3)) of the root's link frame in the root
            body's frame (COM origin, director axes); None: the same frame (this module's
            URDF). A robot's own URDF (`gait_planner.io.robot_tree`) has its base link here.
    """

    root: str
    link_offsets: dict[str, np.ndarray]
    joints: tuple[KinematicJoint, ...]
    massless_links: tuple[str, ...]
    root_pose: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def moving_joints(self) -> tuple[KinematicJoint, ...]:
        return tuple(j for j in self.joints if not j.fixed)

    @property
    def fixed_joints(self) -> tuple[KinematicJoint, ...]:
        return tuple(j for j in self.joints if j.fixed)


def _vec(v) -> tuple[float, float, float]:
    return tuple(float(x) for x in v)  # type: ignore[return-value]


def kinematic_tree(scene: Scene) -> KinematicTree:
    """The URDF's links and joints for `scene` (see the module docstring)."""
    offsets = {scene.root.body: np.zeros(3)}
    for joint in scene.joints:
        offsets[joint.child] = np.array(scene.body(joint.child).points[joint.child_point])
    joints: list[KinematicJoint] = []
    massless: list[str] = []
    index = 0
    for joint in scene.joints:
        parent_point = np.array(scene.body(joint.parent).points[joint.parent_point])
        origin = _vec(parent_point - offsets[joint.parent])
        if joint.type is JointType.SPHERICAL:
            links = [f"{name}_link" for name in joint.angle_names[:2]] + [joint.child]
            parent = joint.parent
            for k, (name, axis, child) in enumerate(zip(joint.angle_names, _SPHERICAL_AXES,
                                                        links)):
                joints.append(KinematicJoint(name, parent, child,
                                             origin if k == 0 else (0.0, 0.0, 0.0),
                                             axis, index))
                parent, index = child, index + 1
            massless += links[:2]
        else:
            joints.append(KinematicJoint(joint.angle_names[0], joint.parent, joint.child,
                                         origin, _vec(joint.child_axis), index,
                                         _vec(joint.reference_rpy)))
            index += 1
    for contact in scene.contacts:
        point = np.array(scene.body(contact.body).points[contact.point])
        joints.append(KinematicJoint(f"{contact.name}_fixed", contact.body, contact.name,
                                     _vec(point - offsets[contact.body]), None, None))
        massless.append(contact.name)
    names = [b.name for b in scene.bodies] + massless + [WORLD_FRAME]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ValueError(f"scene {scene.name!r}: URDF link names clash: {duplicates} "
                         f"(bodies, '<angle>_link' frames, contacts and {WORLD_FRAME!r} "
                         f"must all differ)")
    return KinematicTree(scene.root.body, offsets, tuple(joints), tuple(massless))


# ---------------------------------------------------------------------------- geometry


@dataclass(frozen=True)
class BodyShape:
    """A drawing primitive of one body, in body-fixed coordinates (from the COM).

    kind "box": `size` = full extents along (d1, d2, d3); kind "cylinder": `size` =
    (radius, radius, length), axis along d3. `centre` is the primitive's centre.
    """

    kind: str
    size: tuple[float, float, float]
    centre: tuple[float, float, float]
    side: str  # "right", "left" or "centre" (y of the COM in the scene's initial pose)

    @property
    def color(self) -> tuple[float, float, float, float]:
        return _COLORS[self.side]


def _side(scene: Scene) -> dict[str, str]:
    q = configuration(scene)
    sides = {}
    for i, body in enumerate(scene.bodies):
        y = q[12 * i + 1] - q[1 + 12 * scene.body_index(scene.root.body)]
        sides[body.name] = "right" if y < -1e-6 else "left" if y > 1e-6 else "centre"
    return sides


def _shape(body: Body, is_foot: bool, side: str, foot_breadth: float) -> BodyShape:
    points = np.array(list(body.points.values()) or [[0.0, 0.0, 0.0]], dtype=float)
    low, high = points.min(axis=0), points.max(axis=0)
    if is_foot:
        size = np.maximum(high - low, _MIN_SIZE)
        size[1] = foot_breadth
        centre = 0.5 * (low + high)
        centre[1] = 0.0
        return BodyShape("box", _vec(size), _vec(centre), side)
    length = body.length if body.length > 0 else max(high[2] - low[2], _MIN_SIZE)
    radius = math.sqrt(2.0 * body.inertia[2] / body.mass)
    radius = max(min(radius, _MAX_RADIUS_FRACTION * length), 0.5 * _MIN_SIZE)
    return BodyShape("cylinder", (radius, radius, length), (0.0, 0.0, low[2] + 0.5 * length),
                     side)


def body_shapes(scene: Scene, *, foot_breadth: float = FOOT_BREADTH) -> dict[str, BodyShape]:
    """Drawing primitive of every body (module docstring), body name -> `BodyShape`."""
    contacts = [c.body for c in scene.contacts]
    sides = _side(scene)
    return {b.name: _shape(b, contacts.count(b.name) >= 2, sides[b.name], foot_breadth)
            for b in scene.bodies}


# ---------------------------------------------------------------------------- URDF text


def _num(x: float) -> str:
    return repr(float(x)) if x != 0 else "0"


def _xyz(v) -> str:
    return " ".join(_num(x) for x in v)


def _origin(parent: ET.Element, xyz, rpy=(0.0, 0.0, 0.0)) -> None:
    ET.SubElement(parent, "origin", xyz=_xyz(xyz), rpy=_xyz(rpy))


def realisable_inertia(inertia) -> tuple[float, float, float]:
    """The nearest physically realisable principal moments to `inertia` (J1, J2, J3).

    Moments are realisable (some mass distribution has them) iff J_i <= J_j + J_k for every
    i: the second moment of mass along axis i, (J_j + J_k - J_i) / 2, is then >= 0. With
    positive moments at most one inequality can fail. The moment that violates it is lowered
    to J_j + J_k, the other two are kept: the least change of that one moment, and the
    least total change any fix can make (sum |dJ| = J_i - J_j - J_k, the violation). The
    result lies on the boundary: all mass in the plane normal to axis i (a lamina), the
    closest a real body comes. Realisable moments are returned unchanged.

    (The symmetric alternative, the Euclidean projection that moves each moment by a third
    of the violation, would alter the pitch and yaw moments too: for the paper's torso it
    changes the torso's rotational kinetic energy over the planned walker3d gait by +6.9 %
    where this one changes it by -2.0 %, and it would change walker2d's sagittal dynamics,
    which only J2 enters.)
    """
    j = [float(x) for x in inertia]
    for i in range(3):
        others = j[(i + 1) % 3] + j[(i + 2) % 3]
        if j[i] > others:
            j[i] = others
    return (j[0], j[1], j[2])


def _fmt(values) -> str:
    return "(" + ", ".join(f"{float(x):.6g}" for x in values) + ")"


def _inertial(link: ET.Element, com, mass: float, moments) -> ET.Element:
    inertial = ET.SubElement(link, "inertial")
    _origin(inertial, com)  # the COM in link coordinates; axes = principal axes
    ET.SubElement(inertial, "mass", value=_num(mass))
    j1, j2, j3 = moments
    ET.SubElement(inertial, "inertia", ixx=_num(j1), ixy="0", ixz="0", iyy=_num(j2), iyz="0",
                  izz=_num(j3))
    return inertial


def _nonrealisable_comment(scene: Scene, body: Body, written: tuple[float, ...]) -> str:
    k = next(i for i in range(3) if written[i] != float(body.inertia[i]))
    a, b = (k + 1) % 3, (k + 2) % 3
    names = ("J1", "J2", "J3")
    given = body.inertia
    return (
        f" Scene {scene.name!r} gives {body.name} the principal moments {_fmt(given)} kg m^2 "
        f"about (d1, d2, d3). They are not physically realisable: {names[k]} = {given[k]:.6g} > "
        f"{names[a]} + {names[b]} = {given[a] + given[b]:.6g}, so the second moment of mass "
        f"along d{k + 1}, ({names[a]} + {names[b]} - {names[k]})/2 = "
        f"{0.5 * (given[a] + given[b] - given[k]):.4g} kg m^2, would be negative; no mass "
        f"distribution has these moments, and MuJoCo rejects them. Written below is the "
        f"nearest realisable value {_fmt(written)}: {names[k]} = {names[a]} + {names[b]}, with "
        f"{names[a]} and {names[b]} kept. That is the least change of the one offending moment "
        f"and the least total change any fix can make; it puts all mass in the "
        f"d{a + 1}-d{b + 1} plane. The planner keeps using the scene's values "
        f"(gait_planner.io.urdf.realisable_inertia). ")


def _body_link(robot: ET.Element, scene: Scene, body: Body, offset: np.ndarray,
               shape: BodyShape) -> None:
    link = ET.SubElement(robot, "link", name=body.name)
    moments = realisable_inertia(body.inertia)
    if moments != tuple(float(x) for x in body.inertia):
        link.append(ET.Comment(_nonrealisable_comment(scene, body, moments)))
    _inertial(link, -offset, body.mass, moments)
    visual = ET.SubElement(link, "visual")
    _origin(visual, np.array(shape.centre) - offset)
    geometry = ET.SubElement(visual, "geometry")
    if shape.kind == "box":
        ET.SubElement(geometry, "box", size=_xyz(shape.size))
    else:
        ET.SubElement(geometry, "cylinder", radius=_num(shape.size[0]), length=_num(shape.size[2]))
    material = ET.SubElement(visual, "material", name=shape.side)
    ET.SubElement(material, "color", rgba=_xyz(shape.color))


def scene_to_urdf(scene: Scene, *, foot_breadth: float = FOOT_BREADTH) -> str:
    """The URDF (XML text) of `scene`: one link per body, (nearly) massless links for
    spherical joints and contact points, joints named after the joint angles, loadable by
    MuJoCo and Pinocchio (module docstring)."""
    tree = kinematic_tree(scene)
    shapes = body_shapes(scene, foot_breadth=foot_breadth)
    robot = ET.Element("robot", name=scene.name)
    robot.append(ET.Comment(
        f" generated by gait_planner.io.urdf from scene {scene.name!r}; link frames: directors "
        f"(d1, d2, d3) at the COM for the root, at the parent-joint point otherwise; the root "
        f"hangs from frame {WORLD_FRAME!r} by a transform on /tf "))
    robot.append(ET.Comment(
        " MuJoCo: keep every link a body (root and contact frames keep their names), keep the "
        "drawing geometry, masses and inertias from <inertial> only; other URDF readers ignore "
        "this element "))
    mujoco = ET.SubElement(robot, "mujoco")
    ET.SubElement(mujoco, "compiler", _MUJOCO_COMPILER)
    for body in scene.bodies:
        _body_link(robot, scene, body, tree.link_offsets[body.name], shapes[body.name])
    moved = {j.child for j in tree.moving_joints}  # intermediate links; contacts are fixed
    for name in tree.massless_links:
        link = ET.SubElement(robot, "link", name=name)
        if name in moved:
            link.append(ET.Comment(
                " massless in the model; MuJoCo needs mass and inertia above 1e-15 on a "
                "moving body "))
            _inertial(link, (0.0, 0.0, 0.0), FRAME_LINK_MASS, (FRAME_LINK_INERTIA,) * 3)
    for joint in tree.joints:
        element = ET.SubElement(robot, "joint", name=joint.name,
                                type="fixed" if joint.fixed else "continuous")
        ET.SubElement(element, "parent", link=joint.parent)
        ET.SubElement(element, "child", link=joint.child)
        _origin(element, joint.origin, joint.rpy)
        if not joint.fixed:
            ET.SubElement(element, "axis", xyz=_xyz(joint.axis))
    ET.indent(robot, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"


# ---------------------------------------------------------------------------- the ground


@dataclass(frozen=True)
class GroundBox:
    """One box of the ground's geometry, world frame: full extents `size` (m) along its own
    axes, centred at `centre` (m), turned by `pitch` (rad) about the world y axis (its x
    axis (cos pitch, 0, -sin pitch); along a ramp of slope a, pitch = -a)."""

    centre: tuple[float, float, float]
    size: tuple[float, float, float]
    pitch: float = 0.0

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """(w, x, y, z) of the box's rotation (MuJoCo's order)."""
        return (math.cos(0.5 * self.pitch), 0.0, math.sin(0.5 * self.pitch), 0.0)


def ground_boxes(ground: Ground, x_start: float, x_end: float) -> tuple[GroundBox, ...]:
    """The solid ground under x in [x_start, x_end] m and |y| <= `GROUND_HALF_WIDTH`, its
    top the ground's surface (`gait_planner.model.ground`). Level ground or a ramp: one slab
    `GROUND_THICKNESS` thick under the plane. Stairs: one box per tread the range touches
    (tread j spans x in [riser + (j - 1) tread, riser + j tread) at height j step_height),
    each from its tread down to `GROUND_THICKNESS` below the lowest of them: a solid flight
    whose risers are the boxes' faces."""
    width = 2.0 * GROUND_HALF_WIDTH
    if not ground.stairs:
        middle = 0.5 * (x_start + x_end)
        centre = (np.array([middle, 0.0, float(ground.height(middle))])
                  - 0.5 * GROUND_THICKNESS * ground.normal)
        length = (x_end - x_start) / math.cos(math.radians(ground.slope))
        return (GroundBox(_vec(centre), (length, width, GROUND_THICKNESS),
                          -math.radians(ground.slope)),)
    depth = ground.tread
    first = math.floor((x_start - ground.riser) / depth) + 1
    last = math.floor((x_end - ground.riser) / depth) + 1
    tops = {j: ground.tread_height(j) for j in range(first, last + 1)}
    bottom = min(tops.values()) - GROUND_THICKNESS
    return tuple(GroundBox((ground.riser + (j - 0.5) * depth, 0.0, 0.5 * (top + bottom)),
                           (depth, width, top - bottom)) for j, top in tops.items())


def ground_to_urdf(ground: Ground, x_start: float, x_end: float) -> str:
    """The URDF (XML text) of the ground alone: robot "ground", one link "ground" whose
    frame is the world frame (`WORLD_FRAME`), the `ground_boxes` of x in [x_start, x_end] m
    as its visual and collision boxes. A model of its own: the walker's URDF floats (its
    root hangs from the world frame by /tf) and a URDF is a single tree, so a viewer or
    simulator loads this one beside it (MuJoCo: `gait_planner.walk.mujoco_model` builds the
    same boxes into its world body)."""
    robot = ET.Element("robot", name="ground")
    robot.append(ET.Comment(
        f" generated by gait_planner.io.urdf: the ground a gait was planned on (slope "
        f"{ground.slope:g} deg, step_height {ground.step_height:g} m), x from {x_start:g} to "
        f"{x_end:g} m; the link's frame is frame {WORLD_FRAME!r} "))
    link = ET.SubElement(robot, "link", name="ground")
    for box in ground_boxes(ground, x_start, x_end):
        for kind in ("visual", "collision"):
            element = ET.SubElement(link, kind)
            ET.SubElement(element, "origin", xyz=_xyz(box.centre), rpy=_xyz((0, box.pitch, 0)))
            ET.SubElement(ET.SubElement(element, "geometry"), "box", size=_xyz(box.size))
            if kind == "visual":
                material = ET.SubElement(element, "material", name="ground")
                ET.SubElement(material, "color", rgba=_xyz(_GROUND_COLOR))
    ET.indent(robot, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"
