"""The walker in minimal coordinates: theta -> director configuration q(theta), and the
equations of motion of the product's own model written in theta.

Coordinates theta (n = Multibody.ndof), in this order:

* root position (m): free root (x, y, z); planar root (x, z), y held at the scene pose's;
* root orientation (rad): free root (yaw, pitch, roll) with R = Rz(yaw) Ry(pitch) Rx(roll)
  (`gait_planner.model.angles.root_angles`); planar root (pitch), R = Ry(pitch);
* the joint angles in `angles.angle_names(scene)` order: spherical R_rel = Ry(pitch)
  Rx(roll) Rz(yaw) (pitch, roll, yaw), revolute one angle about the joint axis.

q(theta) builds every triad from these rotations and every child's centre of mass from
its joint condition (as `angles.configuration`), so it satisfies every internal and joint
constraint identically and J = dq/dtheta (k, n) is a null space matrix of G (docs/design.md
section 4). With the constant director mass matrix M = diag(`Multibody.mass_diagonal`)
the Lagrangian is L(theta, w) = 1/2 (J w)^T M (J w) - V(q(theta)), and its Euler-Lagrange
equations with the generalised forces J^T (B^T(q) tau + f) (actuation as
`Multibody.actuation_force`, f a director force such as C^T lambda of the contacts) read

    J^T (M qdd + grad V - B^T(q) tau - f) = 0,   qdd = J a + (dJ/dtheta w) w

(the J-dot^T M qdot terms of d/dt dL/dw and dL/dtheta cancel; e.g. Featherstone, Rigid
Body Dynamics Algorithms, 2008, section 1.4, or any Lagrangian mechanics text): that is
M(theta) a + c(theta, w) + grad_theta V = Q with M(theta) = J^T M J. The accelerations a
stay unknowns of the transcription (implicit form): no symbolic inverse of the 20 x 20
M(theta) is formed (`transcription`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.angles import joint_angles, root_angles
from gait_planner.model.multibody import Multibody
from gait_planner.model.rotations import axis_rotation
from gait_planner.model.scene import JointType, RootType
from gait_planner.ocp.mirror import torque_mirror

E_X, E_Y, E_Z = (ca.DM(np.eye(3)[i]) for i in range(3))


def _chart_limits(mb: Multibody) -> np.ndarray:
    """(n,) bound on |theta_i| (inf: none) keeping the Cardan charts away from their gimbal
    lock (docs/design.md section 5: an unbounded chart gave wrong answers that looked
    converged): the free root's pitch and every spherical joint's roll, 80 deg."""
    limit = np.full(mb.ndof, np.inf)
    if mb.scene.root.type is RootType.FREE:
        limit[4] = np.radians(80.0)
    for j in mb.scene.joints:
        if j.type is JointType.SPHERICAL:
            limit[mb.root_dof + mb.joint_slices[j.name].start + 1] = np.radians(80.0)
    return limit


class MinimalModel:
    """Named CasADi Functions of the minimal-coordinate model of one scene:

    * ``configuration``  theta (n,) -> q (k,)
    * ``velocity``       (theta, w) -> qdot = J w (k,)
    * ``acceleration``   (theta, w, a) -> qdd = J a + (dJ w) w (k,)
    * ``project``        (theta, f) -> J^T f (n,): a director force as a generalised force
    * ``dynamics``       (theta, w, a, tau, f) -> J^T (M qdd + grad V - B^T tau - f) (n,), N
      or N m: zero on a motion of the model (module docstring)
    * ``impact``         (theta, w_minus, w_plus, P) -> J^T (M J (w_plus - w_minus) - P)
      (n,), N s: zero for a plastic impact with the director impulse P = C^T Lambda
      (Lambda: ground impulses); with C J w_plus = 0 this is the map
      w_plus = w_minus + M(theta)^-1 (C J)^T Lambda (e.g. Westervelt et al., Feedback
      Control of Dynamic Bipedal Robot Locomotion, 2007, section 3.4.2, eq. 3.20)
    * ``kinetic_energy`` (theta, w) -> 1/2 w^T J^T M J w (J)
    * ``mass_matrix``    theta -> J^T M J (n, n)
    * ``mirror``         (theta, step) -> theta' with q(theta') = A q(theta) + step e
      (`gait_planner.ocp.mirror.configuration_mirror`, paper eqs. 7-9)
    * ``mirror_velocity`` (theta, w) -> d theta'/d theta w
    """

    def __init__(self, mb: Multibody):
        self.mb, self.scene = mb, mb.scene
        self.n, self.k = mb.ndof, mb.k
        self.gravity_gradient = DiscreteMechanics(mb).gravity_gradient  # dV/dq (N), constant
        self.chart_limits = _chart_limits(mb)
        n, k = self.n, self.k
        theta, w, a = (ca.SX.sym(s, n) for s in ("theta", "w", "a"))
        w2 = ca.SX.sym("w_plus", n)
        tau, f = ca.SX.sym("tau", mb.nt), ca.SX.sym("f", k)
        M = ca.DM(mb.mass_diagonal)
        q = self._configuration_expr(theta)
        qd = ca.jtimes(q, theta, w)
        qdd = ca.jtimes(q, theta, a) + ca.jtimes(qd, theta, w)

        def project(r):
            return ca.jtimes(q, theta, r, True)  # J^T r by reverse mode

        residual = project(M * qdd + ca.DM(self.gravity_gradient) - mb.actuation_force(q, tau) - f)
        self.configuration = ca.Function("configuration", [theta], [q], ["theta"], ["q"])
        self.velocity = ca.Function("velocity", [theta, w], [qd], ["theta", "w"], ["q_dot"])
        self.acceleration = ca.Function("acceleration", [theta, w, a], [qdd],
                                        ["theta", "w", "a"], ["q_ddot"])
        self.project = ca.Function("project", [theta, f], [project(f)], ["theta", "f"], ["Jt_f"])
        self.dynamics = ca.Function("dynamics", [theta, w, a, tau, f], [residual],
                                    ["theta", "w", "a", "tau", "f"], ["r"])
        jump = project(M * ca.jtimes(q, theta, w2 - w) - f)
        self.impact = ca.Function("impact", [theta, w, w2, f], [jump],
                                  ["theta", "w_minus", "w_plus", "P"], ["r"])
        self.kinetic_energy = ca.Function("kinetic_energy", [theta, w], [0.5 * ca.dot(qd, M * qd)],
                                          ["theta", "w"], ["T"])
        J = ca.jacobian(q, theta)
        self.mass_matrix = ca.Function("mass_matrix", [theta], [ca.mtimes(J.T, M * J)],
                                       ["theta"], ["M"])
        step = ca.SX.sym("step")
        image = self._mirror_expr(theta, q, step)
        self.mirror = ca.Function("mirror", [theta, step], [image], ["theta", "step"], ["theta_image"])
        self.mirror_velocity = ca.Function("mirror_velocity", [theta, w],
                                           [ca.jtimes(image, theta, w)], ["theta", "w"], ["w_image"])

    # ---- q(theta) ----------------------------------------------------------------------

    def _root(self, theta):
        """(phi, R) of the root body."""
        if self.scene.root.type is RootType.FREE:
            R = ca.mtimes([axis_rotation(E_Z, theta[3]), axis_rotation(E_Y, theta[4]),
                           axis_rotation(E_X, theta[5])])
            return theta[0:3], R
        y0 = self.scene.initial_pose.root_position[1]
        return ca.vertcat(theta[0], y0, theta[1]), axis_rotation(E_Y, theta[2])

    def _configuration_expr(self, theta):
        mb, scene = self.mb, self.scene
        frames = {scene.root.body: self._root(theta)}
        for joint in scene.joints:
            angles = theta[mb.root_dof + mb.joint_slices[joint.name].start:][: joint.dof]
            if joint.type is JointType.SPHERICAL:
                R_rel = ca.mtimes([axis_rotation(E_Y, angles[0]), axis_rotation(E_X, angles[1]),
                                   axis_rotation(E_Z, angles[2])])
            else:
                R_rel = ca.mtimes(axis_rotation(ca.DM(joint.axis), angles[0]),
                                  ca.DM(joint.reference))
            phi_p, D_p = frames[joint.parent]
            D_c = ca.mtimes(D_p, R_rel)
            rho_p = ca.DM(scene.body(joint.parent).points[joint.parent_point])
            rho_c = ca.DM(scene.body(joint.child).points[joint.child_point])
            frames[joint.child] = (phi_p + ca.mtimes(D_p, rho_p) - ca.mtimes(D_c, rho_c), D_c)
        return ca.vertcat(*[ca.vertcat(frames[b][0], ca.vec(frames[b][1]))
                            for b in mb.body_names])

    # ---- mirror ------------------------------------------------------------------------

    def _mirror_expr(self, theta, q, step):
        """theta' of the mirror image (module `gait_planner.ocp.mirror`): S R S for every
        triad (S = diag(1, -1, 1)), so Rz(yaw) Ry(pitch) Rx(roll) -> Rz(-yaw) Ry(pitch)
        Rx(-roll) and a spherical joint's (pitch, roll, yaw) -> the partner joint's
        (pitch, -roll, -yaw); a revolute angle maps with the factor of `torque_mirror` (an
        angle and its torque are both pseudo-vector components). A planar root whose
        mirror partner is another body (the compass) takes that body's pitch (the root's
        plus the revolute angles about +-y on the way) and centre of mass."""
        mb, scene = self.mb, self.scene
        out = [None] * self.n
        root, partner = scene.root.body, dict(scene.gait.mirror).get(scene.root.body,
                                                                      scene.root.body)
        if scene.root.type is RootType.FREE:
            if partner != root:
                raise ValueError("a free root must be its own mirror image")
            out[0:6] = [theta[0] + step, -theta[1], theta[2], -theta[3], theta[4], -theta[5]]
        else:
            pitch, body, by_child = theta[2], partner, {j.child: j for j in scene.joints}
            while body != root:
                j = by_child[body]
                pitch += float(np.dot(j.axis, [0.0, 1.0, 0.0])) * \
                    theta[mb.root_dof + mb.joint_slices[j.name].start]
                body = j.parent
            phi = q[mb.block(partner).start : mb.block(partner).start + 3]
            out[0:3] = [phi[0] + step, phi[2], pitch]
        B = torque_mirror(mb)
        for j in scene.joints:
            src = mb.joint_slices[j.name]
            dst = int(np.flatnonzero(B[:, src.start])[0])
            if j.type is JointType.SPHERICAL:
                signs = (1.0, -1.0, -1.0)
            else:
                signs = (float(B[dst, src.start]),)
            for i, sign in enumerate(signs):
                out[mb.root_dof + dst + i] = sign * theta[mb.root_dof + src.start + i]
        return ca.vertcat(*out)

    # ---- numeric inverse ---------------------------------------------------------------

    def coordinates(self, q: np.ndarray) -> np.ndarray:
        """theta of director configurations q: (k,) -> (n,) or (m, k) -> (m, n); the
        inverse of `configuration` on the chart (angles as `gait_planner.model.angles`)."""
        q = np.asarray(q, dtype=float)
        if q.ndim == 2:
            return np.array([self.coordinates(row) for row in q])
        start = self.mb.block(self.scene.root.body).start
        phi, R = q[start : start + 3], q[start + 3 : start + 12].reshape(3, 3).T
        if self.scene.root.type is RootType.FREE:
            root = [*phi, *root_angles(R)]
        else:
            root = [phi[0], phi[2], float(np.arctan2(R[0, 2], R[2, 2]))]
        return np.concatenate([root, joint_angles(self.scene, q)])
