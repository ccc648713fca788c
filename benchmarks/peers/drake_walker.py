"""The walker of a problem.json in Drake (drake peer env only): the URDF parsed into a
MultibodyPlant with a quaternion floating base (the parser's default for a free root link),
its AutoDiffXd copy, the coordinates the optimisation uses, and the conversion to and from
the exchange format's Pinocchio configurations.

Drake orders a configuration [qw qx qy qz x y z, joints in the plant's order] (nq) and a
velocity [w_W (3,), v_W (3,), joint rates] (nv), both in world axes. A planar walker (every
revolute axis along y, as walker2d's URDF) is locked to the x-z plane by a linear selection:
the reduced configuration keeps (qw, qy, x, z, joints), the reduced velocity (wy, vx, vz,
joint rates); q = Sq q_r, v = Sv v_r, and the equations of motion are projected by Sv^T
(d'Alembert: the lock's reaction does no work along the kept velocities). A 3D walker keeps
every coordinate (Sq, Sv identity).

Residuals take numpy arrays of float or of AutoDiffXd (MathematicalProgram's generic
constraints call them with both) and evaluate the float or the AutoDiffXd plant (the
dtype decides: object arrays are AutoDiffXd).
"""

from __future__ import annotations

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable, MultibodyForces_

QUAT = slice(0, 4)  # Drake's base quaternion (w, x, y, z) in q
PLANAR_Q = (0, 2, 4, 6)  # qw, qy, x, z
PLANAR_V = (1, 3, 5)  # wy, vx, vz


class Walker:
    """problem["urdf"] in Drake. Attributes: plant, ad (AutoDiffXd plant), planar,
    nq/nv (reduced sizes), nj (joints), dims (force/position rows per contact point:
    (0, 2) planar, (0, 1, 2) in 3D), keep_q/keep_v (reduced -> full indices), quat (reduced
    indices of the quaternion), joint_q/joint_v (reduced indices of the joints in
    problem["joint_names"] order), frames/ad_frames (contact frames of either plant)."""

    def __init__(self, problem: dict):
        plant = MultibodyPlant(0.0)
        Parser(plant).AddModels(problem["urdf"])
        plant.Finalize()
        self.plant, self.ad = plant, plant.ToAutoDiffXd()
        self.context, self.ad_context = plant.CreateDefaultContext(), \
            self.ad.CreateDefaultContext()
        root = plant.GetBodyByName(problem["root_link"])
        if not root.is_floating_base_body() or root.floating_positions_start() != 0:
            raise ValueError(f"root link {problem['root_link']} is not the floating base")
        joints = [plant.GetJointByName(name) for name in problem["joint_names"]]
        self.planar = all(abs(abs(j.revolute_axis()[1]) - 1.0) < 1e-12 for j in joints)
        full_jq = [j.position_start() for j in joints]
        full_jv = [j.velocity_start() for j in joints]
        if self.planar:
            self.keep_q = np.array(PLANAR_Q + tuple(full_jq))
            self.keep_v = np.array(PLANAR_V + tuple(full_jv))
            self.dims = (0, 2)
        else:
            self.keep_q = np.arange(plant.num_positions())
            self.keep_v = np.arange(plant.num_velocities())
            self.dims = (0, 1, 2)
        self.nq, self.nv, self.nj = len(self.keep_q), len(self.keep_v), len(joints)
        self.quat = np.flatnonzero(self.keep_q < 4)
        self.joint_q = np.array([list(self.keep_q).index(i) for i in full_jq])
        self.joint_v = np.array([list(self.keep_v).index(i) for i in full_jv])
        self.frames = {c: plant.GetFrameByName(c) for c in problem["contact_frames"]}
        self.ad_frames = {c: self.ad.GetFrameByName(c) for c in problem["contact_frames"]}
        self._mirror = _mirror_maps(problem, self)

    # --- conversion -------------------------------------------------------------------
    def from_pin(self, q_pin: np.ndarray) -> np.ndarray:
        """Reduced configuration (nq,) from a Pinocchio one (7 + nj,): [x y z qx qy qz qw,
        joints in joint_names order]; the quaternion is normalised."""
        full = np.zeros(self.plant.num_positions())
        quat = np.array([q_pin[6], q_pin[3], q_pin[4], q_pin[5]])
        full[QUAT] = quat / np.linalg.norm(quat)
        full[4:7] = q_pin[:3]
        reduced = full[self.keep_q]
        reduced[self.joint_q] = q_pin[7:]
        if self.planar:
            reduced[self.quat] /= np.linalg.norm(reduced[self.quat])
        return reduced

    def to_pin(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio configuration (7 + nj,) of a reduced one (nq,)."""
        full = self.full_q(q)
        return np.concatenate([full[4:7], full[1:4], full[:1], q[self.joint_q]])

    def full_q(self, q: np.ndarray) -> np.ndarray:
        """Drake configuration (plant nq,) of a reduced one; locked coordinates zero."""
        full = np.zeros(self.plant.num_positions(), dtype=q.dtype)
        full[self.keep_q] = q
        return full

    def full_v(self, v: np.ndarray) -> np.ndarray:
        """Drake velocity (plant nv,) of a reduced one; locked rates zero."""
        full = np.zeros(self.plant.num_velocities(), dtype=v.dtype)
        full[self.keep_v] = v
        return full

    # --- mirror (half-cycle periodicity) --------------------------------------------
    def mirror_q(self, q: np.ndarray) -> np.ndarray:
        """The mirror image (about y = 0, shifted by the step length in x) of a reduced
        configuration: A q + b, linear (the quaternion (w, x, y, z) -> (w, -x, y, -z))."""
        a, b, _ = self._mirror
        return a @ q + b

    def mirror_v(self, v: np.ndarray) -> np.ndarray:
        """The mirror image of a reduced velocity."""
        return self._mirror[2] @ v

    def mirror_matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(A (nq, nq), b (nq,), Av (nv, nv)): q' = A q + b, v' = Av v."""
        return self._mirror

    def contact_partners(self, q: np.ndarray) -> dict[str, str]:
        """Contact -> its mirror partner: the contact whose point at the mirror image of q
        lies nearest the mirror image of this contact's point at q."""
        reflect = np.array([1.0, -1.0, 1.0])
        shift = np.array([self._mirror[1][list(self.keep_q).index(4)], 0.0, 0.0])
        image = self.mirror_q(q)
        return {c: min(self.frames, key=lambda d: np.linalg.norm(
            self.point(image, d) - (reflect * self.point(q, c) + shift)))
            for c in self.frames}

    # --- mechanics ----------------------------------------------------------------------
    def _set(self, q: np.ndarray, v: np.ndarray | None = None):
        """The plant (float or AutoDiffXd, after q's dtype) and its context at (q, v)."""
        ad = q.dtype == object
        plant, context = (self.ad, self.ad_context) if ad else (self.plant, self.context)
        plant.SetPositions(context, self.full_q(q))
        if v is not None:
            plant.SetVelocities(context, self.full_v(v))
        return plant, context

    def point(self, q: np.ndarray, contact: str) -> np.ndarray:
        """World position (3,) m of a contact frame's origin."""
        plant, context = self._set(q)
        return plant.CalcPointsPositions(context, self._frame(plant, contact), np.zeros(3),
                                         plant.world_frame())[:, 0]

    def point_jacobian(self, q: np.ndarray, contact: str) -> np.ndarray:
        """(3, nv) reduced translational Jacobian of a contact frame's origin."""
        return self._jacobian(*self._set(q), contact)

    def _jacobian(self, plant, context, contact: str) -> np.ndarray:
        """point_jacobian at the context's configuration."""
        jac = plant.CalcJacobianTranslationalVelocity(
            context, JacobianWrtVariable.kV, self._frame(plant, contact), np.zeros(3),
            plant.world_frame(), plant.world_frame())
        return jac[:, self.keep_v]

    def dynamics_residual(self, h, q0, q1, v0, v1, tau, forces, midpoint: bool
                          ) -> np.ndarray:
        """Discrete equations of motion over one interval, reduced (nv,):
        M(q*)(v1 - v0) - h (B tau + sum_c J_c(q*)^T f_c + tau_g(q*) - C(q*, v*) v*),
        tau (nj,) joint torques N m, forces {contact: (len(dims),) N world}. Backward Euler
        (Drake's ManipulatorEquationConstraint): (q*, v*) = (q1, v1); midpoint (second
        order): q* = (q0 + q1)/2 with its quaternion normalised, v* = (v0 + v1)/2.
        Evaluated as h ID(q*, v*, (v1 - v0)/h) - h (B tau + sum J^T f) by Drake's recursive
        inverse dynamics with gravity (O(n), no mass matrix formed)."""
        q, v = (self.midpoint(q0, q1), 0.5 * (v0 + v1)) if midpoint else (q1, v1)
        plant, context = self._set(q, v)
        applied = self._gravity(plant, context)
        out = plant.CalcInverseDynamics(context, self.full_v((v1 - v0) / h),
                                        applied)[self.keep_v] - self._joint_forces(tau)
        for contact, force in forces.items():
            out = out - self._jacobian(plant, context, contact)[list(self.dims)].T @ force
        return h * out

    def kinematics_residual(self, h, q0, q1, v0, v1, midpoint: bool) -> np.ndarray:
        """Configuration update (nv,): v* - N+(q*)(q1 - q0)/h (Drake's MapQDotToVelocity;
        the quaternion's norm is a separate constraint), (q*, v*) as dynamics_residual's."""
        if midpoint:
            return 0.5 * (v0 + v1) - self.velocity(h, q0, q1, self.midpoint(q0, q1))
        return v1 - self.velocity(h, q0, q1, q1)

    def velocity(self, h, q0, q1, q) -> np.ndarray:
        """Reduced velocity (nv,) N+(q)(q1 - q0)/h."""
        plant, context = self._set(q)
        return plant.MapQDotToVelocity(context, self.full_q((q1 - q0) / h))[self.keep_v]

    def midpoint(self, q0, q1) -> np.ndarray:
        """(q0 + q1)/2 with its quaternion entries normalised."""
        q = 0.5 * (q0 + q1)
        quat = q[self.quat]
        q[self.quat] = quat / (quat @ quat) ** 0.5
        return q

    def impact_residual(self, q, v_minus, v_plus, impulses) -> np.ndarray:
        """Plastic impact (nv,): M(q)(v+ - v-) - sum_c J_c(q)^T Lambda_c, impulses
        {contact: (len(dims),) N s}."""
        plant, context = self._set(q, np.zeros(self.nv, dtype=q.dtype))
        out = self._mass_times(plant, context, v_plus - v_minus)
        for contact, impulse in impulses.items():
            out = out - self._jacobian(plant, context, contact)[list(self.dims)].T @ impulse
        return out

    def kinetic_energy(self, q, v):
        """1/2 v^T M(q) v, J."""
        return 0.5 * v @ self._mass_times(*self._set(q, np.zeros(self.nv, dtype=q.dtype)), v)

    def _mass_times(self, plant, context, x) -> np.ndarray:
        """M(q) x (nv,) at a context of zero velocity: inverse dynamics with no forces."""
        return plant.CalcInverseDynamics(context, self.full_v(x),
                                         MultibodyForces_[_scalar(plant)](plant))[self.keep_v]

    def _gravity(self, plant, context):
        """MultibodyForces holding the plant's force elements (gravity) at the context."""
        forces = MultibodyForces_[_scalar(plant)](plant)
        plant.CalcForceElementsContribution(context, forces)
        return forces

    def torso_up(self, quat: np.ndarray):
        """World z component of the root's z axis, from the reduced quaternion's entries
        (w, x, y, z, or w, y when planar): 1 - 2 (x^2 + y^2)."""
        return 1.0 - 2.0 * (quat[1:3] @ quat[1:3] if not self.planar else quat[1] ** 2)

    def _joint_forces(self, tau):
        out = np.zeros(self.nv, dtype=tau.dtype)
        out[self.joint_v] = tau
        return out

    def _frame(self, plant, contact):
        return (self.frames if plant is self.plant else self.ad_frames)[contact]


def _mirror_maps(problem: dict, walker: Walker):
    """(A, b, Av) of the mirror in reduced coordinates, from problem["mirror"]: joint_map
    [[i, j, sign]] (mirrored joint j = sign * joint i, joint_names indices) and the base:
    x + x_shift, y reflected (y -> -y, quaternion x and z negated, angular velocity x and z
    negated, linear velocity y negated)."""
    plant = walker.plant
    nq_full, nv_full = plant.num_positions(), plant.num_velocities()
    aq, av = np.zeros((nq_full, nq_full)), np.zeros((nv_full, nv_full))
    base = problem["mirror"]["base"]
    reflect = -1.0 if base.get("reflect_y", True) else 1.0
    for i, s in enumerate((1.0, reflect, 1.0, reflect, 1.0, reflect, 1.0)):
        aq[i, i] = s  # qw qx qy qz x y z
    for i, s in enumerate((reflect, 1.0, reflect, 1.0, reflect, 1.0)):
        av[i, i] = s  # wx wy wz vx vy vz
    b = np.zeros(nq_full)
    b[4] = base["x_shift"]
    a = aq[np.ix_(walker.keep_q, walker.keep_q)]
    a_v = av[np.ix_(walker.keep_v, walker.keep_v)]
    for i, j, sign in problem["mirror"]["joint_map"]:
        qi, qj = walker.joint_q[int(i)], walker.joint_q[int(j)]
        vi, vj = walker.joint_v[int(i)], walker.joint_v[int(j)]
        a[qj, :] = 0.0
        a[qj, qi] = sign
        a_v[vj, :] = 0.0
        a_v[vj, vi] = sign
    return a, b[walker.keep_q], a_v


def _scalar(plant) -> type:
    """The scalar type of a plant: float or AutoDiffXd."""
    return float if isinstance(plant, MultibodyPlant) else AutoDiffXd
