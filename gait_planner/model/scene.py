"""Scene description: the plain, validated data a scene file declares.

A scene declares bodies, joints, contact points and (optionally) a gait with its phases;
`gait_planner.model.multibody.Multibody` builds only what is declared here.
All instances are frozen; they are created by `gait_planner.model.loader.load_scene`,
which validates every field (see its docstring for the YAML layout).

Conventions: world x forward (walking direction), y left, z up; ground plane z = 0.
Body-fixed vectors are components along the body's directors (d1, d2, d3), which are
its principal axes; lengths in m, masses in kg, inertias in kg m^2.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

import numpy as np

from gait_planner.model.rotations import rpy_matrix

Vec3 = tuple[float, float, float]


class JointType(enum.Enum):
    """Kinds of joint between a parent and a child body."""

    SPHERICAL = "spherical"  # 3 rotational degrees of freedom, 3 constraints
    REVOLUTE = "revolute"  # 1 rotational degree of freedom about `axis`, 5 constraints


class RootType(enum.Enum):
    """How the root body of the tree moves relative to the world."""

    FREE = "free"  # 6 degrees of freedom
    PLANAR = "planar"  # sagittal: translation in x-z, rotation about world y (3 dof)


@dataclass(frozen=True)
class Body:
    """A rigid body in director coordinates.

    Attributes:
        name: unique name.
        mass: kg, > 0.
        inertia: principal moments (J1, J2, J3) about the centre of mass along d1, d2, d3.
        points: named body-fixed points (m, from the centre of mass, director components).
        length: drawing length (m) of the body along d3, used for URDF geometry.
        collision: spheres (x, y, z, r) (m: centre from the centre of mass in director
            components, radius > 0) that contain the body's collision geometry: the shapes
            the rows that keep the legs apart measure (`gait_planner.ocp.legs`); () for a
            body those rows leave out.
    """

    name: str
    mass: float
    inertia: Vec3
    points: Mapping[str, Vec3] = field(default_factory=lambda: MappingProxyType({}))
    length: float = 0.0
    collision: tuple[tuple[float, float, float, float], ...] = ()

    @property
    def euler_tensor(self) -> Vec3:
        """Euler-tensor values E_i = (J1 + J2 + J3)/2 - J_i (docs/design.md section 1)."""
        half = 0.5 * sum(self.inertia)
        return tuple(half - j for j in self.inertia)  # type: ignore[return-value]

    @property
    def is_realisable(self) -> bool:
        """True if the inertia satisfies the triangle inequalities J_i <= J_j + J_k."""
        return all(e >= 0.0 for e in self.euler_tensor)


@dataclass(frozen=True)
class Joint:
    """A joint connecting `parent.parent_point` with `child.child_point`.

    Attributes:
        axis: revolute joints only; unit axis in the parent's director components (e.g.
            (0, 1, 0): the lateral d2 axis); in the child's it is R0^T axis.
        reference_rpy: revolute joints only; the zero-angle reference R0 = Rz(y) Ry(p) Rx(r)
            of (r, p, y) rad (URDF's rpy): the child's directors in the parent's at zero
            angle, so that R_rel = Rot(axis, angle) R0. (0, 0, 0), the default, aligns both
            triads at zero angle (the built-in walkers); a URDF's joints, between bodies
            whose directors are their own principal axes, need it
            (`gait_planner.model.urdf_import`).
        angle_names: output names of the joint's angles (3 for spherical, 1 for revolute),
            in the order of `gait_planner.model.angles` (pitch, roll, yaw for spherical).
    """

    name: str
    type: JointType
    parent: str
    parent_point: str
    child: str
    child_point: str
    axis: Vec3 | None = None
    angle_names: tuple[str, ...] = ()
    reference_rpy: Vec3 = (0.0, 0.0, 0.0)

    @property
    def reference(self) -> np.ndarray:
        """R0 (3, 3): the child's directors in the parent's components at zero angle."""
        return rpy_matrix(self.reference_rpy)

    @property
    def child_axis(self) -> Vec3 | None:
        """The revolute axis in the child's director components, R0^T axis."""
        if self.axis is None:
            return None
        return tuple(float(x) for x in self.reference.T @ np.asarray(self.axis))

    @property
    def dof(self) -> int:
        return 3 if self.type is JointType.SPHERICAL else 1


@dataclass(frozen=True)
class Root:
    """The root of the kinematic tree: `body` moves freely (or planar) in the world."""

    body: str
    type: RootType = RootType.FREE

    @property
    def dof(self) -> int:
        return 6 if self.type is RootType.FREE else 3


@dataclass(frozen=True)
class Contact:
    """A named contact point `point` of `body` that can be held on the ground."""

    name: str
    body: str
    point: str


@dataclass(frozen=True)
class InitialPose:
    """A configuration: root centre-of-mass position, root Cardan angles, joint angles.

    `root_angles` are (yaw, pitch, roll) in rad: R = Rz(yaw) Ry(pitch) Rx(roll).
    `joint_angles` maps joint names to their angles (rad, `gait_planner.model.angles`
    convention); joints not named are at zero (the upright pose).
    """

    root_position: Vec3
    root_angles: Vec3 = (0.0, 0.0, 0.0)
    joint_angles: Mapping[str, tuple[float, ...]] = field(
        default_factory=lambda: MappingProxyType({})
    )


@dataclass(frozen=True)
class Phase:
    """One phase of a gait: the contact points held on the ground and its time scaling.

    Attributes:
        contacts: names of the contacts held throughout the phase (both points of one
            foot = full contact).
        scaling: index into the phase-scaling vector sigma (several phases may share one).
        intervals: number of time intervals in the phase.
    """

    name: str
    contacts: tuple[str, ...]
    scaling: int
    intervals: int


@dataclass(frozen=True)
class Gait:
    """A half-cycle gait: phases, mirror pairs and the optimal-control settings.

    Attributes:
        mirror: body name -> body name of its mirror image about y = 0 (each pair listed
            once both ways; unpaired bodies mirror onto themselves).
        base_time_step: s; the interval length of a phase is sigma_k * base_time_step.
        scaling_bounds: (lower, upper) bounds of every sigma_k.
        friction_coefficient: Coulomb static friction coefficient mu_0.
        cost: the default cost name (e.g. "kinetic_energy").
        options: further named settings of the transcription (path constraints,
            regularisation weights ...), validated by the optimal-control code; its posture
            entries (joint_limits, torso_lean_max) already when the scene loads
            (`gait_planner.model.posture`).
        start: the phases of a start from standing, before the first half cycle (its
            first holds both feet flat; `gait_planner.ocp.transition`), each with a
            scaling of its own (numbered from 0 among start and stop phases); () if the
            scene declares none.
        stop: the phases of a stop after a half cycle of `phases` (the last ends standing
            at rest), numbered after the start's; () if none.
    """

    phases: tuple[Phase, ...]
    step_length: float
    mirror: Mapping[str, str]
    base_time_step: float
    scaling_bounds: tuple[float, float]
    friction_coefficient: float
    cost: str = "kinetic_energy"
    options: Mapping[str, object] = field(default_factory=lambda: MappingProxyType({}))
    start: tuple[Phase, ...] = ()
    stop: tuple[Phase, ...] = ()

    @property
    def n_scalings(self) -> int:
        return 1 + max(p.scaling for p in self.phases)


@dataclass(frozen=True)
class Hold:
    """A locked URDF joint whose holding effort the plan bounds (`gait_planner.model.
    urdf_holds`, the scene's ``robot.holds``): its held part, one side of the joint that
    only gravity and the joint act on, rigid in drafted body `body`.

    Attributes:
        name: the URDF joint.
        body: the drafted body the joint is merged into.
        side: +1 the held part is the joint's subtree (the effort acts on it), -1 it is
            the rest of the body (the effort is the reaction).
        effort: the URDF's effort limit, N m (|effort| <= it at every smooth node).
        axis: unit axis, the body's director components (the URDF's positive sense).
        point: the joint's origin, m, director components from the body's centre of mass.
        mass: the held part's mass, kg; com: its centre of mass (as `point`), m;
        inertia: (ixx, iyy, izz, ixy, ixz, iyz) kg m^2 at its centre of mass, directors.
    """

    name: str
    body: str
    side: int
    effort: float
    axis: Vec3
    point: Vec3
    mass: float
    com: Vec3
    inertia: tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class RobotSource:
    """The URDF a scene was drafted from (`gait_planner.model.urdf_import`, the scene file's
    ``robot:`` section): what the outputs publish as the robot's own description.

    Attributes:
        urdf_file: the URDF's path as the scene file gives it (relative: to that file).
        urdf: its text; "" where the scene was rebuilt without it (a recording's scene
            attachment: the recording's /robot_description holds it).
        links: body -> (position (m), rpy (rad)) of the body's URDF link frame in the body's
            frame (origin its centre of mass, axes its directors).
        locked: the URDF's joints held fixed (merged into their parent), name -> rad.
        package_dirs: folders that resolve the URDF's ``package://`` paths (relative: to the
            scene file).
        urdf_path: the URDF's absolute path: where it was read, or as the scene names it
            ("" for a relative name not read), for mesh paths relative to it.
        holds: the locked joints whose holding efforts the plan keeps within their limit.
    """

    urdf_file: str
    urdf: str
    links: Mapping[str, tuple[Vec3, Vec3]]
    locked: Mapping[str, float] = field(default_factory=lambda: MappingProxyType({}))
    package_dirs: tuple[str, ...] = ()
    urdf_path: str = ""
    holds: tuple[Hold, ...] = ()

    def search_dirs(self) -> tuple[str, ...]:
        """Where ``package://PKG/...`` paths are looked for: `package_dirs`, then the URDF's
        own folder and its parents (as ``gait-planner scene from-urdf`` looks)."""
        parents = [str(p) for p in Path(self.urdf_path).parents] if self.urdf_path else []
        return tuple(self.package_dirs) + tuple(parents)

    def link_pose(self, body: str) -> tuple[np.ndarray, np.ndarray]:
        """(position (3,), rotation (3, 3)) of `body`'s link frame in the body's frame."""
        position, rpy = self.links[body]
        return np.asarray(position, dtype=float), rpy_matrix(rpy)


@dataclass(frozen=True)
class Scene:
    """Everything a scene file declares. Bodies are in the order of the file."""

    name: str
    bodies: tuple[Body, ...]
    joints: tuple[Joint, ...]
    root: Root
    contacts: tuple[Contact, ...]
    initial_pose: InitialPose
    gravity: float = 9.81
    gait: Gait | None = None
    description: str = ""
    source: str = ""  # the scene file's text, kept for recordings
    gaits: tuple[str, ...] = ()  # its other gaits (`gaits:`), `model.loader.with_gait`
    robot: RobotSource | None = None  # the URDF it was drafted from (`robot:`)

    def body(self, name: str) -> Body:
        return next(b for b in self.bodies if b.name == name)

    def body_index(self, name: str) -> int:
        return [b.name for b in self.bodies].index(name)

    def contact(self, name: str) -> Contact:
        return next(c for c in self.contacts if c.name == name)

    @property
    def planar(self) -> bool:
        return self.root.type is RootType.PLANAR
