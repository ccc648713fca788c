"""The continuous model of a scene pinned at one contact point, for `integrators.py`: a
fixed-base Pinocchio model in minimal coordinates re-rooted at that point, the map from the
VI's director coordinates to its state, and the right-hand side of its equations of motion.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import pinocchio as pin

from gait_planner.verify.mechanics import SceneData


def _quaternion(R: np.ndarray) -> np.ndarray:
    U, _, Vt = np.linalg.svd(R)  # nearest rotation
    return pin.Quaternion(U @ Vt).coeffs()  # (x, y, z, w)


def _rotation(quat: np.ndarray) -> np.ndarray:
    """The rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = quat
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _angular_velocities(q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """(nb, 3) world angular velocities omega = 1/2 sum_i d_i x d_i' of director rates."""
    d = q.reshape(-1, 4, 3)[:, 1:]
    dd = qdot.reshape(-1, 4, 3)[:, 1:]
    return 0.5 * np.cross(d, dd).sum(axis=1)


class PinnedModel:
    """The scene re-rooted at a pinned contact point: a fixed-base Pinocchio model in
    minimal coordinates (see the module docstring) and the maps from director coordinates.

    Body frames: origin at the joint that carries the body (the pinned point for the
    pinned body), axes the body's principal axes (the directors). `body_joint` maps each
    body to that joint's id; `edges` lists (joint id, new parent, new child, scene joint)."""

    def __init__(self, scene: SceneData, contact: str, anchor: np.ndarray):
        self.scene = scene
        bodies = {b.name: b for b in scene.bodies}
        body, point = scene.contacts[contact]
        model = pin.Model()
        model.gravity = pin.Motion(np.array([0.0, 0.0, -scene.gravity]), np.zeros(3))
        origin = {body: bodies[body].points[point]}  # joint origin, body coordinates
        self.body_joint = {body: model.addJoint(0, pin.JointModelSpherical(),
                                                pin.SE3(np.eye(3), anchor), contact)}
        self.edges, queue = [], [body]
        while queue:  # breadth first over the joint graph from the pinned body
            a = queue.pop(0)
            for j in scene.joints:
                if a not in (j.parent, j.child) or {j.parent, j.child} <= set(origin):
                    continue
                b, at_a, at_b = ((j.child, j.parent_point, j.child_point) if j.parent == a
                                 else (j.parent, j.child_point, j.parent_point))
                kind = (pin.JointModelSpherical() if j.axis is None
                        else pin.JointModelRevoluteUnaligned(j.axis))
                jid = model.addJoint(self.body_joint[a], kind,
                                     pin.SE3(np.eye(3), at_a - origin[a]), j.name)
                self.body_joint[b], origin[b] = jid, np.asarray(at_b, dtype=float)
                self.edges.append((jid, a, b, j))
                queue.append(b)
        self.com = {}
        for name, jid in self.body_joint.items():
            self.com[name] = -origin[name]
            model.appendBodyToJoint(jid, pin.Inertia(bodies[name].mass, -origin[name],
                                                     np.diag(bodies[name].inertia)),
                                    pin.SE3.Identity())
        self.model, self.data = model, model.createData()
        spherical = [j for j in range(1, model.njoints) if model.joints[j].nq == 4]
        self.quat_q = np.array([np.arange(4) + model.joints[j].idx_q for j in spherical])
        self.quat_v = np.array([np.arange(3) + model.joints[j].idx_v for j in spherical])
        revolute = [j for j in range(1, model.njoints) if model.joints[j].nq == 1]
        self.rev_q = np.array([model.joints[j].idx_q for j in revolute], dtype=int)
        self.rev_v = np.array([model.joints[j].idx_v for j in revolute], dtype=int)
        self.index = {b.name: i for i, b in enumerate(scene.bodies)}

    # ---- director coordinates -> Pinocchio --------------------------------------------

    def _rotation(self, q_dir: np.ndarray, body: str) -> np.ndarray:
        i = self.index[body]
        return q_dir[12 * i + 3:12 * i + 12].reshape(3, 3).T  # [d1 d2 d3]

    def state(self, q_dir: np.ndarray, qdot_dir: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pinocchio (q (nq,), v (nv,)) of a director configuration and velocity (k,)."""
        q, v = np.zeros(self.model.nq), np.zeros(self.model.nv)
        omega = dict(zip([b.name for b in self.scene.bodies],
                         _angular_velocities(q_dir, qdot_dir)))
        pinned = next(b for b, j in self.body_joint.items() if j == 1)
        R = self._rotation(q_dir, pinned)
        q[0:4], v[0:3] = _quaternion(R), R.T @ omega[pinned]
        for jid, a, b, joint in self.edges:
            Ra, Rb = self._rotation(q_dir, a), self._rotation(q_dir, b)
            R_rel, w_rel = Ra.T @ Rb, Rb.T @ (omega[b] - omega[a])
            s, t = self.model.joints[jid].idx_q, self.model.joints[jid].idx_v
            if joint.axis is None:
                q[s:s + 4], v[t:t + 3] = _quaternion(R_rel), w_rel
            else:
                w = np.array([R_rel[2, 1] - R_rel[1, 2], R_rel[0, 2] - R_rel[2, 0],
                              R_rel[1, 0] - R_rel[0, 1]])
                q[s] = np.arctan2(0.5 * w @ joint.axis, 0.5 * (np.trace(R_rel) - 1.0))
                v[t] = joint.axis @ w_rel
        return q, v

    # ---- Pinocchio -> bodies, energy ----------------------------------------------------

    def normalised(self, q: np.ndarray) -> np.ndarray:
        out = q.copy()
        quats = out[self.quat_q]
        out[self.quat_q] = quats / np.linalg.norm(quats, axis=1, keepdims=True)
        return out

    def frames(self, q: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """body -> (centre of mass (3,), R (3, 3)) in the world."""
        pin.forwardKinematics(self.model, self.data, self.normalised(q))
        out = {}
        for name, jid in self.body_joint.items():
            M = self.data.oMi[jid]
            out[name] = (M.translation + M.rotation @ self.com[name], M.rotation.copy())
        return out

    def energy(self, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        """(kinetic, potential) energy (J); potential m g z of the centres of mass."""
        q = self.normalised(q)
        return (pin.computeKineticEnergy(self.model, self.data, q, v),
                pin.computePotentialEnergy(self.model, self.data, q))

    # ---- the right-hand side --------------------------------------------------------------

    def rhs(self, torques: Callable[[float], np.ndarray] | None,
            joint_slices: dict[str, slice]):
        """f(t, y) for y = (q, v, W): q' (quaternions: 1/2 q (x) (omega, 0), local omega),
        v' by ABA, W' the power of the joint torques.

        torques(t) (nt,) in the VI's components (`Multibody`: a spherical joint's along the
        scene parent's directors, a revolute joint's about its axis), sliced by
        `joint_slices`. The VI applies +m to the scene child and -m to the scene parent,
        m = R_parent tau_j: a torque across the same joint of this model, whose velocity is
        R_b^T (omega_b - omega_a) (b its child here). Where the tree runs as in the scene
        (b the scene child) its generalised force is R_b^T m = R_rel^T tau_j, R_rel = R_a^T
        R_b the joint's rotation (revolute: tau_j); where it runs the other way, -tau_j."""
        model, data, nq, nv = self.model, self.data, self.model.nq, self.model.nv
        qq, qv, rq, rv = self.quat_q, self.quat_v, self.rev_q, self.rev_v
        joints = [(model.joints[jid].idx_q, model.joints[jid].idx_v, joint_slices[joint.name],
                   joint.axis is None, joint.parent == a) for jid, a, _, joint in self.edges]
        tau_model = np.zeros(nv)

        def f(t, y):
            q, v = self.normalised(y[:nq]), y[nq:nq + nv]
            dy = np.empty_like(y)
            quat, w = q[qq], v[qv]
            dy[qq[:, :3]] = 0.5 * (quat[:, 3:] * w + np.cross(quat[:, :3], w))
            dy[qq[:, 3]] = -0.5 * np.einsum("ij,ij->i", quat[:, :3], w)
            dy[rq] = v[rv]
            if torques is not None:
                tau = torques(t)
                for sq, sv, joint_slice, spherical, forward in joints:
                    tj = tau[joint_slice]
                    if not forward:
                        tau_model[sv:sv + len(tj)] = -tj
                    elif spherical:
                        tau_model[sv:sv + 3] = _rotation(q[sq:sq + 4]).T @ tj
                    else:
                        tau_model[sv] = tj[0]
            dy[nq:nq + nv] = pin.aba(model, data, q, v, tau_model)
            dy[-1] = tau_model @ v
            return dy

        return f
