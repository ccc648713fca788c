"""DMOCC transcription of the half-cycle gait (paper section 7) as a CasADi NLP.

Nodes n = 0..N, intervals n = 0..N-1 (interval n from t_n to t_{n+1}, length
h_n = sigma_{phase(n)} * base_time_step). Phase k owns a run of intervals; the contacts it
holds are held on each of its intervals (chain condition) and their forces act in the
equation of every node that starts one of its intervals, so a contact's force is zero at
the node where it is released and carries the plastic impact at the node where it is
established (docs/design.md section 7).

Unknowns (scaled to O(1)):
* u_n (ndof,) for the free nodes n = 0..N-2: the configuration q_n = F_d(u_n, qref_n) is
  the nodal reparametrisation about a reference configuration of that node (the initial
  guess or a previous plan). Every internal and joint constraint holds exactly, and each
  equation touches only neighbouring nodes (a banded KKT system). Its rotational entries
  are bounded by ROTATION_INCREMENT_MAX.
* tau_n (nt,) joint torques at the free nodes 0..N-2 (in units of TORQUE_SCALE). Torques
  are node values, piecewise linear in time: the trapezoidal rule of the virtual work of
  the Lagrange-d'Alembert principle gives node n the discrete force
  f+_{n-1} + f-_n = (h_{n-1} + h_n)/2 B^T(q_n) tau_n, so the torque published at a node is
  the torque its equation applies. (The paper's piecewise-constant interval torques put
  (h_{n-1} tau_{n-1} + h_n tau_n)/2 into node n's equation: a sequence alternating in sign
  from interval to interval is invisible to the equations, and the optimum deconvolved
  rapidly varying node demands into such zigzags, measured up to 2.7 times a joint's peak
  torque in its second difference; benchmarks/HISTORY.md.)
* lambda_n, contact multipliers of nodes 1..N-1 (in units of FORCE_SCALE): the paper
  removes them by projection (its Q matrices) and recovers them by eq. 10; keeping them as
  unknowns gives the same discrete trajectory and makes the friction cones and unilateral
  conditions plain inequalities on unknowns.
* sigma, the phase scalings (sigma_1 serves phases 1 and 5).
The periodic end is not a set of unknowns: q_{N-1}, q_N, tau_{N-1}, tau_N are the mirrored
expressions of q_0, q_1, tau_0, tau_1, the configurations shifted by the step length (paper
eqs. 7-9). Where each unknown sits in x, and the per-node element Functions of the
derivatives: `ocp.elements`.

Parameters (changeable without rebuilding or compiling): the reference configurations, the
step length, the friction coefficient, the ground's slope or stair height
(`gait_planner.model.ground.ParametricGround`) and the requested speed (`parameters`). A
Transcription is built for one request and serves every request with the same settings
but these values and the same `Ground.form` (`shape_of`).
"""

from __future__ import annotations

import dataclasses
import math

import casadi as ca

import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.model.ground import PARAMETERS, ParametricGround
from gait_planner.ocp.contacts import (body_contacts, establishing_rows, phase_rows,
                                       phase_treads, stacked_rows)
from gait_planner.ocp.cost_terms import CostTerms
from gait_planner.ocp.elements import ElementGroup, Layout
from gait_planner.ocp.held_efforts import HeldRows
from gait_planner.ocp.mirror import increment_mirror, mirror_parts, torque_mirror
from gait_planner.ocp.path_rows import FORCE_SCALE, PathRows
from gait_planner.ocp.settings import GaitSettings, ground_of

TORQUE_SCALE = 100.0  # N m
# Bound (rad) on each rotational entry of u_n. The reparametrisation about qref_n is a chart
# that is one-to-one for turns below half a revolution; a Newton step beyond it is a
# divergence, not progress. With IPOPT's inertia-free curvature test (solve.py) walker2d
# cold solves diverged without these bounds (benchmarks/HISTORY.md); no plan measured had
# one active.
ROTATION_INCREMENT_MAX = np.pi


class Transcription(PathRows, HeldRows, CostTerms):
    """The NLP of one (scene, settings) pair: variables, constraints and their meaning.

    With settings.start_momentum the NLP is a transition (`gait_planner.ocp.transition`):
    not periodic, but with given ends. Every node 0..N has unknowns of its own (u_0,
    u_{N-1} and u_N are fixed at zero by their bounds, so q_0 = qref_0 is the start and
    q_{N-1}, q_N = qref_{N-1}, qref_N join the gait; with settings.end_at_rest, a stop,
    they are node N-2's configuration: at rest, node N holding node N-1's torques); node 0
    has a dynamics row of its own,
    `_start_row`, and contact multipliers; the last interval has a sigma of its own, held
    at the gait's by the row end_scaling, and node N's torques are the gait's (parameters,
    with the gait's at the nodes before for the cost's `CostTerms._join_torques`); no pin_x and
    no speed row."""

    def __init__(self, mech: DiscreteMechanics, settings: GaitSettings):
        self.mech, self.mb, self.settings = mech, mech.mb, settings
        mb, scene = self.mb, self.mb.scene
        phases = scene.gait.phases
        self.phase_of_interval = np.repeat(np.arange(len(phases)), settings.intervals)
        self.N = N = int(self.phase_of_interval.size)
        if N < 3:
            raise ValueError(f"a half cycle needs at least 3 intervals, got {N}")
        # the ground's form shapes the NLP, its values are parameters: symbols gs of the
        # element Functions, the entries gp of p in the NLP's own graph
        self.gs = ParametricGround.symbols(ground_of(scene, settings))
        self.ground_p = ca.MX.sym("ground", len(PARAMETERS))
        self.gp = self.gs.like(self.ground_p)
        self.contacts = [body_contacts(mb, p.contacts) for p in phases]  # rows: level ground
        self.rows = [stacked_rows(c, mb.k) for c in self.contacts]  # (their sizes)
        self.rows_of = [ca.Function(f"contact_rows_phase{k}", [self.gs.values],
                                    [phase_rows(mb, c, self.gs)])
                        for k, c in enumerate(self.contacts)]  # ground -> C_k
        self.A, along, up = mirror_parts(mb)
        self.B = torque_mirror(mb)
        # Nodes N-1 and N are mirror images of nodes 0 and 1. Where the mirror commutes with
        # the reparametrisation (`increment_mirror`), their elements are the regular ones
        # evaluated at mirrored unknowns and references (`Layout.images`), and join the regular
        # nodes' vector passes (`ocp.derivatives`); otherwise (the compass) they are
        # variants of their own that mirror the configuration they compute.
        self.M = increment_mirror(mb)
        self.transition = bool(settings.start_momentum)

        nsig = scene.gait.n_scalings + self.transition  # a transition's last interval: its own
        scaling = np.array([phases[k].scaling for k in self.phase_of_interval])
        if self.transition:
            scaling[N - 1] = nsig - 1
        rest = self.transition and settings.end_at_rest  # nodes N-1, N: node N-2, at rest
        free = N + 1 if self.transition and not rest else N - 1  # nodes with unknowns
        self.U = ca.MX.sym("u", mb.ndof, free)
        self.T = ca.MX.sym("tau", mb.nt, N if self.transition else N - 1)
        self.S = ca.MX.sym("sigma", nsig)
        self.lam_nodes = list(range(0 if self.transition else 1, N))
        self.lam_sizes = [sum(bc.n_multipliers for bc in self.contacts[self.phase_of_interval[n]])
                          for n in self.lam_nodes]
        self.L = ca.MX.sym("lambda", int(sum(self.lam_sizes)))
        self.layout = Layout(mb, N, self.lam_sizes, nsig, scaling, self.A, along, up, self.B,
                             self.M, self.transition, rest)
        self.Qref = ca.MX.sym("qref", mb.k, free)
        self.step, self.mu = ca.MX.sym("step_length"), ca.MX.sym("mu")
        self.inverse_speed = ca.MX.sym("inverse_speed")
        self.start_momentum = ca.MX.sym("start_momentum", mb.k if self.transition else 0)
        self.end_scaling = ca.MX.sym("end_scaling", 1 if self.transition else 0)
        self.end_torque = ca.MX.sym("end_torque", (N + 1) * mb.nt if self.transition else 0)

        q_free = mb.reparametrise.map(free)(self.U, self.Qref)
        tau = TORQUE_SCALE * self.T
        if rest:  # at rest from node N-2 on, node N-1's torques held at node N
            self.Q = ca.horzcat(q_free, q_free[:, N - 2], q_free[:, N - 2])  # (k, N+1)
            self.TAU = ca.horzcat(tau, tau[:, N - 1])  # (nt, N+1)
        elif self.transition:
            self.Q = q_free  # (k, N+1)
            self.TAU = ca.horzcat(tau, self.end_torque[N * mb.nt :])  # (nt, N+1)
        else:
            q_end = [self.layout.image(q_free[:, j], self.step, self.ground_p) for j in (0, 1)]
            self.Q = ca.horzcat(q_free, *q_end)  # (k, N+1)
            self.TAU = ca.horzcat(tau, ca.mtimes(ca.DM(self.B), tau[:, 0:2]))  # (nt, N+1) nodes
        select = np.zeros((N, nsig))
        select[np.arange(N), scaling] = 1.0
        self.h = settings.base_time_step * ca.mtimes(ca.DM(select), self.S)  # (N,)
        self.lam_of_node = {}
        offset = 0
        for n, size in zip(self.lam_nodes, self.lam_sizes):
            self.lam_of_node[n] = FORCE_SCALE * self.L[offset : offset + size]
            offset += size

        self._eq, self._ineq = [], []  # (name, expression)
        self._without_elements = {}  # name -> the group's expression without its elements
        self._upper = {}  # name -> the upper bound of an inequality group's rows (default: none)
        self.elements: list[ElementGroup] = []  # parts of g and cost (see ElementGroup)
        self._dynamics()
        self._contacts()
        self._path()
        self._held()
        self.cost = self._cost()
        self._node_rows()

    # ---- constraint groups ----------------------------------------------------------

    def _dynamics(self):
        """Reduced discrete Euler-Lagrange equations of nodes 1..N-1, divided by
        w_n = (h_{n-1} + h_n)/2 so that they read as forces, in units of FORCE_SCALE: the
        rows are O(1) like the others, so IPOPT's absolute constraint tolerance (1e-10)
        means 1e-7 N here, reachable in floating point (in plain newtons it stalled at
        ~2e-10 for hundreds of iterations).

        A node's row is P(q_n)^T r / (w_n FORCE_SCALE) + P(q_n)^T C^T lambda_n / FORCE_SCALE
        (the contact force term; w_n cancels). The first part is the same function in
        every phase; it is also declared as an element of the NLP's own unknowns
        (`ElementGroup`, `_dynamics_element`), so that its derivatives can be formed node by
        node (`ocp.derivatives`), and so is the contact term (`_node_rows`). g itself is
        built from the configurations Q, which all rows share."""
        mb, N = self.mb, self.N
        for variant, nodes in self._element_nodes().items():
            self.elements.append(ElementGroup(
                self._dynamics_element(*variant),
                np.stack([self._element_z_index(n) for n in nodes], axis=1),
                np.stack([self._element_p_index(n) for n in nodes], axis=1),
                np.stack([np.arange(mb.ndof) + (n - 1) * mb.ndof for n in nodes], axis=1),
                np.array([self.settings.base_time_step])))
        for k, C in enumerate(self.rows):
            nodes = [n for n in range(1, N) if self.phase_of_interval[n] == k]
            if not nodes:
                continue
            q0, q1, q2 = (ca.SX.sym(s, mb.k) for s in ("q_prev", "q", "q_next"))
            h0, h1 = ca.SX.sym("h_prev"), ca.SX.sym("h")
            tau = ca.SX.sym("tau", mb.nt)  # node n's torque acts on both its half intervals
            lam, ground = ca.SX.sym("lambda", C.shape[0]), self.gs.values
            w = 0.5 * (h0 + h1)
            r = self.mech.discrete_euler_lagrange(q0, q1, q2, h0, h1, tau, tau)
            contact = mb.null_space_transpose(
                q1, ca.mtimes(self.rows_of[k](ground).T, lam)) / FORCE_SCALE
            res = mb.null_space_transpose(q1, r) / (w * FORCE_SCALE) + contact
            f = ca.Function(f"dynamics_phase{k}", [q0, q1, q2, h0, h1, tau, lam, ground], [res])
            idx = np.array(nodes)
            lam_cols = ca.horzcat(*[self._row_multipliers(n) for n in nodes]) if C.shape[0] \
                else ca.DM.zeros(0, len(nodes))
            out = f.expand().map(len(nodes))(
                self.Q[:, idx - 1], self.Q[:, idx], self.Q[:, idx + 1], self.h[idx - 1].T,
                self.h[idx].T, self.TAU[:, idx], lam_cols,
                ca.repmat(self.ground_p, 1, len(nodes)))
            name = f"dynamics[{self._phase_name(k)}]"
            self._eq.append((name, ca.vec(out)))
            self._without_elements[name] = ca.MX(out.numel(), 1)  # contact part: _node_rows
        if self.transition:
            self._start_row()

    def _start_row(self):
        """A transition's node 0 (`ocp.transition`): the discrete Legendre transform
        p_0 = -D1 L_d(q_0, q_1, h_0) - f-_0 - C^T lambda_0 of the given momentum p_0, the
        start's, reduced by P(q_0)^T and divided by w_0 = h_0 / 2 (rows in units of
        FORCE_SCALE, as `_dynamics`): node 0's discrete Euler-Lagrange equation with
        D2 L_d(q_{-1}, q_0) + f+_{-1} replaced by p_0 (DMOC's initial condition; paper
        section 4). lambda_0 are the contact multipliers of the first phase at node 0:
        the impulse of contacts that the start's velocity would break (a plastic strike)
        and their forces over the half interval. Their term is `_node_rows`' element."""
        mb, q0, h0 = self.mb, self.Q[:, 0], self.h[0]
        r = (self.start_momentum + self.mech.discrete_lagrangian_d1(q0, self.Q[:, 1], h0)
             + mb.actuation_force(q0, 0.5 * h0 * self.TAU[:, 0]))
        own = mb.null_space_transpose(q0, r) / (0.5 * h0 * FORCE_SCALE)
        k = self.phase_of_interval[0]
        contact = mb.null_space_transpose(
            q0, ca.mtimes(self.rows_of[k](self.ground_p).T, self._row_multipliers(0))) \
            / FORCE_SCALE if self.rows[k].shape[0] else 0.0
        self._eq.append(("start_momentum", own + contact))
        self._without_elements["start_momentum"] = own

    def node_multipliers(self, x: np.ndarray) -> dict[int, np.ndarray]:
        """The scaled contact multipliers (entries of L, FORCE_SCALE N) of each node
        1..N-1 in a numeric x."""
        return {n: x[self.layout.lam_index(n)] for n in self.lam_nodes}

    def _row_multipliers(self, n: int):
        """The multipliers of node n's contact rows (the along-line shares left out), N."""
        lam, parts, offset = self.lam_of_node[n], [], 0
        for bc in self.contacts[self.phase_of_interval[n]]:
            parts.append(lam[offset : offset + bc.n_rows])
            offset += bc.n_multipliers
        return ca.vertcat(*parts)

    def _element_nodes(self) -> dict[tuple[bool, bool], list[int]]:
        """Nodes 1..N-1 by element variant (q_n mirrored, q_{n+1} mirrored): q_{N-1} and
        q_N are mirror images of q_0 and q_1, and so is tau_{N-1} of tau_0."""
        out: dict[tuple[bool, bool], list[int]] = {}
        for n in range(1, self.N):
            out.setdefault((self.layout.mirrored(n == self.N - 1),
                            self.layout.mirrored(n + 1 >= self.N - 1)), []).append(n)
        return out

    def _element_configurations(self, mirrored: bool, next_mirrored: bool):
        """(z, pz, c, [q_{n-1}, q_n, q_{n+1}], h_{n-1}, h_n) of a node's three-node
        element: SX inputs z = (u_{n-1}, u_n, u_{n+1}, T_n, sigma_{n-1}, sigma_n) (scaled
        unknowns, a mirrored node given by the u and T of its source node), pz =
        (qref_{n-1}, qref_n, qref_{n+1}, step length, ground) and c = (base time step),
        and the configurations and time steps they give."""
        mb = self.mb
        nd, nt, k = mb.ndof, mb.nt, mb.k
        z = ca.SX.sym("z", 3 * nd + nt + 2)
        pz = ca.SX.sym("pz", 3 * k + 1 + len(PARAMETERS))
        c = ca.SX.sym("c", 1)
        step, ground = pz[3 * k], pz[3 * k + 1 :]
        q = [mb.reparametrise(z[i * nd : (i + 1) * nd], pz[i * k : (i + 1) * k]) for i in range(3)]
        for i, flag in ((1, mirrored), (2, next_mirrored)):
            if flag:
                q[i] = self.layout.image(q[i], step, ground)
        return z, pz, c, q, c[0] * z[3 * nd + nt], c[0] * z[3 * nd + nt + 1]

    def _dynamics_element(self, mirrored: bool, next_mirrored: bool) -> ca.Function:
        """The phase-independent part of a node's dynamics row (ndof,) as an SX Function
        of the three-node element's inputs (`_element_configurations`)."""
        mb = self.mb
        nd, nt = mb.ndof, mb.nt
        z, pz, c, q, h0, h1 = self._element_configurations(mirrored, next_mirrored)
        tau = TORQUE_SCALE * z[3 * nd : 3 * nd + nt]
        if mirrored:  # tau_{N-1} is the image of tau_0
            tau = ca.mtimes(ca.DM(self.B), tau)
        r = self.mech.discrete_euler_lagrange(q[0], q[1], q[2], h0, h1, tau, tau)
        res = mb.null_space_transpose(q[1], r) / (0.5 * (h0 + h1) * FORCE_SCALE)
        name = "dynamics_element" + ("_mirrored" if mirrored else "_next_mirrored" if next_mirrored else "")
        return ca.Function(name, [z, pz, c], [res], ["z", "pz", "c"], ["r"])

    def _element_z_index(self, n: int) -> np.ndarray:
        """Indices into x of the dynamics element's z (see _dynamics_element) at node n."""
        lay = self.layout
        return np.concatenate([lay.u_index(n - 1), lay.u_index(n), lay.u_index(n + 1),
                               lay.tau_index(n), [lay.scaling_index(n - 1), lay.scaling_index(n)]])

    def _element_p_index(self, n: int) -> np.ndarray:
        """Indices into p of the dynamics element's pz at node n."""
        lay = self.layout
        return np.concatenate([lay.qref_index(n - 1), lay.qref_index(n), lay.qref_index(n + 1),
                               [lay.step_index], lay.ground_index])

    def _contacts(self):
        mb, N = self.mb, self.N
        chain, rows = [], [f(self.ground_p) for f in self.rows_of]
        for n in range(N - 1):  # interval N-1 is the mirror image of interval 0
            k = self.phase_of_interval[n]
            if self.rows[k].shape[0]:
                chain.append(ca.mtimes(rows[k], self.Q[:, n + 1] - self.Q[:, n]))
        self._hold_elements(sum(int(e.shape[0]) for _, e in self._eq + self._ineq))
        self._eq.append(("contact_hold", ca.vertcat(*chain)))
        self._without_elements["contact_hold"] = ca.MX(sum(int(c.shape[0]) for c in chain), 1)
        est = []
        stops = {p.name for p in mb.scene.gait.stop} if self.settings.end_at_rest else set()
        treads = phase_treads(self.contacts, [p.name in stops for p in mb.scene.gait.phases])
        for n in range(1, N):
            k_prev, k = self.phase_of_interval[n - 1], self.phase_of_interval[n]
            if k != k_prev:
                E, e = establishing_rows(mb, self.contacts[k_prev], self.contacts[k],
                                         self.gp, treads[k])
                if E.shape[0]:
                    est.append(ca.mtimes(E, self.Q[:, n]) - e)
        if est:
            self._eq.append(("contact_establish", ca.vertcat(*est)))
        if self.transition:  # the last interval's length is the gait's first
            self._eq.append(("end_scaling", self.S[-1] - self.end_scaling))
        else:
            first = self.contacts[0][0].points[0]
            self._eq.append(("pin_x", ca.mtimes(ca.DM(mb.contact_rows(first)[0:1]),
                                                self.Q[:, 0])))
        if self.settings.speed > 0 and not self.transition:  # an equality: before the first
            # inequality group
            self._eq.append(("speed", speed_row(self.step, ca.sum1(self.h[0 : N - 1]),
                                                self.inverse_speed)))
        cones = []
        for n in self.lam_nodes:
            lam = self.lam_of_node[n]
            offset = 0
            for bc in self.contacts[self.phase_of_interval[n]]:
                cones += bc.cone_rows(lam[offset : offset + bc.n_multipliers], self.Q[:, n],
                                      self.mu, *self._cone_constants, normal=self.gp.normal)
                offset += bc.n_multipliers
        self._ineq.append(("friction_cone", ca.vertcat(*cones)))
        self._without_elements["friction_cone"] = ca.MX(len(cones), 1)  # _node_rows

    @property
    def _cone_constants(self) -> tuple[float, float]:
        """(friction smoothing N, foot half width m) of `BodyContact.cone_rows`."""
        return self.settings.friction_smoothing, self.settings.foot_half_width

    def _hold_elements(self, first_row: int):
        """The contact_hold rows C_k (q_{n+1} - q_n) of each interval n (phase k), from
        row first_row of g on, declared as interval elements."""
        N, mb = self.N, self.mb
        q0, q1, h, c = ca.SX.sym("q", mb.k), ca.SX.sym("q_next", mb.k), ca.SX.sym("h"), \
            ca.SX.sym("c", 2)
        ground = self.gs.values
        intervals: dict[tuple[int, bool], list[tuple[int, np.ndarray]]] = {}
        row = first_row
        for n in range(N - 1):
            C = self.rows[self.phase_of_interval[n]]
            if C.shape[0]:
                key = (int(self.phase_of_interval[n]), self.layout.mirrored(n == N - 2))
                intervals.setdefault(key, []).append((n, row + np.arange(C.shape[0])))
                row += C.shape[0]
        for (k, next_mirrored), chosen in intervals.items():
            fn = ca.Function(f"contact_hold_phase{k}", [q0, q1, h, c, ground],
                             [ca.mtimes(self.rows_of[k](ground), q1 - q0)],
                             ["q", "q_next", "h", "c", "ground"], ["r"])
            self.elements.append(ElementGroup(
                self.layout.interval_element(fn, next_mirrored),
                np.stack([self.layout.interval_z_index(n) for n, _ in chosen], 1),
                np.stack([self.layout.interval_p_index(n) for n, _ in chosen], 1),
                np.stack([rows for _, rows in chosen], 1),
                np.array([self.settings.base_time_step, 0.0])))

    def _interval_terms(self, fn: ca.Function, constant, first_row):
        """fn(q_n, q_{n+1}, h_n, c) (r,) of intervals 0..N-2 as an MX (r, N-1), with
        c = (base time step, constant) (constant a number or a vector). Declared as elements of the NLP (`ElementGroup`,
        `Layout.interval_element`): rows first_row + r n + (0..r-1) of g, or with first_row None
        terms of the cost; first_row False declares nothing (a term not in the NLP)."""
        N = self.N
        c = np.r_[self.settings.base_time_step, np.atleast_1d(constant)].astype(float)
        if first_row is not False:
            size = int(fn.size1_out(0))
            groups = ((False, range(N - 1)),) if not self.layout.mirrored(True) else \
                ((False, range(N - 2)), (True, [N - 2]))
            for next_mirrored, intervals in groups:
                rows = None if first_row is None else np.stack(
                    [first_row + size * n + np.arange(size) for n in intervals], 1)
                self.elements.append(ElementGroup(
                    self.layout.interval_element(fn, next_mirrored),
                    np.stack([self.layout.interval_z_index(n) for n in intervals], 1),
                    np.stack([self.layout.interval_p_index(n) for n in intervals], 1), rows, c))
        return fn.map(N - 1)(self.Q[:, 0 : N - 1], self.Q[:, 1:N], self.h[0 : N - 1].T,
                             ca.repmat(ca.DM(c), 1, N - 1))

    def _node_terms(self, fn: ca.Function, c: np.ndarray, first_row: int, nodes: list[int]):
        """fn(q_n, c) (r,) at `nodes` (within 1..N-1) as an MX (r, len(nodes)), declared as
        elements of the NLP: rows first_row + r j + (0..r-1) of g for the j-th node."""
        size = int(fn.size1_out(0))
        for mirrored in (False, True):
            chosen = [(j, n) for j, n in enumerate(nodes)
                      if self.layout.mirrored(n == self.N - 1) == mirrored]
            if chosen:
                self.elements.append(ElementGroup(
                    self.layout.node_element(fn, mirrored),
                    np.stack([self.layout.u_index(n) for _, n in chosen], 1),
                    np.stack([self.layout.node_p_index(n) for _, n in chosen], 1),
                    np.stack([first_row + size * j + np.arange(size) for j, _ in chosen], 1), c))
        return fn.map(len(nodes))(self.Q[:, nodes], ca.repmat(ca.DM(c), 1, len(nodes)))

    def _phase_name(self, k: int) -> str:
        return self.mb.scene.gait.phases[k].name

    # ---- NLP assembly -----------------------------------------------------------------

    @property
    def x(self):
        return ca.vertcat(ca.vec(self.U), ca.vec(self.T), self.L, self.S)

    @property
    def p(self):
        return ca.vertcat(ca.vec(self.Qref), self.step, self.mu, self.ground_p,
                          self.inverse_speed, self.start_momentum, self.end_scaling,
                          self.end_torque)

    def duration(self, x: np.ndarray) -> float:
        """The half cycle's duration (s) at the NLP's x (nx,), as `speed_row` counts it
        (the first N-1 intervals, each base_time_step times its phase's sigma)."""
        sigma = np.asarray(x, dtype=float)[-int(self.S.shape[0]):]
        scaling = self.layout.scaling_of_interval[: self.N - 1]
        return float(self.settings.base_time_step * np.sum(sigma[scaling]))

    def parameters(self, qref: np.ndarray, settings: GaitSettings) -> np.ndarray:
        """The numeric p of a request (`settings`, of this problem's `shape_of`) with the
        references qref (N-1, k): step length, friction coefficient, its ground's
        parameters (`Ground.parameters`) and 1 / speed (0 with free durations); a
        transition's qref (N+1, k), then its start momentum and last interval's scaling."""
        ground = ground_of(self.mb.scene, settings)
        if ground.form != self.gs.form:
            raise ValueError(f"a request on {ground.form} cannot use a problem built for "
                             f"{self.gs.form}")
        inverse = 1.0 / settings.speed if settings.speed > 0 else 0.0
        ends = [settings.start_momentum, [settings.end_scaling], settings.end_torque] \
            if self.transition else []
        return np.concatenate([np.asarray(qref, dtype=float).reshape(-1),
                               [settings.step_length, settings.friction_coefficient],
                               ground.parameters, [inverse], *ends])

    @property
    def g_without_elements(self):
        """g with the element rows' element parts left out (g minus the `elements`)."""
        return ca.vertcat(*[self._without_elements.get(n, e) for n, e in self._eq + self._ineq])

    def constraint_groups(self):
        """[(name, size, is_equality)] in the order of g."""
        return [(n, int(e.shape[0]), True) for n, e in self._eq] + \
               [(n, int(e.shape[0]), False) for n, e in self._ineq]

    @property
    def g(self):
        return ca.vertcat(*[e for _, e in self._eq], *[e for _, e in self._ineq])

    def bounds(self):
        """(lbx, ubx, lbg, ubg) as numpy arrays."""
        n_eq = sum(int(e.shape[0]) for _, e in self._eq)
        n_in = sum(int(e.shape[0]) for _, e in self._ineq)
        nx = int(self.x.shape[0])
        lbx, ubx = np.full(nx, -np.inf), np.full(nx, np.inf)
        free = self.layout.free
        rotations = np.tile(self.mb.rotation_mask, free)  # U is stored column by column
        lbx[: rotations.size][rotations] = -ROTATION_INCREMENT_MAX
        ubx[: rotations.size][rotations] = ROTATION_INCREMENT_MAX
        nsig = int(self.S.shape[0])
        lbx[-nsig:], ubx[-nsig:] = self.settings.scaling_bounds
        if self.transition:  # the given ends: q_n = qref_n (at rest: the start only)
            for n in (0,) if self.layout.rest else (0, self.N - 1, self.N):
                lbx[self.layout.u_index(n)] = ubx[self.layout.u_index(n)] = 0.0
        start = self.mb.ndof * free  # T follows U, column by column
        columns = int(self.T.shape[1])
        for name, limit in self.settings.effort_limits:  # |tau| <= the joint's effort limit
            rows = start + self.mb.joint_slices[name].start + self.mb.nt * np.arange(columns)
            lbx[rows], ubx[rows] = -limit / TORQUE_SCALE, limit / TORQUE_SCALE  # T = tau / scale
        lbg = np.concatenate([np.zeros(n_eq), np.zeros(n_in)])
        ubg = np.concatenate([np.zeros(n_eq)] + [
            np.full(int(e.shape[0]), self._upper.get(name, np.inf)) for name, e in self._ineq])
        return lbx, ubx, lbg, ubg

    def relaxed_lower_bounds(self, lbg: np.ndarray) -> np.ndarray:
        """lbg of a first, relaxed stage: swing points only above the ground (not by
        swing_clearance), joint speeds free, a requested speed only a lower bound on the
        half cycle's duration (sigma is fixed then; `speed_row`). From a kinematic guess
        IPOPT finds the gait of the relaxed problem in about 100 iterations and the full
        one from there; with every limit from the start its inertia-free attempt stalled
        (walker3d: 851 iterations through the fallback; benchmarks/HISTORY.md). With a
        speed, sigma starting at the speed's value instead of the upper bound changed
        nothing measurable (walker3d 1.4 m/s: 146 iterations instead of 177, walker2d 65
        instead of 51, the same optimum; 2026-11-27)."""
        return relaxed_lower_bounds(self.constraint_groups(), lbg, self.clearances)


def shape_of(settings: GaitSettings) -> GaitSettings:
    """The settings that shape a Transcription: `settings` with the values that enter it as
    parameters (step length, friction coefficient, slope, step height and the stairs'
    shift, speed) replaced by
    representatives of their form (level or stairs up or down; free or requested speed),
    so that two requests of one shape share one problem (`Transcription.parameters`)."""
    height = math.copysign(1.0, settings.step_height) if settings.step_height else 0.0
    return dataclasses.replace(settings, step_length=1.0, friction_coefficient=1.0, slope=0.0,
                               step_height=height, speed=1.0 if settings.speed > 0 else 0.0,
                               start_momentum=(0.0,) * len(settings.start_momentum),
                               end_scaling=1.0 if settings.start_momentum else 0.0,
                               end_torque=(0.0,) * len(settings.end_torque),
                               stairs_shift=0.0)


def speed_row(step, duration, inverse_speed):
    """The row of a requested mean forward speed (m/s) of the half cycle (both
    transcriptions): 1/speed - duration/step (s/m), 0 when step / duration = speed, with
    inverse_speed = 1/speed (a parameter, or a number). Linear in sigma; the constant
    1/speed drops out of its derivatives. Below 0 when the half
    cycle is shorter than step/speed, above when longer: with only its upper bound (the
    first stage, `relaxed_lower_bounds`) it asks for a half cycle at least that long, which
    sigma fixed at its upper bound gives within `settings.speed_range`."""
    return inverse_speed - duration / step


def relaxed_lower_bounds(groups, lbg: np.ndarray, clearances: list[float]) -> np.ndarray:
    """lbg with the group [(name, size, is_equality)] "ground_clearance" (rows z - height)
    lowered by each row's required height `clearances` (points only above the ground) and
    "joint_speed", "strike_speed", "strike_approach" and "speed" free below (`speed_row`)."""
    out, offset = lbg.copy(), 0
    for name, size, _ in groups:
        if name == "ground_clearance":
            out[offset : offset + size] = -np.asarray(clearances)
        elif name in ("joint_speed", "strike_speed", "strike_approach", "speed"):
            out[offset : offset + size] = -np.inf
        offset += size
    return out
