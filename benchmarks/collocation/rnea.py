"""Recursive Newton-Euler inverse dynamics of the walker in minimal coordinates, as a
compact SX expression (what bioptim/biorbd or Simbody users evaluate).

Same coordinates theta as `minimal.MinimalModel` (root position, root Cardan angles,
joint angles: spherical R_rel = Ry(pitch) Rx(roll) Rz(yaw), revolute about the body-fixed
axis), same bodies (mass, principal inertia diag(J1, J2, J3) about the centre of mass in
director components, points from the centre of mass), gravity -g e_z.

Forward pass (world frame): every Cardan angle or revolute angle is a rotation about a
unit axis s (world components) through a point r (the root's centre of mass, or the joint
point); body angular velocity omega = sum s_i w_i and acceleration alpha = sum (s_i a_i +
omega_before_i x s_i w_i) along the chain of axes; centre-of-mass velocity and
acceleration by the rigid-body transport from the joint point. Backward pass: each body's
Newton-Euler wrench m (a - g) and I alpha + omega x I omega (about its centre of mass),
minus the external wrench of the director force f on it (force f_phi, moment
sum_i d_i x f_{d_i}: the power-conjugate wrench of a director force on a rigid body), is
summed over the subtree as a force F and a moment N about the world origin; the
generalised force of a rotation coordinate (axis s through r) is s . (N - r x F), of a
root translation e_i . F. This is J^T (M qdd + grad V - f) of `MinimalModel.dynamics`
(the Lagrange equations in theta, Featherstone 2008, ch. 5): the joint torques' own
generalised forces are s_i . m (m = D_p tau or D_p n tau, the couple +m on the child,
-m on the parent, `Multibody.actuation_force`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from benchmarks.collocation.minimal import E_X, E_Y, E_Z, MinimalModel
from gait_planner.model.multibody import Multibody
from gait_planner.model.rotations import axis_rotation
from gait_planner.model.scene import JointType, RootType


class _Kinematics:
    """Forward pass: per body R, p (COM), v, omega, a (COM), alpha; per coordinate its
    (axis s, point r) or a translation direction."""

    def __init__(self, model: "SpatialModel", theta, w, a):
        mb, scene = model.mb, model.scene
        self.R, self.p, self.v, self.om, self.acc, self.al = {}, {}, {}, {}, {}, {}
        self.coords: list = [None] * model.n  # ("t", e) or ("r", s, r_point, subtree root)
        zero = ca.DM.zeros(3)
        root = scene.root.body
        if scene.root.type is RootType.FREE:
            p, v, acc = theta[0:3], w[0:3], a[0:3]
            for i in range(3):
                self.coords[i] = ("t", ca.DM(np.eye(3)[i]), None, root)
            axes, idx = [E_Z, E_Y, E_X], [3, 4, 5]
        else:
            y0 = model.scene.initial_pose.root_position[1]
            p = ca.vertcat(theta[0], y0, theta[1])
            v, acc = ca.vertcat(w[0], 0, w[1]), ca.vertcat(a[0], 0, a[1])
            self.coords[0] = ("t", E_X, None, root)
            self.coords[1] = ("t", E_Z, None, root)
            axes, idx = [E_Y], [2]
        R, om, al = self._chain(ca.DM.eye(3), zero, zero, axes, idx, p, root, theta, w, a)
        self.R[root], self.p[root], self.v[root], self.acc[root] = R, p, v, acc
        self.om[root], self.al[root] = om, al
        for joint in scene.joints:
            P = joint.parent
            start = mb.root_dof + mb.joint_slices[joint.name].start
            Rp = self.R[P]
            rho_p = ca.mtimes(Rp, ca.DM(scene.body(P).points[joint.parent_point]))
            rj = self.p[P] + rho_p
            vj = self.v[P] + ca.cross(self.om[P], rho_p)
            aj = self.acc[P] + ca.cross(self.al[P], rho_p) \
                + ca.cross(self.om[P], ca.cross(self.om[P], rho_p))
            if joint.type is JointType.SPHERICAL:
                axes, idx = [E_Y, E_X, E_Z], [start, start + 1, start + 2]
            else:
                axes, idx = [ca.DM(joint.axis)], [start]
            R, om, al = self._chain(Rp, self.om[P], self.al[P], axes, idx, rj, joint.child,
                                    theta, w, a)
            if joint.type is JointType.REVOLUTE:  # R_rel = Rot(n, theta) R0
                R = ca.mtimes(R, ca.DM(joint.reference))
            c = -ca.mtimes(R, ca.DM(scene.body(joint.child).points[joint.child_point]))
            self.R[joint.child], self.p[joint.child] = R, rj + c
            self.om[joint.child], self.al[joint.child] = om, al
            self.v[joint.child] = vj + ca.cross(om, c)
            self.acc[joint.child] = aj + ca.cross(al, c) + ca.cross(om, ca.cross(om, c))

    def _chain(self, R, om, al, axes, idx, point, body, theta, w, a):
        """Rotations about body-fixed axes in sequence (R <- R Rot(axis, theta_i))."""
        for axis, i in zip(axes, idx):
            s = ca.mtimes(R, axis)
            self.coords[i] = ("r", s, point, body)
            al = al + s * a[i] + ca.cross(om, s) * w[i]
            om = om + s * w[i]
            R = ca.mtimes(R, axis_rotation(axis, theta[i]))
        return R, om, al


class SpatialModel(MinimalModel):
    """`MinimalModel` whose equations of motion, impact map, J^T projection, contact-row
    kinematics and kinetic energy are evaluated by the recursive Newton-Euler algorithm
    and rigid-body kinematics (module docstring) instead of derivatives of q(theta):

    * ``inverse_dynamics`` (theta, w, a, f) -> generalised forces of M qdd + grad V - f
      (n,): inverse dynamics with the director force f as external load
    * ``dynamics``, ``impact``, ``project``, ``velocity``, ``acceleration``,
      ``kinetic_energy``: as `MinimalModel`'s, the same values
    """

    def __init__(self, mb: Multibody):
        super().__init__(mb)
        self.reference = {name: getattr(self, name) for name in (
            "dynamics", "impact", "project", "velocity", "acceleration", "kinetic_energy")}
        n, k = self.n, self.k
        theta, w, a = (ca.SX.sym(s, n) for s in ("theta", "w", "a"))
        w2 = ca.SX.sym("w_plus", n)
        tau, f = ca.SX.sym("tau", mb.nt), ca.SX.sym("f", k)
        zero = ca.SX.zeros(n)
        self.bodies = {b.name: b for b in self.scene.bodies}
        self.order = [self.scene.root.body] + [j.child for j in self.scene.joints]
        self.parent = {j.child: j.parent for j in self.scene.joints}

        def rnea(th, wv, av, force, gravity=True):
            kin = _Kinematics(self, th, wv, av)
            return self._backward(kin, force, gravity), kin

        ID, kin = rnea(theta, w, a, f)
        residual = ID - self._torque_forces(kin, tau)
        self.inverse_dynamics = ca.Function("inverse_dynamics", [theta, w, a, f], [ID],
                                            ["theta", "w", "a", "f"], ["Q"])
        self.dynamics = ca.Function("dynamics", [theta, w, a, tau, f], [residual],
                                    ["theta", "w", "a", "tau", "f"], ["r"])
        jump, _ = rnea(theta, zero, w2 - w, f, gravity=False)
        self.impact = ca.Function("impact", [theta, w, w2, f], [jump],
                                  ["theta", "w_minus", "w_plus", "P"], ["r"])
        Jtf, _ = rnea(theta, zero, zero, -f, gravity=False)
        self.project = ca.Function("project", [theta, f], [Jtf], ["theta", "f"], ["Jt_f"])
        kv = _Kinematics(self, theta, w, zero)
        qd = self._director_rates(kv, kv.v, lambda b, d: ca.cross(kv.om[b], d))
        self.velocity = ca.Function("velocity", [theta, w], [qd], ["theta", "w"], ["q_dot"])
        qdd = self._director_rates(
            kin, kin.acc,
            lambda b, d: ca.cross(kin.al[b], d) + ca.cross(kin.om[b], ca.cross(kin.om[b], d)))
        self.acceleration = ca.Function("acceleration", [theta, w, a], [qdd],
                                        ["theta", "w", "a"], ["q_ddot"])
        T = 0
        for b in self.order:
            J = ca.DM(np.diag(self.bodies[b].inertia))
            om_body = ca.mtimes(kv.R[b].T, kv.om[b])
            T += 0.5 * self.bodies[b].mass * ca.dot(kv.v[b], kv.v[b]) \
                + 0.5 * ca.dot(om_body, ca.mtimes(J, om_body))
        self.kinetic_energy = ca.Function("kinetic_energy", [theta, w], [T], ["theta", "w"], ["T"])

    def _director_rates(self, kin, lin, rot):
        """Director-coordinate vector (k,) in body order: lin[b], rot(b, d_i)."""
        out = []
        for b in self.mb.body_names:
            R = kin.R[b]
            out += [lin[b]] + [rot(b, R[:, i]) for i in range(3)]
        return ca.vertcat(*out)

    def _backward(self, kin, f, gravity: bool):
        """Generalised forces of the Newton-Euler wrenches minus the director force f."""
        g = ca.DM([0.0, 0.0, -self.scene.gravity]) if gravity else ca.DM.zeros(3)
        F, N = {}, {}
        for b in self.order:
            body, R = self.bodies[b], kin.R[b]
            block = self.mb.block(b).start
            fb = f[block : block + 12]
            J = ca.DM(np.diag(body.inertia))
            om_body = ca.mtimes(R.T, kin.om[b])
            al_body = ca.mtimes(R.T, kin.al[b])
            M_body = ca.mtimes(J, al_body) + ca.cross(om_body, ca.mtimes(J, om_body))
            force = body.mass * (kin.acc[b] - g) - fb[0:3]
            moment = ca.mtimes(R, M_body) - sum(ca.cross(R[:, i], fb[3 + 3 * i : 6 + 3 * i])
                                                for i in range(3))
            F[b], N[b] = force, moment + ca.cross(kin.p[b], force)
        for b in reversed(self.order[1:]):  # subtree sums, children before parents
            F[self.parent[b]] = F[self.parent[b]] + F[b]
            N[self.parent[b]] = N[self.parent[b]] + N[b]
        out = []
        for kind, s, r, b in kin.coords:
            if kind == "t":
                out.append(ca.dot(s, F[b]))
            else:
                out.append(ca.dot(s, N[b] - ca.cross(r, F[b])))
        return ca.vertcat(*out)

    def _torque_forces(self, kin, tau):
        """Generalised forces s_i . m of the joint couples (`Multibody.actuation_force`)."""
        out = [ca.SX.zeros(1)] * self.n
        for joint in self.scene.joints:
            tj = tau[self.mb.joint_slices[joint.name]]
            Rp = kin.R[joint.parent]
            m = ca.mtimes(Rp, tj if joint.type is JointType.SPHERICAL else ca.DM(joint.axis) * tj)
            start = self.mb.root_dof + self.mb.joint_slices[joint.name].start
            for i in range(joint.dof):
                out[start + i] = ca.dot(kin.coords[start + i][1], m)
        return ca.vertcat(*out)
