"""Continuous-dynamics certificate of a plan: is the published motion a physical motion of a
real body, with the published torques and ground forces?

Inverse dynamics of the continuous rigid-body model (Pinocchio's RNEA) at every inner node
n = 1..N-1, from the published configurations q (director coordinates), joint efforts and
ground forces; nothing here comes from gait_planner.model, .dynamics or .ocp (the scene is
`gait_planner.verify.mechanics.parse_scene`'s plain data).

* Model: the root body on a free-flyer joint at its centre of mass with its principal-axis
  frame (directors d1, d2, d3 = the body axes); every scene joint placed at its parent
  point (measured from the parent joint's origin, rotated by the joint's zero-angle
  reference R0: the identity for the built-in walkers, whose body frames are all aligned
  upright), spherical (JointModelSpherical) or revolute about its axis in the child's
  directors (R0^T n); each child body's inertia (mass, diag(J1, J2, J3) at its centre of mass,
  which sits at minus the child point from the joint). RNEA needs no realisable inertia, so
  the paper's torso (J1 > J2 + J3) is accepted. Planar scenes get a free-flyer too, and only
  the in-plane base residual (world force x, z; moment y) is judged: the out-of-plane part is
  the planar constraint's reaction.
* Motion: q_n -> Pinocchio's q (root COM and quaternion of R = [d1 d2 d3]; spherical joint
  quaternion of R_rel = R_p^T R_c; revolute angle of R_rel about the axis). Velocity and
  acceleration by central differences on the configuration group (pinocchio.difference):
  xi+ = diff(q_n, q_{n+1})/h_n, xi- = -diff(q_n, q_{n-1})/h_{n-1}, a_n = (xi+ - xi-)/w_n,
  v_n = (h_{n-1} xi+ + h_n xi-)/(h_{n-1} + h_n), w_n = (h_{n-1} + h_n)/2: what the discrete
  Euler-Lagrange equation at node n sees, second-order accurate on smooth motion. The
  velocity terms (Coriolis, centrifugal) C(v_n) are replaced by their average over the two
  intervals, (h_{n-1} C(xi-) + h_n C(xi+))/(h_{n-1} + h_n): the same to O(h^2) on smooth
  motion, but at an impact (velocity jump dv) C(v_n) leaves an error (1/4) C(dv) dv that
  does not shrink with h (test/verify: 0.5 N m at a forefoot impact, 1e-3 N m averaged).
* Forces: gravity -g e_z; the ground wrench on each foot as an external force of its joint
  (local frame, about the joint origin). RNEA's joint torques are converted to efforts
  conjugate to the published angles (spherical, R_rel = Ry(pitch) Rx(roll) Rz(yaw):
  e = E^T m_local with omega_local = E (pitch', roll', yaw')', E's columns
  Rz(yaw)^T Rx(roll)^T e_y, Rz(yaw)^T e_x, e_z; revolute: the moment about the axis) and
  compared with effort[n] (the node torque node n's equation applies). The free-flyer
  torque is the base residual: the force and moment (about the root COM, world frame) that
  nothing in the plan supplies.
* Verdict (`LIMITS`): judged separately away from contact switches and at them (a node
  whose set of held contacts differs from the previous one's, and both neighbours), where
  an impact or a lift-off makes the motion non-smooth. Measured on simulated motion
  (test/verify): the error falls like h^2, 0.07 % / 0.02 % of the peak torque at 2 / 1 ms.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin

from gait_planner.verify.mechanics import SceneData

# Judged maxima: torque error relative to the plan's peak |effort|, base force relative to
# the body weight, base moment relative to weight x MOMENT_ARM; "switch" = at a contact
# switch or next to it (central differences straddle a velocity jump there).
LIMITS = {"torque": 0.002, "torque_switch": 0.02, "force": 0.01, "moment": 0.01}
MOMENT_ARM = 1.0  # m


@dataclass(frozen=True)
class ContinuousCertificate:
    """Inverse dynamics of the published plan at the inner nodes (n_in = N - 1 of them).

    nodes (n_in,) node indices 1..N-1; times (n_in,) s; joint_names (na,) effort names;
    torque_error (n_in, na) N m = RNEA effort - published effort; torque_error_relative
    (n_in, na) = torque_error / peak_effort; base_force (n_in,) N and base_moment (n_in,) N m
    = norms of the free-flyer residual (world; planar scenes: in-plane components only);
    near_switch (n_in,) bool: node whose contact set differs from a neighbour's, or next to
    one; max_* (relative torque, N, N m) away from switches ("calm") and at them;
    wrench_source: "recorded" (published foot wrenches) or "point forces" (sum of point
    forces and p x f: the full-contact roll moment about the heel-toe line is missing)."""

    scene: str
    planar: bool
    nodes: np.ndarray
    times: np.ndarray
    joint_names: tuple[str, ...]
    torque_error: np.ndarray
    torque_error_relative: np.ndarray
    base_force: np.ndarray
    base_moment: np.ndarray
    near_switch: np.ndarray
    peak_effort: float  # N m, max |effort| over all joints and nodes
    weight: float  # N, total mass x g
    wrench_source: str

    def _max(self, values: np.ndarray, switch: bool) -> float:
        rows = values[self.near_switch == switch]
        return float(np.abs(rows).max()) if rows.size else 0.0

    # maxima of |value| away from switches ("calm") and at them
    max_torque_calm = property(lambda self: self._max(self.torque_error_relative, False))
    max_torque_switch = property(lambda self: self._max(self.torque_error_relative, True))
    max_force_calm = property(lambda self: self._max(self.base_force, False))  # N
    max_force_switch = property(lambda self: self._max(self.base_force, True))  # N
    max_moment_calm = property(lambda self: self._max(self.base_moment, False))  # N m
    max_moment_switch = property(lambda self: self._max(self.base_moment, True))  # N m

    @property
    def failures(self) -> tuple[str, ...]:
        out = []
        for value, limit, what in (
                (self.max_torque_calm, LIMITS["torque"],
                 "torque error (of peak) away from switches"),
                (self.max_torque_switch, LIMITS["torque_switch"],
                 "torque error (of peak) at switches"),
                (self.max_force_calm / self.weight, LIMITS["force"], "base force (of weight)"),
                (self.max_moment_calm / (self.weight * MOMENT_ARM), LIMITS["moment"],
                 f"base moment (of weight x {MOMENT_ARM:g} m)")):
            if not value <= limit:  # NaN fails
                out.append(f"{what} {100 * value:.3g} % > {100 * limit:.3g} %")
        return tuple(out)

    @property
    def ok(self) -> bool:
        return not self.failures

    def summary(self) -> str:
        """One line: the maxima, the limits' verdict and where the ground wrenches came from."""
        return (f"continuous dynamics ({self.scene}, {self.wrench_source}): torque error "
                f"{100 * self.max_torque_calm:.3g} % of peak {self.peak_effort:.4g} N m "
                f"({100 * self.max_torque_switch:.3g} % at switches), base residual "
                f"{self.max_force_calm:.3g} N = {100 * self.max_force_calm / self.weight:.3g} % "
                f"of weight ({self.max_force_switch:.3g} N at switches), "
                f"{self.max_moment_calm:.3g} N m ({self.max_moment_switch:.3g} N m at switches): "
                + ("OK" if self.ok else "FAILED: " + "; ".join(self.failures)))


# ----------------------------------------------------------------------------- the model


def effort_names(scene: SceneData) -> tuple[str, ...]:
    """Effort (joint angle) names in scene joint order: j_pitch, j_roll, j_yaw (or the
    spherical joint's angle_names) or j."""
    return tuple(n for j in scene.joints for n in j.angles)


def _revolute(axis: np.ndarray):
    """RX/RY/RZ for a world axis (e.g. knees: RY), RevoluteUnaligned otherwise."""
    aligned = [i for i in range(3) if np.array_equal(axis, np.eye(3)[i])]
    kinds = (pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)
    return kinds[aligned[0]]() if aligned else pin.JointModelRevoluteUnaligned(axis)


def build_model(scene: SceneData) -> tuple[pin.Model, dict[str, int]]:
    """(Pinocchio model, body name -> id of the joint that carries it) of `scene`."""
    bodies = {b.name: b for b in scene.bodies}
    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, 0.0, -scene.gravity]), np.zeros(3))

    def inertia(name: str, com: np.ndarray) -> pin.Inertia:
        return pin.Inertia(bodies[name].mass, com, np.diag(bodies[name].inertia))

    joint_of = {scene.root: model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(),
                                           scene.root)}
    origin = {scene.root: np.zeros(3)}  # joint origin from the body's COM (body frame)
    model.appendBodyToJoint(joint_of[scene.root], inertia(scene.root, np.zeros(3)),
                            pin.SE3.Identity())
    for j in scene.joints:  # parents before children (parse_scene's order)
        # a revolute joint's frame: R_rel = R0 Rot(R0^T n, angle) = Rot(n, angle) R0
        kind = pin.JointModelSpherical() if j.axis is None else \
            _revolute(j.reference.T @ j.axis)
        placement = pin.SE3(j.reference, j.parent_point - origin[j.parent])
        joint_of[j.child] = model.addJoint(joint_of[j.parent], kind, placement, j.name)
        origin[j.child] = np.asarray(j.child_point, dtype=float)
        model.appendBodyToJoint(joint_of[j.child], inertia(j.child, -origin[j.child]),
                                pin.SE3.Identity())
    return model, joint_of


def _frames(scene: SceneData, q_row: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """body -> (phi (3,), R (3, 3) = [d1 d2 d3]) of one director configuration (k,)."""
    return {b.name: (q_row[12 * i:12 * i + 3], q_row[12 * i + 3:12 * i + 12].reshape(3, 3).T)
            for i, b in enumerate(scene.bodies)}


def _quaternion(R: np.ndarray) -> np.ndarray:
    U, _, Vt = np.linalg.svd(R)  # nearest rotation (directors orthonormal to round-off)
    return pin.Quaternion(U @ Vt).coeffs()  # (x, y, z, w)


def _revolute_angle(R: np.ndarray, axis: np.ndarray) -> float:
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return float(np.arctan2(0.5 * w @ axis, 0.5 * (np.trace(R) - 1.0)))


def pin_configuration(scene: SceneData, model: pin.Model, q_row: np.ndarray) -> np.ndarray:
    """Pinocchio's q (nq,) of one director configuration q_row (k,)."""
    frames = _frames(scene, np.asarray(q_row, dtype=float))
    out = np.zeros(model.nq)
    phi, R = frames[scene.root]
    out[:3], out[3:7] = phi, _quaternion(R)
    for j in scene.joints:
        R_rel = frames[j.parent][1].T @ frames[j.child][1]
        s = model.joints[model.getJointId(j.name)].idx_q
        if j.axis is None:
            out[s:s + 4] = _quaternion(R_rel)
        else:
            out[s] = _revolute_angle(R_rel @ j.reference.T, j.axis)
    return out


def cardan_efforts(R_rel: np.ndarray, m_local: np.ndarray) -> np.ndarray:
    """(pitch, roll, yaw) efforts (3,) conjugate to R_rel = Ry(pitch) Rx(roll) Rz(yaw) of a
    joint moment m_local (3,) in child components (Pinocchio's spherical joint torque)."""
    roll = np.arctan2(-R_rel[1, 2], np.hypot(R_rel[0, 2], R_rel[2, 2]))
    yaw = np.arctan2(R_rel[1, 0], R_rel[1, 1])
    cr, sr, cy, sy = np.cos(roll), np.sin(roll), np.cos(yaw), np.sin(yaw)
    E = np.array([[cr * sy, cy, 0.0], [cr * cy, -sy, 0.0], [-sr, 0.0, 1.0]])
    return E.T @ m_local


# ----------------------------------------------------------------------------- the certificate


def switch_mask(active: Sequence[Sequence[str]]) -> np.ndarray:
    """(N+1,) bool: nodes whose contact set differs from the previous node's, and neighbours."""
    out = np.zeros(len(active), dtype=bool)
    for n in range(1, len(active)):
        if set(active[n]) != set(active[n - 1]):
            out[n - 1:n + 2] = True  # n-1 (the last node of the old set), n, n+1
    return out


def local_force(R: np.ndarray, origin: np.ndarray, wrench: np.ndarray) -> "pin.Force":
    """A world wrench (6,) (force, moment about the world origin) as Pinocchio's external
    force on a joint at `origin` (3,) with rotation `R` (3, 3): local force and moment."""
    f, m_origin = np.asarray(wrench[:3]), np.asarray(wrench[3:])
    return pin.Force(R.T @ f, R.T @ (m_origin - np.cross(origin, f)))


def inverse_dynamics(model: "pin.Model", configs: Sequence[np.ndarray], times: np.ndarray,
                     external) -> list[np.ndarray]:
    """RNEA's generalized forces (nv,) at the inner nodes 1..N-1 of configurations `configs`
    (N+1 of Pinocchio's q) at `times` (N+1,) s: central differences and the averaged
    velocity terms of the module docstring; external(n, data) gives node n's external
    forces per joint (called after forward kinematics at node n: data.oMi is set)."""
    data = model.createData()
    h = np.diff(times)
    out = []
    for n in range(1, len(configs) - 1):
        xi_plus = pin.difference(model, configs[n], configs[n + 1]) / h[n]
        xi_minus = -pin.difference(model, configs[n], configs[n - 1]) / h[n - 1]
        a = (xi_plus - xi_minus) / (0.5 * (h[n - 1] + h[n]))
        v = (h[n - 1] * xi_plus + h[n] * xi_minus) / (h[n - 1] + h[n])
        pin.forwardKinematics(model, data, configs[n])
        tau = pin.rnea(model, data, configs[n], v, a, external(n, data))
        # velocity terms C(.) averaged over the two intervals (module docstring)
        wm, wp = h[n - 1] / (h[n - 1] + h[n]), h[n] / (h[n - 1] + h[n])
        tau += (wm * pin.nonLinearEffects(model, data, configs[n], xi_minus)
                + wp * pin.nonLinearEffects(model, data, configs[n], xi_plus)
                - pin.nonLinearEffects(model, data, configs[n], v))
        out.append(tau.copy())
    return out


def certificate(scene: SceneData, times: np.ndarray, q: np.ndarray, efforts: np.ndarray,
                foot_wrenches: Mapping[str, np.ndarray],
                active_contacts: Sequence[Sequence[str]],
                wrench_source: str = "recorded") -> ContinuousCertificate:
    """The certificate of a plan given as plain arrays.

    times (N+1,) s; q (N+1, 12 nb) director coordinates; efforts (N+1, na) N m in the order
    of `effort_names(scene)`; foot_wrenches: body -> (N+1, 6) force (N) and moment (N m) of
    the ground on that body about the world origin, world frame (zero without contact);
    active_contacts: N+1 collections of contact names (for the switch mask)."""
    times, q, efforts = (np.asarray(a, dtype=float) for a in (times, q, efforts))
    n_nodes, names = q.shape[0], effort_names(scene)
    if efforts.shape != (n_nodes, len(names)) or n_nodes < 3:
        raise ValueError(f"efforts {efforts.shape} do not match q {q.shape} and {len(names)} "
                         "effort names (at least 3 nodes)")
    model, joint_of = build_model(scene)
    configs = [pin_configuration(scene, model, row) for row in q]
    slots = {j.name: model.joints[model.getJointId(j.name)].idx_v for j in scene.joints}

    def external(n: int, data) -> list:
        frames = _frames(scene, q[n])
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        for body, wrench in foot_wrenches.items():
            phi, R = frames[body]
            origin = phi + R @ (np.zeros(3) if body == scene.root else
                                next(j.child_point for j in scene.joints if j.child == body))
            fext[joint_of[body]] = local_force(R, origin, wrench[n])
        return fext

    torque, force, moment = [], [], []
    for n, tau in enumerate(inverse_dynamics(model, configs, times, external), start=1):
        frames = _frames(scene, q[n])
        R_root = frames[scene.root][1]
        base_f, base_m = R_root @ tau[:3], R_root @ tau[3:6]
        if scene.planar:
            base_f, base_m = base_f[[0, 2]], base_m[[1]]
        force.append(np.linalg.norm(base_f))
        moment.append(np.linalg.norm(base_m))
        row = []
        for j in scene.joints:
            s = slots[j.name]
            if j.axis is None:
                R_rel = frames[j.parent][1].T @ frames[j.child][1]
                row += list(cardan_efforts(R_rel, tau[s:s + 3]))
            else:
                row.append(tau[s])
        torque.append(row)
    error = np.array(torque) - efforts[1:-1]
    peak = float(np.abs(efforts).max()) or 1.0
    return ContinuousCertificate(
        scene=scene.name, planar=scene.planar, nodes=np.arange(1, n_nodes - 1),
        times=times[1:-1], joint_names=names, torque_error=error,
        torque_error_relative=error / peak, base_force=np.array(force),
        base_moment=np.array(moment), near_switch=switch_mask(active_contacts)[1:-1],
        peak_effort=peak, weight=sum(b.mass for b in scene.bodies) * scene.gravity,
        wrench_source=wrench_source)


def foot_wrenches_of_recording(rec, scene: SceneData) -> tuple[dict[str, np.ndarray], str]:
    """(body -> (N+1, 6) ground wrench about the world origin, source) of a `RecordedPlan`.

    The recorded per-foot wrenches are preferred (per node: rec.wrench_bodies names,
    rec.wrench_points (b, 3), rec.wrenches (b, 6): force, moment of the ground on the foot
    about its point, world; they include the full-contact roll moment about the heel-toe
    line). TRANSITION HOOK: a recording without them (made before ContactForces carried
    them: empty per node) falls back to the point
    forces (sum f, sum p x f), which miss that roll moment."""
    n_nodes = len(rec.times)
    out = {body: np.zeros((n_nodes, 6)) for body, _ in scene.contacts.values()}
    bodies = rec.wrench_bodies
    if any(len(b) for b in bodies):
        for n in range(n_nodes):
            for body, p, w in zip(bodies[n], np.asarray(rec.wrench_points[n]).reshape(-1, 3),
                                  np.asarray(rec.wrenches[n]).reshape(-1, 6)):
                out.setdefault(body, np.zeros((n_nodes, 6)))
                out[body][n] += np.concatenate([w[:3], w[3:] + np.cross(p, w[:3])])
        return out, "recorded"
    for n in range(n_nodes):
        for name, p, f in zip(rec.contact_names[n], np.asarray(rec.contact_points[n]),
                              np.asarray(rec.contact_force_vectors[n])):
            out[scene.contacts[name][0]][n] += np.concatenate([f, np.cross(p, f)])
    return out, "point forces"
