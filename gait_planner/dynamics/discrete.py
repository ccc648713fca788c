"""Discrete mechanics of a `Multibody`: the variational integrator's named Functions.

Paper section 3 (Koch & Leyendecker 2015, eqs. 1-2), docs/design.md section 3. Shapes: k = 12 nb
configuration entries, nt joint torque components, ndof generalised velocities; h in s.

* ``discrete_lagrangian``  L_d(q0, q1, h) = h/2 v^T M v - h/2 (V(q0) + V(q1)),
  v = (q1 - q0)/h  (J s)
* ``discrete_lagrangian_d1`` / ``_d2``  D1 L_d, D2 L_d (k,), the slot derivatives
  (N s, director components)
* ``discrete_euler_lagrange``  r(q_prev, q, q_next, h_prev, h, tau_prev, tau) =
  D2 L_d(q_prev, q) + D1 L_d(q, q_next) + f+_{n-1} + f-_n (k,) with f-_n = h/2 B^T(q) tau,
  f+_{n-1} = h_prev/2 B^T(q) tau_prev; the constrained equations read
  r = (h_prev + h)/2 G^T(q) lambda  (eq. 1)
* ``reduced_discrete_euler_lagrange``  P^T(q) r (ndof,): the discrete null space method
* ``kinetic_energy`` T(q_dot) = 1/2 q_dot^T M q_dot (J), ``potential_energy`` V(q) (J)
* ``linear_momentum`` (p) -> (3,) kg m/s and ``angular_momentum`` (q, p) -> (3,) kg m^2/s
  about the world origin, for a momentum p conjugate to q (k,): sum phi x p_phi + d_i x p_di
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gait_planner.model.multibody import Multibody


class DiscreteMechanics:
    """The variational integrator's Functions for one multibody system."""

    def __init__(self, mb: Multibody):
        self.mb = mb
        k, nt = mb.k, mb.nt
        M = ca.DM(mb.mass_diagonal)
        grad_v = np.zeros(k)
        for i, body in enumerate(mb.scene.bodies):
            grad_v[12 * i + 2] = body.mass * mb.scene.gravity
        self.gravity_gradient = grad_v  # dV/dq, constant (N)

        q0, q1, q2 = (ca.SX.sym(n, k) for n in ("q_prev", "q", "q_next"))
        h0, h1 = ca.SX.sym("h_prev"), ca.SX.sym("h")
        t0, t1 = ca.SX.sym("tau_prev", nt), ca.SX.sym("tau", nt)
        qd, p = ca.SX.sym("q_dot", k), ca.SX.sym("p", k)

        V = ca.dot(ca.DM(grad_v), q0)
        self.potential_energy = ca.Function("potential_energy", [q0], [V], ["q"], ["V"])
        T = 0.5 * ca.dot(qd, M * qd)
        self.kinetic_energy = ca.Function("kinetic_energy", [qd], [T], ["q_dot"], ["T"])

        v = (q1 - q0) / h1
        Ld = 0.5 * h1 * ca.dot(v, M * v) - 0.5 * h1 * (
            self.potential_energy(q0) + self.potential_energy(q1)
        )
        self.discrete_lagrangian = ca.Function(
            "discrete_lagrangian", [q0, q1, h1], [Ld], ["q0", "q1", "h"], ["Ld"]
        )
        self.discrete_lagrangian_d1 = ca.Function(
            "discrete_lagrangian_d1", [q0, q1, h1], [ca.gradient(Ld, q0)], ["q0", "q1", "h"], ["D1Ld"]
        )
        self.discrete_lagrangian_d2 = ca.Function(
            "discrete_lagrangian_d2", [q0, q1, h1], [ca.gradient(Ld, q1)], ["q0", "q1", "h"], ["D2Ld"]
        )

        r = (
            self.discrete_lagrangian_d2(q0, q1, h0)
            + self.discrete_lagrangian_d1(q1, q2, h1)
            + mb.actuation_force(q1, 0.5 * h0 * t0 + 0.5 * h1 * t1)  # f+_{n-1} + f-_n
        )
        names = ["q_prev", "q", "q_next", "h_prev", "h", "tau_prev", "tau"]
        args = [q0, q1, q2, h0, h1, t0, t1]
        self.discrete_euler_lagrange = ca.Function(
            "discrete_euler_lagrange", args, [r], names, ["r"]
        )
        self.reduced_discrete_euler_lagrange = ca.Function(
            "reduced_discrete_euler_lagrange",
            args,
            [ca.mtimes(mb.null_space(q1).T, r)],
            names,
            ["Ptr"],
        )

        blocks = [p[12 * i : 12 * i + 12] for i in range(mb.nb)]
        qblocks = [q0[12 * i : 12 * i + 12] for i in range(mb.nb)]
        L = sum((b[0:3] for b in blocks), ca.DM.zeros(3))
        J = ca.DM.zeros(3)
        for qb, b in zip(qblocks, blocks):
            for j in range(4):
                J += ca.cross(qb[3 * j : 3 * j + 3], b[3 * j : 3 * j + 3])
        self.linear_momentum = ca.Function("linear_momentum", [p], [L], ["p"], ["L"])
        self.angular_momentum = ca.Function(
            "angular_momentum", [q0, p], [J], ["q", "p"], ["J"]
        )

    def momentum(self, q_prev: np.ndarray, q: np.ndarray, h_prev: float,
                 tau_prev: np.ndarray | None = None) -> np.ndarray:
        """Discrete momentum p-_n = D2 L_d(q_{n-1}, q_n) + f+_{n-1} at node n (k,)."""
        p = np.array(self.discrete_lagrangian_d2(q_prev, q, h_prev)).ravel()
        if tau_prev is not None:
            p += 0.5 * h_prev * np.array(self.mb.actuation(q)) @ tau_prev
        return p
