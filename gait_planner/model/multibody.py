"""A tree of rigid bodies in director coordinates, built from a `Scene`.

Configuration q in R^k, k = 12 nb: per body (phi, d1, d2, d3), world components, bodies in
scene order. Generalised velocities nu in R^ndof: the root's (v, omega) in world components
(free: 6; planar: v_x, v_z, omega_y), then per joint in scene (tree) order its relative
angular velocity: spherical joints 3 components along the parent's directors, revolute
joints 1 rate about the joint axis. Joint torques tau in R^nt use the same components as the
joint rates, so the generalised force of the actuation is exactly (0_root, tau).

Named CasADi Functions (one definition each, used by simulation, optimisation and checks):

* ``constraints``  g(q) -> (m,)            internal, joint and planar-root conditions
* ``constraint_jacobian``  G(q) -> (m, k)
* ``null_space``   P(q) -> (k, ndof), G P = 0  (Betsch & Leyendecker 2006; paper section 3)
* ``null_space_transpose``  (q, r) -> P(q)^T r, (ndof,): the projection of a redundant force
  r (k,) onto the generalised velocities, by reverse-mode differentiation of the velocity
  map (subtree wrenches accumulated leaves to root) instead of forming P
* ``reparametrise``  F_d(u, q) -> q_next: nodal reparametrisation, g(F_d(u, q)) = 0 for
  every u (paper section 3; docs/design.md section 4)
* ``actuation``    B^T(q) -> (k, nt): director forces of the joint torques (paper section 2)
* ``actuation_force``  (q, tau) -> B^T(q) tau (k,), without forming B^T (half the operations)
"""

from __future__ import annotations

import weakref
from functools import cached_property

import casadi as ca
import numpy as np

from gait_planner.model.rotations import axis_rotation, exp_so3, log_so3
from gait_planner.model.scene import JointType, RootType, Scene

E_X, E_Y, E_Z = (ca.DM([1.0, 0.0, 0.0]), ca.DM([0.0, 1.0, 0.0]), ca.DM([0.0, 0.0, 1.0]))


def _perpendicular_pair(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing the unit vector n to an orthonormal basis."""
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    a = np.cross(n, helper)
    a /= np.linalg.norm(a)
    return a, np.cross(n, a)


_BUILT: dict[int, "Multibody"] = {}  # id(scene) -> its Multibody while the scene lives


class Multibody:
    """Index layout and kinematic CasADi Functions of one scene's body tree (immutable once
    built)."""

    @classmethod
    def of(cls, scene: Scene) -> "Multibody":
        """The scene's Multibody, built once per scene object and kept while it lives:
        building one takes 20-25 ms (walker2d, its CasADi expressions), and a re-planned
        transition built nine (0.2 s of a 0.55 s answer, 2026-12-07)."""
        mb = _BUILT.get(id(scene))
        if mb is None or mb.scene is not scene:
            mb = _BUILT[id(scene)] = cls(scene)
            weakref.finalize(scene, _BUILT.pop, id(scene), None)
        return mb

    def __init__(self, scene: Scene):
        self.scene = scene
        self.body_names = tuple(b.name for b in scene.bodies)
        self.nb = len(scene.bodies)
        self.k = 12 * self.nb
        self.root_dof = scene.root.dof
        offsets = np.cumsum([0] + [j.dof for j in scene.joints])
        self.joint_slices = {
            j.name: slice(int(a), int(b)) for j, a, b in zip(scene.joints, offsets, offsets[1:])
        }
        self.nt = int(offsets[-1])
        self.ndof = self.root_dof + self.nt
        # which entries of u (reparametrise) are rotations (rad) rather than translations (m)
        translations = 3 if scene.root.type is RootType.FREE else 2
        self.rotation_mask = np.arange(self.ndof) >= translations
        self._joint_of_child = {j.child: j for j in scene.joints}

        masses = []
        for body in scene.bodies:
            e1, e2, e3 = body.euler_tensor
            masses += [body.mass] * 3 + [e1] * 3 + [e2] * 3 + [e3] * 3
        self.mass_diagonal = np.array(masses)  # M = diag(...); may be indefinite (torso)

        self._build()

    # ---- layout helpers --------------------------------------------------------------

    def block(self, body: str) -> slice:
        """Slice of q holding body `body` (12 entries: phi, d1, d2, d3)."""
        i = self.body_names.index(body)
        return slice(12 * i, 12 * i + 12)

    def _split(self, q):
        """Per body: (phi, D) with D = [d1 d2 d3] a 3x3 expression."""
        out = {}
        for i, name in enumerate(self.body_names):
            b = q[12 * i : 12 * i + 12]
            out[name] = (b[0:3], ca.horzcat(b[3:6], b[6:9], b[9:12]))
        return out

    @staticmethod
    def _join(frames, names):
        parts = []
        for name in names:
            phi, D = frames[name]
            parts += [phi, D[:, 0], D[:, 1], D[:, 2]]
        return ca.vertcat(*parts)

    def point_matrix(self, body: str, point: str) -> np.ndarray:
        """Constant C (3, k) with x = C q the world position of a body-fixed point."""
        X = self.scene.body(body).points[point]
        C = np.zeros((3, self.k))
        s = self.block(body).start
        C[:, s : s + 3] = np.eye(3)
        for i in range(3):
            C[:, s + 3 + 3 * i : s + 6 + 3 * i] = X[i] * np.eye(3)
        return C

    def contact_rows(self, contact: str) -> np.ndarray:
        """Constant rows (3, k), or (2, k) in planar scenes (x and z only: y is fixed by the
        planar root), of a contact point's world position: the contact Jacobian G_C."""
        c = self.scene.contact(contact)
        C = self.point_matrix(c.body, c.point)
        return C[[0, 2]] if self.scene.planar else C

    def _rho(self, body: str, point: str) -> ca.DM:
        return ca.DM(self.scene.body(body).points[point])

    # ---- symbolic kinematics ----------------------------------------------------------

    def _reparametrise_expr(self, u, q):
        """q_next = F_d(u, q): every body's triad is turned by an exact rotation R_body,
        D_next = R_body D; the root by exp(theta^), a child by
        R_child = exp((D_parent_next a_j)^) R_parent with a_j = u_j (spherical: parent
        components) or u_j n (revolute: the parent's NEW axis). As
        exp((R w)^) = R exp(w^) R^T, this is R_child = R_parent exp((D_parent a_j)^), the
        form built here: each exponential depends on its own joint's u_j only (D_parent is
        the given triad), which keeps the derivatives of F_d short (a revolute joint is
        a plain rotation about the given axis D_parent n). Rotations are never built
        from q, so round-off in q does not propagate down the tree. phi of a child follows
        from its joint condition."""
        frames = self._split(q)
        rot, new = {}, {}
        root = self.scene.root
        phi, D = frames[root.body]
        if root.type is RootType.FREE:
            rot[root.body] = exp_so3(u[3:6])
            new[root.body] = (phi + u[0:3], ca.mtimes(rot[root.body], D))
        else:
            rot[root.body] = exp_so3(ca.vertcat(0, u[2], 0))
            new[root.body] = (phi + ca.vertcat(u[0], 0, u[1]), ca.mtimes(rot[root.body], D))
        for joint in self.scene.joints:
            _, Dc = frames[joint.child]
            _, Dp = frames[joint.parent]
            phip_new, Dp_new = new[joint.parent]
            uj = u[self.root_dof + self.joint_slices[joint.name].start :][: joint.dof]
            if joint.type is JointType.SPHERICAL:
                turn = exp_so3(ca.mtimes(Dp, uj))
            else:
                turn = axis_rotation(ca.mtimes(Dp, ca.DM(joint.axis)), uj)
            rot[joint.child] = ca.mtimes(rot[joint.parent], turn)
            Dc_new = ca.mtimes(rot[joint.child], Dc)
            phic_new = (
                phip_new
                + ca.mtimes(Dp_new, self._rho(joint.parent, joint.parent_point))
                - ca.mtimes(Dc_new, self._rho(joint.child, joint.child_point))
            )
            new[joint.child] = (phic_new, Dc_new)
        return self._join(new, self.body_names)

    def _velocity_expr(self, nu, q):
        """q_dot = P(q) nu, built from body twists: phi_dot = v, d_i_dot = omega x d_i."""
        frames = self._split(q)
        twist = {}
        root = self.scene.root
        if root.type is RootType.FREE:
            twist[root.body] = (nu[0:3], nu[3:6])
        else:
            twist[root.body] = (ca.vertcat(nu[0], 0, nu[1]), ca.vertcat(0, nu[2], 0))
        for joint in self.scene.joints:
            _, Dp = frames[joint.parent]
            _, Dc = frames[joint.child]
            vp, wp = twist[joint.parent]
            nuj = nu[self.root_dof + self.joint_slices[joint.name].start :][: joint.dof]
            axis = nuj if joint.type is JointType.SPHERICAL else ca.DM(joint.axis) * nuj
            wc = wp + ca.mtimes(Dp, axis)
            vc = (
                vp
                + ca.cross(wp, ca.mtimes(Dp, self._rho(joint.parent, joint.parent_point)))
                - ca.cross(wc, ca.mtimes(Dc, self._rho(joint.child, joint.child_point)))
            )
            twist[joint.child] = (vc, wc)
        parts = []
        for name in self.body_names:
            v, w = twist[name]
            _, D = frames[name]
            parts += [v] + [ca.cross(w, D[:, i]) for i in range(3)]
        return ca.vertcat(*parts)

    def _constraints_expr(self, q):
        frames = self._split(q)
        rows = []
        for name in self.body_names:  # internal constraints (6 per body)
            _, D = frames[name]
            d1, d2, d3 = D[:, 0], D[:, 1], D[:, 2]
            rows += [
                0.5 * (ca.dot(d1, d1) - 1),
                0.5 * (ca.dot(d2, d2) - 1),
                0.5 * (ca.dot(d3, d3) - 1),
                ca.dot(d1, d2),
                ca.dot(d1, d3),
                ca.dot(d2, d3),
            ]
        for joint in self.scene.joints:
            phip, Dp = frames[joint.parent]
            phic, Dc = frames[joint.child]
            gap = (
                phip
                + ca.mtimes(Dp, self._rho(joint.parent, joint.parent_point))
                - phic
                - ca.mtimes(Dc, self._rho(joint.child, joint.child_point))
            )
            rows += [gap[i] for i in range(3)]
            if joint.type is JointType.REVOLUTE:
                # the parent's axis stays normal to two child vectors a, b normal to the
                # child's axis R0^T n (a, b in child components)
                a, b = _perpendicular_pair(np.array(joint.child_axis))
                n_world = ca.mtimes(Dp, ca.DM(joint.axis))
                rows += [
                    ca.dot(n_world, ca.mtimes(Dc, ca.DM(a))),
                    ca.dot(n_world, ca.mtimes(Dc, ca.DM(b))),
                ]
        if self.scene.root.type is RootType.PLANAR:
            phi, D = frames[self.scene.root.body]
            y0 = self.scene.initial_pose.root_position[1]
            rows += [phi[1] - y0, ca.dot(D[:, 1], E_X), ca.dot(D[:, 1], E_Z)]
        return ca.vertcat(*rows)

    def _actuation_expr(self, q, tau):
        """Director forces of the joint torques: +m on the child, -m on the parent,
        m = D_p tau (spherical) or tau D_p n (revolute), as f_{d_i} = m x d_i / 2."""
        frames = self._split(q)
        force = {name: [ca.DM.zeros(3) for _ in range(4)] for name in self.body_names}
        for joint in self.scene.joints:
            _, Dp = frames[joint.parent]
            _, Dc = frames[joint.child]
            tj = tau[self.joint_slices[joint.name]]
            m = ca.mtimes(Dp, tj if joint.type is JointType.SPHERICAL else ca.DM(joint.axis) * tj)
            for i in range(3):
                force[joint.child][1 + i] += 0.5 * ca.cross(m, Dc[:, i])
                force[joint.parent][1 + i] -= 0.5 * ca.cross(m, Dp[:, i])
        return ca.vertcat(*[f for name in self.body_names for f in force[name]])

    def _build(self) -> None:
        q = ca.SX.sym("q", self.k)
        u = ca.SX.sym("u", self.ndof)
        nu = ca.SX.sym("nu", self.ndof)
        tau = ca.SX.sym("tau", self.nt)
        g = self._constraints_expr(q)
        self.m = int(g.shape[0])
        qdot = self._velocity_expr(nu, q)
        f = self._actuation_expr(q, tau)
        self.constraints = ca.Function("constraints", [q], [g], ["q"], ["g"])
        self.constraint_jacobian = ca.Function(
            "constraint_jacobian", [q], [ca.jacobian(g, q)], ["q"], ["G"]
        )
        self.null_space = ca.Function(
            "null_space", [q], [ca.jacobian(qdot, nu)], ["q"], ["P"]
        )
        r = ca.SX.sym("r", self.k)
        projected = ca.jtimes(qdot, nu, r, True)  # qdot is linear in nu: free of nu
        self.null_space_transpose = ca.Function(
            "null_space_transpose", [q, r], [projected], ["q", "r"], ["Pt_r"]
        )
        self.reparametrise = ca.Function(
            "reparametrise", [u, q], [self._reparametrise_expr(u, q)], ["u", "q"], ["q_next"]
        )
        self.actuation = ca.Function(
            "actuation", [q], [ca.jacobian(f, tau)], ["q"], ["Bt"]
        )
        self.actuation_force = ca.Function(
            "actuation_force", [q, tau], [f], ["q", "tau"], ["f"]
        )

    def increment(self, q: np.ndarray, q_next: np.ndarray) -> np.ndarray:
        """u (ndof,) with reparametrise(u, q) = q_next, both (k,) satisfying the constraints
        (the inverse of F_d, numpy): the root's displacement and rotation vector, each
        joint's relative turn expressed as `_reparametrise_expr` takes it (spherical: the
        rotation vector in the parent's given directors; revolute: the angle about its
        axis). Rotation vectors are the principal logarithm, so turns above pi are not
        recovered."""
        frames = {}
        for i, name in enumerate(self.body_names):
            b0, b1 = q[12 * i : 12 * i + 12], q_next[12 * i : 12 * i + 12]
            D0, D1 = b0[3:].reshape(3, 3).T, b1[3:].reshape(3, 3).T
            frames[name] = (b1[:3] - b0[:3], D0, D1 @ D0.T)  # displacement, D, rotation
        root = self.scene.root
        u = np.zeros(self.ndof)
        move, _, turn = frames[root.body]
        w = log_so3(turn)
        u[: self.root_dof] = (np.concatenate([move, w]) if root.type is RootType.FREE
                              else [move[0], move[2], w[1]])
        for joint in self.scene.joints:
            _, Dp, Rp = frames[joint.parent]
            a = Dp.T @ log_so3(Rp.T @ frames[joint.child][2])
            sl = slice(self.root_dof + self.joint_slices[joint.name].start, None)
            u[sl][: joint.dof] = a if joint.type is JointType.SPHERICAL else a @ joint.axis
        return u

    @cached_property
    def mass_matrix(self) -> np.ndarray:
        """The constant (k, k) mass matrix of docs/design.md section 1 (not positive definite
        when a body's inertia violates the triangle inequality)."""
        return np.diag(self.mass_diagonal)
