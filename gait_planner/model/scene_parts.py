"""The parts of a scene file, each parsed and checked: its bodies (masses, inertias that a
body can have, points), joints (their axes, angle names, and the tree they make from the
root, reordered depth-first), contacts and initial pose. `gait_planner.model.loader` reads
the file and builds the `Scene` from them; every error names the key path
(`model._validate.Checker`).
"""

from __future__ import annotations

import math
from types import MappingProxyType
from typing import Any

from gait_planner.model._validate import Checker, join
from gait_planner.model.scene import Body, Contact, InitialPose, Joint, JointType, Root, RootType

__all__ = ["parse_bodies", "parse_contacts", "parse_initial_pose", "parse_joints"]

_SPHERICAL_ANGLES = ("pitch", "roll", "yaw")  # the order of gait_planner.model.angles
_MIN_AXIS_NORM = 1e-9
_PLANAR_AXIS = (0.0, 1.0, 0.0)
_INERTIA_TOLERANCE = 1e-12  # relative round-off allowed in E_i >= 0


def parse_bodies(c: Checker, value: Any, allow_nonphysical: bool) -> tuple[Body, ...]:
    """The `bodies:` list: each a name, a mass (kg), principal inertias (kg m^2) a rigid body
    can have (`_check_inertia`), body-fixed points (m, from the centre of mass), an
    optional length (m) and optional collision spheres ([x, y, z, r] m, r > 0); in the
    file's order."""
    items = c.named_list(value, "bodies", "body")
    if not items:
        c.fail("bodies", "must list at least one body")
    bodies = []
    for i, item in enumerate(items):
        key = join("bodies", i)
        b = c.mapping(item, key, ("name", "mass", "inertia"),
                      ("length", "points", "collision"))
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
            collision=_spheres(c, b.get("collision", []), join(key, "collision")),
        )
        _check_inertia(c, body, join(key, "inertia"), allow_nonphysical)
        bodies.append(body)
    return tuple(bodies)


def _spheres(c: Checker, value: Any, key: str) -> tuple[tuple[float, ...], ...]:
    """A body's `collision:` list of spheres [x, y, z, r] (m; r > 0)."""
    out = []
    for i, sphere in enumerate(c.sequence(value, key)):
        x, y, z, r = c.vector(sphere, join(key, i), 4)
        out.append((x, y, z, c.number(r, join(join(key, i), 3), positive=True)))
    return tuple(out)


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


def parse_joints(c: Checker, value: Any, bodies: tuple[Body, ...], root: Root) -> tuple[Joint, ...]:
    """The `joints:` list: each joint's ends, type, axis and angle names, the joints as one
    tree on `bodies` from `root`, ordered depth-first (`_tree_order`)."""
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


def parse_contacts(c: Checker, value: Any, bodies: tuple[Body, ...]) -> tuple[Contact, ...]:
    """The `contacts:` list: each a name and a point of one of `bodies`."""
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


def parse_initial_pose(c: Checker, value: Any, joints: tuple[Joint, ...],
                       root: Root) -> InitialPose:
    """The `initial_pose:` block: the root's position (m) and angles (rad), the joints'
    angles (rad, by joint name; the count each joint's type takes)."""
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

