"""The transcription's cost (paper section 7; docs/design.md sections 5 and 8): J over the half
cycle t_0..t_{N-1}, the discrete kinetic energy of its intervals (the paper's) or the
trapezoidal integral of the squared node torques, and the regularisers that give the
unknowns the equations leave free some curvature: the squared torques (a small weight under
the kinetic energy), the full contacts' along-line shares and the feet's twist about the
shank (`ocp.posture.twist_squares`).

`CostTerms` is a part of `ocp.transcription.Transcription` (a mixin, as `ocp.path_rows.
PathRows`: it reads the transcription's unknowns and declares the kinetic energy as
elements through its `_interval_terms`); `cost_parts` keeps the named terms for the result
(`ocp.solution`).
"""

from __future__ import annotations

import casadi as ca

from gait_planner.ocp.posture import twist_squares

# Weight (cost per (N m)^2) of a transition's torques' distance from the gait's at its
# join (`CostTerms._join_torques`). 1e-4 (walker2d's torque_smoothness) kept transitions
# from states near the gait smooth, but walker2d's start from standing zigzagged at the
# join (knee_r 4-6 N m from node to node, the verifier's check); 1e-3 made it smooth at
# +1.7 % J (benchmarks/HISTORY.md, 2026-12-07).
JOIN_WEIGHT = 1e-3


class CostTerms:
    """The cost of a `Transcription` (its `_cost` step)."""

    def _cost(self):
        """J over the half cycle t_0..t_{N-1} (intervals 0..N-2), plus the torque
        regulariser; returns the MX cost and stores the named parts. The kinetic energy is
        also declared as elements (`_interval_terms`), for `ocp.derivatives`."""
        N, s = self.N, self.settings
        h = self.h[0 : N - 1].T
        squares = ca.sum1(self.TAU[:, 0:N] ** 2)  # nodes 0..N-1
        torque = ca.sum2(0.5 * (squares[0 : N - 1] + squares[1:N]) * h)  # trapezoidal
        kinetic = ca.sum2(self._interval_terms(self._kinetic_energy(), 0.0, None
                                               if s.cost == "kinetic_energy" else False))
        self.cost_parts = {"kinetic_energy": kinetic, "torque_squared": torque}
        # The along-line shares of full contacts (`ocp.contacts`) move no equation: without
        # curvature of their own IPOPT's steps in them were unbounded (constraint violation
        # 1e5 and more, walker3d's inertia-free attempt failed). The regulariser's weight,
        # times sum h_n s^2, picks the smallest shares that keep every point in its cone.
        shares = s.torque_regularisation * self._share_squares()
        twist = 0.0
        if s.twist_regularisation > 0:
            twist = ca.sum2(self._interval_terms(twist_squares(self.mb), s.twist_regularisation,
                                                 None))
        smooth = self._torque_smoothness() + self._join_torques()
        if s.cost == "torque_squared":
            self.cost_without_elements = torque + shares + smooth
            return self.cost_without_elements + twist
        self.cost_without_elements = s.torque_regularisation * torque + shares + smooth
        return kinetic + self.cost_without_elements + twist

    def _torque_smoothness(self):
        """w sum over nodes n = 1..N-1 of |tau_{n+1} - 2 tau_n + tau_{n-1}|^2, w the setting
        `torque_smoothness` (units of the cost per (N m)^2): the node torques' second
        differences, across the half cycle's mirrored join (nodes N-1 and N are the images
        of 0 and 1), so a torque that jumps at one node and back costs what it costs
        anywhere; 0 if the setting is off."""
        w = self.settings.torque_smoothness
        if w <= 0:
            return 0.0
        tau = self.TAU
        second = tau[:, 2:] - 2 * tau[:, 1:-1] + tau[:, :-2]  # (nt, N-1): nodes 1..N-1
        return w * ca.sum1(ca.sum2(second**2))

    def _join_torques(self):
        """A transition's (`ocp.transition`) JOIN_WEIGHT sum over nodes n = 1..N-1 of
        |e_{n+1} - 2 e_n + e_{n-1}|^2, e_n = tau_n - tau_n^gait the torques' departure from
        the gait walked as far (`end_torque`, node N's the gait's own): a start off the
        gait is corrected smoothly, and from the gait's own first node the gait costs
        nothing. Node N-1's torque is free (its equation meets the gait's next node):
        without a cost the optimum spent it on a one-node spike (walker2d from a turned
        start: knee -31, -49, -38 N m at nodes 38-40), and with the distance from the
        gait's torques at the last 2 or 4 nodes only, walker3d's two-half-cycle
        transitions zigzagged where that window began (the verifier's check).
        0 for a periodic half cycle."""
        if not self.transition:
            return 0.0
        nt, N = self.mb.nt, self.N
        off = self.TAU - ca.reshape(self.end_torque, nt, N + 1)
        second = off[:, 2:] - 2 * off[:, 1:-1] + off[:, :-2]  # nodes 1..N-1
        return JOIN_WEIGHT * ca.sum1(ca.sum2(second**2))

    def _share_squares(self):
        """sum over nodes of w_n s^2 (N^2 s) of the full contacts' along-line shares s."""
        terms = []
        for n in self.lam_nodes:
            lam, offset = self.lam_of_node[n], 0
            w = 0.5 * ((self.h[n - 1] if n > 0 else 0.0) + self.h[n])
            for bc in self.contacts[self.phase_of_interval[n]]:
                offset += bc.n_multipliers
                if bc.full:
                    terms.append(w * lam[offset - 1] ** 2)
        return ca.sum1(ca.vertcat(*terms)) if terms else 0.0

    def _kinetic_energy(self) -> ca.Function:
        """(q_n, q_{n+1}, h_n, c) -> h_n times the discrete kinetic energy of interval n,
        0.5 (q_{n+1} - q_n)^T M (q_{n+1} - q_n) / h_n (J s); c unused."""
        q0, q1 = ca.SX.sym("q", self.mb.k), ca.SX.sym("q_next", self.mb.k)
        h, c = ca.SX.sym("h"), ca.SX.sym("c", 2)
        dq = q1 - q0
        kinetic = 0.5 * ca.dot(dq, ca.DM(self.mb.mass_diagonal) * dq) / h
        return ca.Function("kinetic", [q0, q1, h, c], [kinetic], ["q", "q_next", "h", "c"], ["J"])
