"""Hermite-Simpson direct collocation of the half-cycle gait in minimal coordinates.

The same optimal control problem as `gait_planner.ocp.transcription` (phases, free
durations, plastic contacts, Coulomb cones, mirror periodicity, posture constraints, cost
and regularisers), transcribed the way bioptim, OpenSim Moco or Drake users would:

* State x = (theta, w) (`minimal.MinimalModel`), controls tau (joint torques as the
  product's), knots 0..K of `mesh.Mesh`, and per interval i a midpoint (theta_m, w_m):
  separated Hermite-Simpson (Betts, Practical Methods for Optimal Control, 2nd ed. 2010,
  section 4.6.5), torques linear in time (tau_m = (tau_i + tau_{i+1})/2, the product's
  node torques are linear too):
      theta_m = (theta_i + theta_{i+1})/2 + h (w_i - w_{i+1})/8
      w_m     = (w_i + w_{i+1})/2 + h (a_i - a_{i+1})/8
      theta_{i+1} = theta_i + h (w_i + 4 w_m + w_{i+1})/6 + h (C J(theta_m))^T gamma_i
      w_{i+1} = w_i + h (a_i + 4 a_m + a_{i+1})/6
* Dynamics in implicit form: the accelerations a at every knot and midpoint are
  unknowns and the residual `MinimalModel.dynamics` (with the contact forces C^T lambda)
  is a constraint there. Forming a = M(theta)^-1 rhs symbolically would put a dense 20 x 20
  solve into every collocation point's expression graph (and its Hessian); the implicit
  form is OpenSim Moco's default for multibody dynamics, for the same reason.
* Held contacts (Posa, Kuindersma & Tedrake, "Optimization and stabilization of
  trajectories for constrained dynamical systems", ICRA 2016): position C q(theta) held
  over every interval (the product's chain rows), velocity C J w = 0 and acceleration
  C qdd = 0 at every knot of the phase, contact forces lambda at knots and midpoints, and
  the velocity correction gamma_i (r rows per interval) that lets the HS quadrature meet
  the position rows exactly: per interval 3r new rows for 3r new unknowns.
* Phase boundaries: theta and tau continuous; where a phase holds a point the previous
  one did not, the knot has a pre-impact velocity w_minus and a plastic impact
  (`MinimalModel.impact`, every contact of the new phase takes an impulse Lambda, in its
  friction cone, and has zero velocity after it); elsewhere w is continuous. The
  touching-down points sit on the ground (`establishing_rows`).
* Path constraints: the product's at the knots 1..K (swing clearance by
  `ocp.clearance`, torso, joint ranges, joint speeds over the intervals: mean speeds, so
  the collocation's own knot velocities may exceed them; walker2d's ankle turned at
  625 deg/s just after its heel strike). Box bounds on the joint rates made it fragile:
  on every knot and midpoint walker2d did not converge (212 iterations in 120 s), on the
  impact knots alone it converged or not depending on the swing clearance ramp.
* A requested speed (settings.speed > 0): the product's row on the half cycle's duration
  (`ocp.transcription.speed_row`).
* Periodicity: theta_K, w_K (after the impact, if any, at the end) and tau_K are the
  mirror images of theta_0, w_0, tau_0 (expressions, not unknowns: no redundant rows).

Scaling as the product: torques in TORQUE_SCALE, forces in FORCE_SCALE (impulses in
FORCE_SCALE * base_time_step), accelerations in ACCELERATION_SCALE; the dynamics rows are
divided by FORCE_SCALE (N -> 1e-3 units, as the product's).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from gait_planner.collocation.mesh import Mesh
from gait_planner.collocation.minimal import MinimalModel
from gait_planner.ocp.clearance import (clearance_rows, clearance_schedule, strike_rows,
                                        strike_schedule)
from gait_planner.ocp.contacts import body_contacts, establishing_rows, stacked_rows
from gait_planner.ocp.mirror import torque_mirror
from gait_planner.ocp.posture import (joint_limit_margins, joint_margin_constants,
                                      joint_speed_margins, twist_squares)
from gait_planner.ocp.settings import GaitSettings, SettingsError, ground_of
from gait_planner.ocp.transcription import (FORCE_SCALE, TORQUE_SCALE, relaxed_lower_bounds,
                                           speed_row)

ACCELERATION_SCALE = 10.0  # rad/s^2


class _Variables:
    """Blocks of unknowns: MX symbols with bounds, stacked (column by column) into x."""

    def __init__(self):
        self.blocks: list[tuple[str, ca.MX, np.ndarray, np.ndarray]] = []

    def add(self, name: str, rows: int, cols: int = 1, bound=np.inf) -> ca.MX:
        sym = ca.MX.sym(name, rows, cols)
        ub = np.broadcast_to(np.asarray(bound, float).reshape(-1, 1), (rows, cols))
        self.blocks.append((name, sym, -ub.T.ravel(), ub.T.ravel()))
        return sym

    def index(self, name: str) -> slice:
        start = 0
        for block, sym, _, _ in self.blocks:
            if block == name:
                return slice(start, start + sym.numel())
            start += sym.numel()
        raise KeyError(name)


class CollocationTranscription:
    """The NLP of one (scene, settings, mesh): x, p = (step length, mu), f, g, bounds."""

    def __init__(self, model: MinimalModel, settings: GaitSettings, mesh: Mesh):
        self.model, self.mb, self.settings, self.mesh = model, model.mb, settings, mesh
        mb, s, scene, n = model.mb, settings, model.scene, model.n
        if not ground_of(scene, s).level:
            raise SettingsError(
                f"the collocation baseline plans on level ground only; slope {s.slope:g} deg "
                f"and step_height {s.step_height:g} m need the DMOCC planner")
        self.step, self.mu = ca.MX.sym("step_length"), ca.MX.sym("mu")
        V = self.variables = _Variables()
        self.sigma = V.add("sigma", scene.gait.n_scalings)
        K = self.K = mesh.K
        self.B = torque_mirror(mb)
        phases = [scene.gait.phases[k] for k in mesh.phases]
        self.contacts = [body_contacts(mb, p.contacts) for p in phases]
        self.contacts_after_end = body_contacts(mb, scene.gait.phases[-1].contacts)
        TH = V.add("theta", n, K, model.chart_limits)
        W = V.add("w", n, K)
        TAU = TORQUE_SCALE * V.add("tau", mb.nt, K)
        self.theta = [TH[:, j] for j in range(K)] + [model.mirror(TH[:, 0], self.step)]
        self.w = [W[:, j] for j in range(K)] + [model.mirror_velocity(TH[:, 0], W[:, 0])]
        self.tau = [TAU[:, j] for j in range(K)] + [ca.mtimes(ca.DM(self.B), TAU[:, 0])]
        self.q = [model.configuration(t) for t in self.theta]
        self.h = []
        for c, k in enumerate(mesh.phases):
            length = s.base_time_step * mesh.base_steps[c] / mesh.intervals[c]
            self.h += [length * self.sigma[scene.gait.phases[k].scaling]] * mesh.intervals[c]

        self._eq, self._ineq = [], []  # (name, expression)
        self.w_minus, self.impulses = {}, {}  # knot -> pre-impact w, impulse multipliers
        self.knot_forces = {}  # (phase, local knot) -> multipliers (N)
        self.knot_accelerations = {}  # (phase, local knot) -> a (rad/s^2)
        self._cost_terms = {"kinetic_energy": 0, "torque_squared": 0, "shares": 0, "twist": 0}
        self._boundaries()
        for c in range(len(phases)):
            self._phase(c)
        self._path()
        self.cost_parts = self._cost_terms
        main = self._cost_terms[s.cost]
        if s.cost == "kinetic_energy":
            main = main + s.torque_regularisation * self._cost_terms["torque_squared"]
        self.cost = main + s.torque_regularisation * self._cost_terms["shares"] \
            + self._cost_terms["twist"]

    # ---- helpers -----------------------------------------------------------------------

    def _w_before(self, j: int):
        return self.w_minus.get(j, self.w[j])

    def _force(self, contacts, lam):
        """The director force C^T lambda_rows (k,) of multipliers lam (the along-line shares
        of full contacts move nothing, `ocp.contacts`)."""
        parts, offset = [], 0
        for bc in contacts:
            parts.append(ca.mtimes(ca.DM(bc.rows).T, lam[offset : offset + bc.n_rows]))
            offset += bc.n_multipliers
        return sum(parts) if parts else ca.DM.zeros(self.mb.k)

    def _cones(self, contacts, lam, q, smoothing: float):
        """The product's friction cones and roll bounds (`BodyContact.cone_rows`) of every
        contact of a collocation point (or impact) with multipliers lam."""
        out, offset = [], 0
        for bc in contacts:
            out += bc.cone_rows(lam[offset : offset + bc.n_multipliers], q, self.mu, smoothing,
                                self.settings.foot_half_width)
            offset += bc.n_multipliers
        return out

    @staticmethod
    def _shares(contacts, lam) -> list:
        """The along-line shares s (N) of the full contacts among lam."""
        out, offset = [], 0
        for bc in contacts:
            offset += bc.n_multipliers
            if bc.full:
                out.append(lam[offset - 1])
        return out

    # ---- phase boundaries ------------------------------------------------------------

    def _boundaries(self):
        """Impacts and touch-down rows at the knots where new contact points are held."""
        mb, s, V = self.mb, self.settings, self.variables
        switches = [(start, self.contacts[c - 1], self.contacts[c])
                    for c, start in enumerate(self.mesh.starts) if c > 0]
        switches.append((self.K, self.contacts[-1], self.contacts_after_end))
        touch = []
        for j, before, after in switches:
            held = {p for bc in before for p in bc.points}
            E, _ = establishing_rows(mb, before, after)
            if E.shape[0]:
                touch.append(ca.mtimes(ca.DM(E), self.q[j]))
            if all(p in held for bc in after for p in bc.points):
                continue
            size = sum(bc.n_multipliers for bc in after)
            lam = FORCE_SCALE * s.base_time_step * V.add(f"impulse{j}", size)
            self.w_minus[j] = V.add(f"w_minus{j}", self.model.n)
            self.impulses[j] = (after, lam)
            jump = self.model.impact(self.theta[j], self.w_minus[j], self.w[j],
                                     self._force(after, lam))
            self._eq.append((f"impact[{j}]", jump / (FORCE_SCALE * s.base_time_step)))
            C = stacked_rows(after, mb.k)
            self._eq.append((f"impact_velocity[{j}]",
                             ca.mtimes(ca.DM(C), self.model.velocity(self.theta[j], self.w[j]))))
            self._ineq.append((f"impulse_cone[{j}]", ca.vertcat(*self._cones(
                after, lam / s.base_time_step, self.q[j], s.friction_smoothing))))
            self._cost_terms["shares"] += sum(x**2 for x in self._shares(after, lam)) \
                / s.base_time_step
        if touch:
            self._eq.append(("contact_establish", ca.vertcat(*touch)))
        first = self.contacts[0][0].points[0]
        self._eq.append(("pin_x", ca.mtimes(ca.DM(mb.contact_rows(first)[0:1]), self.q[0])))
        if s.speed > 0:  # the product's row (`speed_row`): knots 0..K span the half cycle
            self._eq.append(("speed", speed_row(self.step, ca.sum1(ca.vertcat(*self.h)),
                                                s.speed)))

    # ---- one phase ---------------------------------------------------------------------

    def _phase(self, c: int):
        model, mb, s, V = self.model, self.mb, self.settings, self.variables
        n, name = model.n, self.mb.scene.gait.phases[self.mesh.phases[c]].name
        contacts, start, m = self.contacts[c], self.mesh.starts[c], self.mesh.intervals[c]
        C = ca.DM(stacked_rows(contacts, mb.k))
        nr, nl = C.shape[0], sum(bc.n_multipliers for bc in contacts)
        A = ACCELERATION_SCALE * V.add(f"a[{name}]", n, m + 1)
        L = FORCE_SCALE * V.add(f"lambda[{name}]", nl, m + 1)
        AM = ACCELERATION_SCALE * V.add(f"a_mid[{name}]", n, m)
        LM = FORCE_SCALE * V.add(f"lambda_mid[{name}]", nl, m)
        TM = V.add(f"theta_mid[{name}]", n, m, model.chart_limits)
        WM = V.add(f"w_mid[{name}]", n, m)
        GAM = V.add(f"gamma[{name}]", nr, m)
        dyn, hold, vel, acc, cones, defects = [], [], [], [], [], []

        def point(theta, w, a, tau, lam, q, knot: int | None):
            """Rows of one collocation point (knot: local knot index; None: a midpoint);
            returns its along-line shares."""
            dyn.append(model.dynamics(theta, w, a, tau, self._force(contacts, lam)) / FORCE_SCALE)
            cones.extend(self._cones(contacts, lam, q, s.friction_smoothing))
            if knot is not None and nr:
                acc.append(ca.mtimes(C, model.acceleration(theta, w, a)) / ACCELERATION_SCALE)
                if knot > 0:  # knot 0: at rest since the previous phase, or after an impact
                    vel.append(ca.mtimes(C, model.velocity(theta, w)))
            return self._shares(contacts, lam)

        knot_shares = []
        for local in range(m + 1):
            j = start + local
            w = self._w_before(j) if local == m else self.w[j]
            knot_shares.append(point(self.theta[j], w, A[:, local], self.tau[j], L[:, local],
                                     self.q[j], local))
            self.knot_forces[(c, local)] = L[:, local]
            self.knot_accelerations[(c, local)] = A[:, local]
        kinetic = torque = twist = share = 0
        twist_fn, twist_c = twist_squares(mb), ca.DM([s.base_time_step, 1.0])
        for local in range(m):
            i = start + local
            h = self.h[i]
            th0, th1, w0, w1 = self.theta[i], self.theta[i + 1], self.w[i], self._w_before(i + 1)
            a0, a1, tm, wm, am = A[:, local], A[:, local + 1], TM[:, local], WM[:, local], AM[:, local]
            tau_m = 0.5 * (self.tau[i] + self.tau[i + 1])
            qm = model.configuration(tm)
            mid_shares = point(tm, wm, am, tau_m, LM[:, local], qm, None)
            correction = model.project(tm, ca.mtimes(C.T, GAM[:, local])) if nr else 0
            defects += [tm - 0.5 * (th0 + th1) - h / 8 * (w0 - w1),
                        wm - 0.5 * (w0 + w1) - h / 8 * (a0 - a1),
                        th1 - th0 - h / 6 * (w0 + 4 * wm + w1) - h * correction,
                        w1 - w0 - h / 6 * (a0 + 4 * am + a1)]
            if nr:
                hold.append(ca.mtimes(C, self.q[i + 1] - self.q[i]))

            def simpson(f0, fm, f1):
                return h / 6 * (f0 + 4 * fm + f1)

            kinetic += simpson(model.kinetic_energy(th0, w0), model.kinetic_energy(tm, wm),
                               model.kinetic_energy(th1, w1))
            torque += simpson(ca.sumsqr(self.tau[i]), ca.sumsqr(tau_m), ca.sumsqr(self.tau[i + 1]))
            if s.twist_regularisation > 0:
                twist += s.twist_regularisation * simpson(
                    *(twist_fn(q, q, 1.0, twist_c) for q in (self.q[i], qm, self.q[i + 1])))
            share += simpson(*(sum(x**2 for x in v) for v in
                               (knot_shares[local], mid_shares, knot_shares[local + 1])))
        for key, value in (("kinetic_energy", kinetic), ("torque_squared", torque),
                           ("twist", twist), ("shares", share)):
            self._cost_terms[key] += value
        self._eq += [(f"collocation[{name}]", ca.vertcat(*defects)),
                     (f"dynamics[{name}]", ca.vertcat(*dyn))]
        if nr:
            self._eq += [(f"contact_hold[{name}]", ca.vertcat(*hold)),
                         (f"contact_velocity[{name}]", ca.vertcat(*vel)),
                         (f"contact_acceleration[{name}]", ca.vertcat(*acc))]
        if cones:
            self._ineq.append((f"friction_cone[{name}]", ca.vertcat(*cones)))

    # ---- path constraints (the product's, at the knots 1..K = its nodes 1..N-1) ------

    def _path(self):
        """The product's path constraints at the knots 1..K (knot K, the image of knot 0,
        is its node N-1; the phase of interval K is the last scene phase), joint speeds
        over the intervals 0..K-1."""
        mb, s, K, scene = self.mb, self.settings, self.K, self.mb.scene
        phase_names = [scene.gait.phases[self.mesh.phases[c]].name
                       for c in self.mesh.phase_of_interval] + [scene.gait.phases[-1].name]
        held = [{p for bc in self.contacts[c] for p in bc.points}
                for c in self.mesh.phase_of_interval]  # interval K: the image of 0
        spacing = s.base_time_step * sum(self.mesh.base_steps) / K  # s at sigma = 1
        ground, self.clearances = clearance_rows(
            mb, lambda j: self.q[j], clearance_schedule(scene, held, s, spacing),
            s.foot_half_width)
        if ground:
            self._ineq.append(("ground_clearance", ca.vertcat(*ground)))
        strikes = strike_schedule(scene, held) if s.strike_speed_max > 0 else {}
        if strikes:
            c = ca.DM([spacing, s.strike_speed_max])
            self._ineq.append(("strike_speed", ca.vertcat(
                *[strike_rows(mb, points)(self.q[j], self.q[j + 1], self.h[j], c)
                  for j, points in strikes.items()])))
        root = mb.block(scene.root.body).start
        inner = self.q[1 : K + 1]
        if s.torso_lean_max > 0:
            lean = math.cos(math.radians(s.torso_lean_max))
            self._ineq.append(("torso_lean", ca.vertcat(*[q[root + 11] - lean for q in inner])))
        if s.torso_height_min > 0:
            self._ineq.append(("torso_height",
                               ca.vertcat(*[q[root + 2] - s.torso_height_min for q in inner])))
        if s.joint_limits:
            fn, c = self._limits(s.joint_limits)
            self._ineq.append(("joint_limits", ca.vertcat(*[fn(q, c) for q in inner])))
        for phase, limits in s.phase_joint_limits:
            fn, c = self._limits(limits)
            rows = [fn(self.q[j], c) for j in range(1, K + 1) if phase_names[j] == phase]
            if rows:
                self._ineq.append((f"joint_limits[{phase}]", ca.vertcat(*rows)))
        if s.joint_speed_max > 0 and scene.joints:
            fn, c = joint_speed_margins(mb), ca.DM([s.base_time_step,
                                                   math.radians(s.joint_speed_max)])
            self._ineq.append(("joint_speed", ca.vertcat(
                *[fn(self.q[j], self.q[j + 1], self.h[j], c) for j in range(K)])))

    def _limits(self, limits):
        """The joint-range margins (`ocp.posture.joint_limit_margins`, two one-sided rows per
        angle) and their constants. Not the product's one row per angle with two bounds
        (`ocp.posture.joint_limit_rows`): with those this baseline's walker3d plans missed
        work_precision.py's 150 s limit on all four grids, and with the ranges as bounds on
        the knots' angles on 4 intervals per phase (the one grid measured), where the
        margins converge on 4, 6 and 8 (benchmarks/HISTORY.md, 2026-11-26)."""
        return (joint_limit_margins(self.mb, tuple(a for a, _, _ in limits)),
                ca.DM(joint_margin_constants(self.mb, limits)))

    # ---- NLP assembly ----------------------------------------------------------------

    @property
    def x(self):
        return ca.vertcat(*[ca.vec(sym) for _, sym, _, _ in self.variables.blocks])

    @property
    def p(self):
        return ca.vertcat(self.step, self.mu)

    @property
    def g(self):
        return ca.vertcat(*[e for _, e in self._eq], *[e for _, e in self._ineq])

    def constraint_groups(self):
        """[(name, size, is_equality)] in the order of g."""
        return [(n, int(e.shape[0]), True) for n, e in self._eq] + \
               [(n, int(e.shape[0]), False) for n, e in self._ineq]

    def bounds(self):
        """(lbx, ubx, lbg, ubg): sigma within the scaling bounds, the chart's angles within
        `MinimalModel.chart_limits`; equalities 0, inequalities >= 0."""
        blocks = self.variables.blocks
        lbx, ubx = np.concatenate([b[2] for b in blocks]), np.concatenate([b[3] for b in blocks])
        sig = self.variables.index("sigma")
        lbx[sig], ubx[sig] = self.settings.scaling_bounds
        groups = self.constraint_groups()
        lbg = np.zeros(sum(size for _, size, _ in groups))
        ubg = np.concatenate([np.zeros(size) if eq else np.full(size, np.inf)
                              for _, size, eq in groups])
        return lbx, ubx, lbg, ubg

    def relaxed_lower_bounds(self, lbg: np.ndarray) -> np.ndarray:
        """lbg of the first stage, as the product's (`Transcription.relaxed_lower_bounds`):
        swing points only above the ground, joint speeds free, a requested speed only a
        lower bound on the half cycle's duration."""
        return relaxed_lower_bounds(self.constraint_groups(), lbg, self.clearances)
