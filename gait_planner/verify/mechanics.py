"""The scene and mechanics of the independent verifier, written from docs/design.md sections 1-3 and 5-6 in numpy; nothing here comes from gait_planner.model, .dynamics or .ocp."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import yaml

MIRROR = np.array([1.0, -1.0, 1.0])  # the mirror y -> -y

# ----------------------------------------------------------------------------- the scene


@dataclass(frozen=True)
class BodyData:
    name: str
    mass: float
    inertia: tuple[float, float, float]
    points: dict[str, np.ndarray]
    # spheres (x, y, z, r) containing the body (`collision:`; m, director components)
    collision: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))


@dataclass(frozen=True)
class JointData:
    name: str
    type: str  # "spherical" | "revolute"
    parent: str
    parent_point: np.ndarray
    child: str
    child_point: np.ndarray
    axis: np.ndarray | None  # unit, parent's director components (revolute)
    reference: np.ndarray  # (3, 3) child's directors in the parent's at zero angle
    angles: tuple[str, ...]  # its angle (effort) names: j, or j_pitch, j_roll, j_yaw or
    # the spherical joint's angle_names


@dataclass(frozen=True)
class SceneData:
    """What the checks need from the scene file (plain data; joints in tree order)."""

    name: str
    gravity: float
    bodies: tuple[BodyData, ...]
    joints: tuple[JointData, ...]
    root: str
    planar: bool
    root_y: float
    contacts: dict[str, tuple[str, str]]  # contact -> (body, point)
    mirror: dict[str, str]  # body -> partner body (symmetric, total)
    phases: dict[str, tuple[int, tuple[str, ...]]]  # phase -> (scaling index, contacts)
    scaling_bounds: tuple[float, float] | None
    base_time_step: float | None
    options: dict[str, Any]
    # the start from standing and the stop phases (gait.start, gait.stop): (name, contacts)
    start_phases: tuple[tuple[str, tuple[str, ...]], ...] = ()
    stop_phases: tuple[tuple[str, tuple[str, ...]], ...] = ()
    # the URDF it was drafted from (`robot:`): root link pose (position, rotation) in the
    # root body's frame and the locked joints (name -> rad); None for hand-written scenes
    robot_root: tuple[np.ndarray, np.ndarray] | None = None
    robot_locked: dict[str, float] | None = None
    robot_links: dict[str, tuple[np.ndarray, np.ndarray]] | None = None  # every body's link

    def body_index(self, name: str) -> int:
        return [b.name for b in self.bodies].index(name)

    @property
    def contact_partners(self) -> dict[str, str]:
        """contact -> the contact at the same point of its body's mirror partner."""
        return {c: next(d for d, (bd, pd) in self.contacts.items()
                        if bd == self.mirror[bc] and pd == pc)
                for c, (bc, pc) in self.contacts.items()}


def parse_scene(text: str) -> SceneData:
    """The scene attached to a recording, from its YAML text (plain safe loading, by libyaml
    where PyYAML has it: walker3d's scene in 1.3 instead of 11 ms, once or twice a plan)."""
    data = yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))  # noqa: S506
    if not isinstance(data, dict):
        raise ValueError("the attached scene is not a YAML mapping")
    bodies = tuple(
        BodyData(str(b["name"]), float(b["mass"]), tuple(float(j) for j in b["inertia"]),
                 {str(p): np.asarray(v, dtype=float) for p, v in (b.get("points") or {}).items()},
                 np.asarray(b.get("collision") or np.zeros((0, 4)), dtype=float).reshape(-1, 4))
        for b in data["bodies"])
    by_name = {b.name: b for b in bodies}
    joints = []
    for j in data["joints"]:
        axis, reference = None, _rpy(j.get("reference_rpy") or (0.0, 0.0, 0.0))
        if j["type"] == "revolute":
            axis = np.asarray(j["axis"], dtype=float)
            axis = axis / np.linalg.norm(axis)
        elif j["type"] != "spherical":
            raise ValueError(f"joint {j['name']!r}: unknown type {j['type']!r}")
        angles = (str(j["name"]),) if axis is not None else tuple(
            str(a) for a in j.get("angle_names") or
            [f"{j['name']}_{a}" for a in ("pitch", "roll", "yaw")])
        joints.append(JointData(
            str(j["name"]), str(j["type"]), str(j["parent"]),
            by_name[j["parent"]].points[j["parent_point"]], str(j["child"]),
            by_name[j["child"]].points[j["child_point"]], axis, reference, angles))
    root = str(data["root"]["body"])
    ordered, stack = [], [j for j in joints if j.parent == root][::-1]
    while stack:  # depth first from the root: parents before children
        joint = stack.pop()
        ordered.append(joint)
        stack.extend([j for j in joints if j.parent == joint.child][::-1])
    if len(ordered) != len(joints):
        raise ValueError("the scene's joints do not form one tree on the root")
    contacts = {str(c["name"]): (str(c["body"]), str(c["point"])) for c in data["contacts"]}
    gait = data.get("gait") or {}
    mirror = {b.name: b.name for b in bodies}
    for a, b in (gait.get("mirror") or {}).items():
        mirror[str(a)], mirror[str(b)] = str(b), str(a)
    phases = {str(p["name"]): (int(p["scaling"]), tuple(str(c) for c in p["contacts"]))
              for p in gait.get("phases") or ()}
    bounds = gait.get("scaling_bounds")

    def ends(key):
        return tuple((str(p["name"]), tuple(str(c) for c in p["contacts"]))
                     for p in gait.get(key) or ())

    return SceneData(
        name=str(data["name"]), gravity=float(data.get("gravity", 9.81)), bodies=bodies,
        joints=tuple(ordered), root=root, planar=data["root"]["type"] == "planar",
        root_y=float(data["initial_pose"]["root_position"][1]), contacts=contacts,
        mirror=mirror, phases=phases,
        scaling_bounds=tuple(float(b) for b in bounds) if bounds else None,
        base_time_step=float(gait["base_time_step"]) if "base_time_step" in gait else None,
        options=dict(gait.get("options") or {}), start_phases=ends("start"),
        stop_phases=ends("stop"), **_robot(data.get("robot"), root))


def _robot(robot: Any, root: str) -> dict[str, Any]:
    """SceneData's robot fields of a ``robot:`` section (or none)."""
    if not robot:
        return {}
    links = {str(body): (np.asarray([float(v) for v in pose[:3]]),
                         _rpy([float(v) for v in pose[3:]]))
             for body, pose in robot["links"].items()}
    return {"robot_root": links[root], "robot_links": links,
            "robot_locked": {str(k): float(v) for k, v in (robot.get("locked") or {}).items()}}


def _rpy(rpy) -> np.ndarray:
    """Rz(y) Ry(p) Rx(r) of a joint's reference_rpy (r, p, y) rad (URDF's convention)."""
    (cr, sr), (cp, sp), (cy, sy) = ((np.cos(float(a)), np.sin(float(a))) for a in rpy)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


# ----------------------------------------------------------------------------- mechanics


def _perpendicular(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors a, b with (n, a, b) orthonormal (Gram-Schmidt on the world axes)."""
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    a = helper - (helper @ n) * n
    a = a / np.linalg.norm(a)
    return a, np.cross(n, a)


class Mechanics:
    """Director-coordinate mechanics of a `SceneData`, in numpy (docs/design.md sections 1-3).

    q (k,) = per body (phi, d1, d2, d3), bodies in scene order. Every function accepts
    real or complex q (complex-step differentiation of `constraint_values`)."""

    def __init__(self, scene: SceneData):
        self.scene = scene
        self.nb = len(scene.bodies)
        self.k = 12 * self.nb
        diag = []
        for b in scene.bodies:
            half = 0.5 * sum(b.inertia)
            diag += [b.mass] * 3 + [half - j for j in b.inertia for _ in range(3)]
        self.mass_diagonal = np.array(diag)
        self.gravity_gradient = np.zeros(self.k)
        for i, b in enumerate(scene.bodies):
            self.gravity_gradient[12 * i + 2] = b.mass * scene.gravity
        self.frames = {}
        for joint in scene.joints:
            if joint.axis is not None:  # normal to the axis in child components, R0^T n
                self.frames[joint.name] = _perpendicular(joint.reference.T @ joint.axis)
        groups = [("internal", 6 * self.nb)]
        groups += [(f"joint {j.name}", 3 if j.type == "spherical" else 5) for j in scene.joints]
        if scene.planar:
            groups.append(("planar root", 3))
        self.groups = groups
        self.m = sum(size for _, size in groups)

    # layout
    def start(self, body: str) -> int:
        return 12 * self.scene.body_index(body)

    def phi(self, q, body):
        s = self.start(body)
        return q[..., s:s + 3]

    def director(self, q, body, i):
        s = self.start(body) + 3 + 3 * i
        return q[..., s:s + 3]

    def directors(self, q, body):
        """(.., 3, 3) with columns d1, d2, d3."""
        s = self.start(body)
        return np.stack([q[..., s + 3:s + 6], q[..., s + 6:s + 9], q[..., s + 9:s + 12]], axis=-1)

    def point_matrix(self, body: str, X: np.ndarray) -> np.ndarray:
        """C (3, k): world position C q = phi + X_i d_i of body point X."""
        C = np.zeros((3, self.k))
        s = self.start(body)
        C[:, s:s + 3] = np.eye(3)
        for i in range(3):
            C[:, s + 3 + 3 * i:s + 6 + 3 * i] = X[i] * np.eye(3)
        return C

    def contact_matrix(self, name: str) -> np.ndarray:
        body, point = self.scene.contacts[name]
        return self.point_matrix(body, self.scene.bodies[self.scene.body_index(body)].points[point])

    # constraints
    def constraint_values(self, q: np.ndarray) -> np.ndarray:
        """g(q) (m,) in the order of `groups`."""
        rows = []
        for b in self.scene.bodies:
            d = [self.director(q, b.name, i) for i in range(3)]
            rows += [0.5 * (d[0] @ d[0] - 1), 0.5 * (d[1] @ d[1] - 1), 0.5 * (d[2] @ d[2] - 1),
                     d[0] @ d[1], d[0] @ d[2], d[1] @ d[2]]
        for j in self.scene.joints:
            Dp, Dc = self.directors(q, j.parent), self.directors(q, j.child)
            gap = self.phi(q, j.parent) + Dp @ j.parent_point - self.phi(q, j.child) \
                - Dc @ j.child_point
            rows += list(gap)
            if j.axis is not None:
                a, b = self.frames[j.name]
                n_world = Dp @ j.axis
                rows += [n_world @ (Dc @ a), n_world @ (Dc @ b)]
        if self.scene.planar:
            d2 = self.director(q, self.scene.root, 1)
            rows += [self.phi(q, self.scene.root)[1] - self.scene.root_y, d2[0], d2[2]]
        return np.array(rows)

    def constraint_jacobian(self, q: np.ndarray) -> np.ndarray:
        """G(q) = dg/dq (m, k), analytic."""
        G = np.zeros((self.m, self.k))
        r = 0
        for b in self.scene.bodies:
            s = self.start(b.name)
            d = [q[s + 3 + 3 * i:s + 6 + 3 * i] for i in range(3)]
            for i in range(3):
                G[r + i, s + 3 + 3 * i:s + 6 + 3 * i] = d[i]
            for row, (i, j) in enumerate(((0, 1), (0, 2), (1, 2)), start=r + 3):
                G[row, s + 3 + 3 * i:s + 6 + 3 * i] = d[j]
                G[row, s + 3 + 3 * j:s + 6 + 3 * j] = d[i]
            r += 6
        for j in self.scene.joints:
            sp, sc = self.start(j.parent), self.start(j.child)
            G[r:r + 3, sp:sp + 3] += np.eye(3)
            G[r:r + 3, sc:sc + 3] -= np.eye(3)
            for i in range(3):
                G[r:r + 3, sp + 3 + 3 * i:sp + 6 + 3 * i] += j.parent_point[i] * np.eye(3)
                G[r:r + 3, sc + 3 + 3 * i:sc + 6 + 3 * i] -= j.child_point[i] * np.eye(3)
            r += 3
            if j.axis is not None:
                Dp, Dc = self.directors(q, j.parent), self.directors(q, j.child)
                n_world = Dp @ j.axis
                for vec in self.frames[j.name]:
                    c_world = Dc @ vec
                    for i in range(3):
                        G[r, sp + 3 + 3 * i:sp + 6 + 3 * i] += j.axis[i] * c_world
                        G[r, sc + 3 + 3 * i:sc + 6 + 3 * i] += vec[i] * n_world
                    r += 1
        if self.scene.planar:
            s = self.start(self.scene.root)
            G[r, s + 1] = 1.0
            G[r + 1, s + 6] = 1.0
            G[r + 2, s + 8] = 1.0
            r += 3
        assert r == self.m
        return G

    # dynamics
    def d1_ld(self, q0, q1, h):
        return -self.mass_diagonal * (q1 - q0) / h - 0.5 * h * self.gravity_gradient

    def d2_ld(self, q0, q1, h):
        return self.mass_diagonal * (q1 - q0) / h - 0.5 * h * self.gravity_gradient

    def potential_energy(self, q):
        return q @ self.gravity_gradient

    # mirror
    def mirror(self, q: np.ndarray, step: float, rise: float = 0.0) -> np.ndarray:
        """mirror(q) + step e_x + rise e_z (m): each body's image in its partner body, its
        position shifted by the step and by the ground's rise over it (ramp: step tan(slope),
        stairs: the step height; `gait_planner.verify.ground`)."""
        out = np.zeros_like(q)
        for b in self.scene.bodies:
            src, dst = self.start(b.name), self.start(self.scene.mirror[b.name])
            for j, sign in enumerate((1.0, 1.0, -1.0, 1.0)):
                out[dst + 3 * j:dst + 3 * j + 3] = sign * MIRROR * q[src + 3 * j:src + 3 * j + 3]
            out[dst] += step
            out[dst + 2] += rise
        return out


