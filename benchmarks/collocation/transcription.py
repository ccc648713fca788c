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

g and the cost are built as one MX graph (what IPOPT evaluates); every row and cost term
that is one formula of one collocation point, knot or interval is also declared as an
element (`collocation.elements`: `elements`, `layout`, `g_without_elements`,
`cost_without_elements`), from which `ocp.derivatives.nlp_derivatives` forms the
derivatives point by point. Left to CasADi: the touch-down rows, the pinned start, the
speed row, the required heights of the swing clearance, the torque and share terms.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from benchmarks.collocation.elements import (ElementSet, ImageLayout, acceleration_element,
                                               cone_rows, contact_element, contact_force,
                                               cost_element, dynamics_element, heights_element,
                                               impact_element, interval_element, knot_element,
                                               knot_pair_element, mirror_map, signed_permutation,
                                               velocity_element)
from benchmarks.collocation.mesh import Mesh
from benchmarks.collocation.minimal import MinimalModel
from gait_planner.ocp.clearance import (clearance_rows, clearance_schedule, ground_heights,
                                        schedule_heights, strike_rows, strike_schedule)
from gait_planner.ocp.contacts import body_contacts, establishing_rows, stacked_rows
from gait_planner.ocp.mirror import torque_mirror
from gait_planner.ocp.posture import (joint_limit_margins, joint_margin_constants,
                                      joint_speed_margins, twist_squares)
from gait_planner.ocp.settings import GaitSettings, SettingsError, ground_of
from gait_planner.ocp.transcription import (FORCE_SCALE, TORQUE_SCALE, relaxed_lower_bounds,
                                           speed_row)

ACCELERATION_SCALE = 10.0  # rad/s^2


class _Variables:
    """Blocks of unknowns: MX symbols with bounds, stacked (column by column) into x;
    at[name] (rows, cols) the indices of a block's entries in x."""

    def __init__(self):
        self.blocks: list[tuple[str, ca.MX, np.ndarray, np.ndarray]] = []
        self.at: dict[str, np.ndarray] = {}
        self.size = 0

    def add(self, name: str, rows: int, cols: int = 1, bound=np.inf) -> ca.MX:
        sym = ca.MX.sym(name, rows, cols)
        ub = np.broadcast_to(np.asarray(bound, float).reshape(-1, 1), (rows, cols))
        self.blocks.append((name, sym, -ub.T.ravel(), ub.T.ravel()))
        self.at[name] = self.size + np.arange(rows * cols).reshape(cols, rows).T
        self.size += rows * cols
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
        self._declare_images()
        self.theta = [TH[:, j] for j in range(K)] + [model.mirror(TH[:, 0], self.step)]
        self.w = [W[:, j] for j in range(K)] + [model.mirror_velocity(TH[:, 0], W[:, 0])]
        self.tau = [TAU[:, j] for j in range(K)] + [ca.mtimes(ca.DM(self.B), TAU[:, 0])]
        self.q = [model.configuration(t) for t in self.theta]
        self.h = []
        self._length, self._sigma_at = [], []  # of each interval: h = length * x[sigma_at]
        for c, k in enumerate(mesh.phases):
            length = s.base_time_step * mesh.base_steps[c] / mesh.intervals[c]
            self.h += [length * self.sigma[scene.gait.phases[k].scaling]] * mesh.intervals[c]
            self._length += [length] * mesh.intervals[c]
            self._sigma_at += [V.at["sigma"][scene.gait.phases[k].scaling, 0]] * mesh.intervals[c]

        self._eq, self._ineq = [], []  # (name, expression)
        self._without_elements = {}  # name -> the group's expression without its elements
        self._element_set, self._element_fns = ElementSet(), {}
        self.w_minus, self.impulses = {}, {}  # knot -> pre-impact w, impulse multipliers
        self._w_minus_at = {}  # knot -> indices of w_minus in x
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
        # the cost's parts that are not elements (`_interval_elements`)
        self.cost_without_elements = s.torque_regularisation * (
            self._cost_terms["torque_squared"] if s.cost == "kinetic_energy" else 0) \
            + (0 if s.cost == "kinetic_energy" else main) \
            + s.torque_regularisation * self._cost_terms["shares"]
        offsets = dict(zip([name for name, _, _ in self.constraint_groups()],
                           np.cumsum([0] + [size for _, size, _ in self.constraint_groups()])))
        self.elements = [] if self.layout is None else \
            self._element_set.groups(self.variables.size, offsets)

    # ---- helpers -----------------------------------------------------------------------

    def _declare_images(self):
        """Indices of every knot's theta, w and tau among (x, images) (`collocation.elements`):
        knot K's are the images of knot 0's, encoded -1 - i (the i-th image) until x is
        complete; the layout of these images, None if the mirror is not a signed permutation
        (plus the step) of theta."""
        n, nt, K, at = self.model.n, self.mb.nt, self.K, self.variables.at
        image = -1 - np.arange(2 * n + nt)
        self._theta_at = [at["theta"][:, j] for j in range(K)] + [image[:n]]
        self._w_at = [at["w"][:, j] for j in range(K)] + [image[n : 2 * n]]
        self._tau_at = [at["tau"][:, j] for j in range(K)] + [image[2 * n :]]
        mirror, torque = mirror_map(self.model), signed_permutation(self.B)
        self.layout = None
        if mirror is not None and torque is not None:
            (source, sign, shift), (t_source, t_sign) = mirror, torque
            self.layout = ImageLayout(
                np.concatenate([at["theta"][source, 0], at["w"][source, 0],
                                at["tau"][t_source, 0]]),
                np.concatenate([sign, sign, t_sign]), np.concatenate([shift, np.zeros(n + nt)]))

    def _w_before_at(self, j: int) -> np.ndarray:
        return self._w_minus_at.get(j, self._w_at[j])

    def _element_fn(self, kind: str, make, *key) -> ca.Function:
        """The element Function `kind` of key (built by make() once)."""
        if (kind, *key) not in self._element_fns:
            self._element_fns[(kind, *key)] = make()
        return self._element_fns[(kind, *key)]

    def _contact_fns(self, contacts):
        """(contact, velocity, acceleration) element Functions of a contact set; the
        velocity and acceleration ones None without contact rows."""
        points = tuple(p for bc in contacts for p in bc.points)
        name = "_".join(points)
        C = stacked_rows(contacts, self.mb.k)
        contact = self._element_fn("contact", lambda: contact_element(
            self.model, contacts, name, FORCE_SCALE), points)
        if not C.shape[0]:
            return contact, None, None
        return (contact,
                self._element_fn("velocity", lambda: velocity_element(self.model, C, name), points),
                self._element_fn("acceleration", lambda: acceleration_element(
                    self.model, C, name, ACCELERATION_SCALE), points))

    def _no_elements_left(self, name: str, size: int):
        """The group `name` is all elements (`_without_elements`)."""
        self._without_elements[name] = ca.MX(size, 1)

    def _w_before(self, j: int):
        return self.w_minus.get(j, self.w[j])

    def _force(self, contacts, lam):
        return contact_force(contacts, lam, self.mb.k)

    def _cones(self, contacts, lam, q, smoothing: float):
        return cone_rows(contacts, lam, q, self.mu, smoothing, self.settings.foot_half_width)

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
            self._w_minus_at[j] = V.at[f"w_minus{j}"][:, 0]
            self.impulses[j] = (after, lam)
            jump = self.model.impact(self.theta[j], self.w_minus[j], self.w[j],
                                     self._force(after, lam))
            self._eq.append((f"impact[{j}]", jump / (FORCE_SCALE * s.base_time_step)))
            C = stacked_rows(after, mb.k)
            self._eq.append((f"impact_velocity[{j}]",
                             ca.mtimes(ca.DM(C), self.model.velocity(self.theta[j], self.w[j]))))
            self._ineq.append((f"impulse_cone[{j}]", ca.vertcat(*self._cones(
                after, lam / s.base_time_step, self.q[j], s.friction_smoothing))))
            self._impact_elements(j, after, V.at[f"impulse{j}"][:, 0])
            self._cost_terms["shares"] += sum(x**2 for x in self._shares(after, lam)) \
                / s.base_time_step
        if touch:
            self._eq.append(("contact_establish", ca.vertcat(*touch)))
        first = self.contacts[0][0].points[0]
        self._eq.append(("pin_x", ca.mtimes(ca.DM(mb.contact_rows(first)[0:1]), self.q[0])))
        if s.speed > 0:  # the product's row (`speed_row`): knots 0..K span the half cycle
            self._eq.append(("speed", speed_row(self.step, ca.sum1(ca.vertcat(*self.h)),
                                                1.0 / s.speed)))

    def _impact_elements(self, j: int, after, impulse_at: np.ndarray):
        """The impact rows at knot j as elements: `impact_element` and the impulse's
        `contact_element` (with its cones), the velocity rows after it."""
        n, s = self.model.n, self.settings
        th = self._theta_at[j]
        impact = self._element_fn("impact", lambda: impact_element(self.model))
        contact, velocity, _ = self._contact_fns(after)
        self._element_set.add(impact, [FORCE_SCALE * s.base_time_step],
                              np.concatenate([th, self._w_minus_at[j], self._w_at[j]]),
                              [(f"impact[{j}]", np.arange(n))])
        cones = contact.size1_out(0) - n
        self._element_set.add(contact, [s.friction_smoothing, s.foot_half_width],
                              np.concatenate([th, impulse_at]),
                              [(f"impact[{j}]", np.arange(n)),
                               (f"impulse_cone[{j}]", np.arange(cones))])
        self._element_set.add(velocity, [], np.concatenate([th, self._w_at[j]]),
                              [(f"impact_velocity[{j}]", np.arange(velocity.size1_out(0)))])
        for name, size in ((f"impact[{j}]", n), (f"impact_velocity[{j}]", velocity.size1_out(0)),
                           (f"impulse_cone[{j}]", cones)):
            self._no_elements_left(name, size)

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
        for group, rows in ((f"collocation[{name}]", defects), (f"dynamics[{name}]", dyn),
                            (f"contact_hold[{name}]", hold), (f"contact_velocity[{name}]", vel),
                            (f"contact_acceleration[{name}]", acc),
                            (f"friction_cone[{name}]", cones)):
            self._no_elements_left(group, sum(int(r.shape[0]) for r in rows))
        self._point_elements(c, name)
        self._interval_elements(c, name)

    def _point_elements(self, c: int, name: str):
        """The rows of phase c's collocation points as elements, points in the order of
        their rows (knots 0..m, then midpoints 0..m-1): `dynamics_element`, the contact
        term and cones (`contact_element`), at the knots the contact velocity (not at the
        phase's first knot) and acceleration rows."""
        model, s, at, add = self.model, self.settings, self.variables.at, self._element_set.add
        n, start, m = model.n, self.mesh.starts[c], self.mesh.intervals[c]
        contacts = self.contacts[c]
        dynamics = self._element_fn("dynamics", lambda: dynamics_element(
            model, (ACCELERATION_SCALE, TORQUE_SCALE, FORCE_SCALE)))
        contact, velocity, acceleration = self._contact_fns(contacts) if contacts else (None,) * 3
        cones = contact.size1_out(0) - n if contact is not None else 0
        nr = acceleration.size1_out(0) if acceleration is not None else 0
        A, L = at[f"a[{name}]"], at[f"lambda[{name}]"]
        AM, LM, TM, WM = (at[f"{v}[{name}]"] for v in ("a_mid", "lambda_mid", "theta_mid", "w_mid"))

        def point(index: int, theta, w, a, tau0, tau1, weights, lam):
            rows = (f"dynamics[{name}]", index * n + np.arange(n))
            add(dynamics, weights, np.concatenate([theta, w, a, tau0, tau1]), [rows])
            if contact is not None:
                add(contact, [s.friction_smoothing, s.foot_half_width],
                    np.concatenate([theta, lam]),
                    [rows] + ([(f"friction_cone[{name}]", index * cones + np.arange(cones))]
                              if cones else []))

        for local in range(m + 1):
            j = start + local
            theta, w = self._theta_at[j], self._w_before_at(j) if local == m else self._w_at[j]
            point(local, theta, w, A[:, local], self._tau_at[j], self._tau_at[j], [1.0, 0.0],
                  L[:, local])
            if nr:
                add(acceleration, [], np.concatenate([theta, w, A[:, local]]),
                    [(f"contact_acceleration[{name}]", local * nr + np.arange(nr))])
                if local > 0:
                    add(velocity, [], np.concatenate([theta, w]),
                        [(f"contact_velocity[{name}]", (local - 1) * nr + np.arange(nr))])
        for local in range(m):
            i = start + local
            point(m + 1 + local, TM[:, local], WM[:, local], AM[:, local], self._tau_at[i],
                  self._tau_at[i + 1], [0.5, 0.5], LM[:, local])

    def _interval_elements(self, c: int, name: str):
        """Phase c's intervals as elements: the defects and held contacts
        (`interval_element`), the kinetic energy (for that cost) and twist terms of the cost
        (`cost_element`)."""
        model, s, at, add = self.model, self.settings, self.variables.at, self._element_set.add
        n, start, m = model.n, self.mesh.starts[c], self.mesh.intervals[c]
        C = stacked_rows(self.contacts[c], self.mb.k)
        nr = C.shape[0]
        points = tuple(p for bc in self.contacts[c] for p in bc.points)
        interval = self._element_fn("interval", lambda: interval_element(
            model, C, "_".join(points) or "flight", ACCELERATION_SCALE), points)
        kinetic, twist = s.cost == "kinetic_energy", s.twist_regularisation > 0
        cost = self._element_fn("cost", lambda: cost_element(
            model, kinetic, twist_squares(self.mb) if twist else None)) \
            if kinetic or twist else None
        A, TM, WM, AM, GAM = (at[f"{v}[{name}]"] for v in ("a", "theta_mid", "w_mid", "a_mid",
                                                            "gamma"))
        for local in range(m):
            i = start + local
            th0, th1 = self._theta_at[i], self._theta_at[i + 1]
            w0, w1, sig = self._w_at[i], self._w_before_at(i + 1), [self._sigma_at[i]]
            add(interval, [self._length[i]],
                np.concatenate([th0, th1, w0, w1, A[:, local], A[:, local + 1], TM[:, local],
                                WM[:, local], AM[:, local], GAM[:, local], sig]),
                [(f"collocation[{name}]", 4 * n * local + np.arange(4 * n))]
                + ([(f"contact_hold[{name}]", nr * local + np.arange(nr))] if nr else []))
            if cost is not None:
                add(cost, [self._length[i], s.twist_regularisation, s.base_time_step],
                    np.concatenate([th0, w0, TM[:, local], WM[:, local], th1, w1, sig]))

    # ---- path constraints (the product's, at the knots 1..K = its nodes 1..N-1) ------

    def _path(self):
        """The product's path constraints at the knots 1..K (knot K, the image of knot 0,
        is its node N-1; the phase of interval K is the last scene phase), joint speeds
        over the intervals 0..K-1; each row also an element (`_knot_rows`,
        `_interval_rows`)."""
        mb, s, K, scene = self.mb, self.settings, self.K, self.mb.scene
        phase_names = [scene.gait.phases[self.mesh.phases[c]].name
                       for c in self.mesh.phase_of_interval] + [scene.gait.phases[-1].name]
        held = [{p for bc in self.contacts[c] for p in bc.points}
                for c in self.mesh.phase_of_interval]  # interval K: the image of 0
        spacing = s.base_time_step * sum(self.mesh.base_steps) / K  # s at sigma = 1
        schedule = clearance_schedule(scene, held, s, spacing)
        ground, self.clearances = clearance_rows(mb, lambda j: self.q[j], schedule,
                                                 s.foot_half_width)
        if ground:
            self._ineq.append(("ground_clearance", ca.vertcat(*ground)))
            self._without_elements["ground_clearance"] = ca.MX(-ca.DM(self.clearances))
            row = 0
            for j, points in schedule.items():
                if points:
                    fn = ground_heights(mb, tuple(points), s.foot_half_width)
                    size = len(schedule_heights(mb, points, s.foot_half_width))
                    self._element_set.add(
                        self._element_fn("heights", lambda: heights_element(self.model, fn),
                                         tuple(points)),
                        [], self._theta_at[j], [("ground_clearance", row + np.arange(size))])
                    row += size
        strikes = strike_schedule(scene, held) if s.strike_speed_max > 0 else {}
        if strikes:
            c = ca.DM([spacing, s.strike_speed_max])
            self._ineq.append(("strike_speed", ca.vertcat(
                *[strike_rows(mb, points)(self.q[j], self.q[j + 1], self.h[j], c)
                  for j, points in strikes.items()])))
            row = 0
            for j, points in strikes.items():
                self._interval_rows("strike_speed", strike_rows(mb, points), tuple(points),
                                    [spacing, s.strike_speed_max], [j], row)
                row += len(points)
            self._no_elements_left("strike_speed", row)
        root = mb.block(scene.root.body).start
        inner = self.q[1 : K + 1]
        if s.torso_lean_max > 0:
            lean = math.cos(math.radians(s.torso_lean_max))
            self._ineq.append(("torso_lean", ca.vertcat(*[q[root + 11] - lean for q in inner])))
            self._knot_rows("torso_lean", self._entry_row(root + 11), [lean],
                            range(1, K + 1))
        if s.torso_height_min > 0:
            self._ineq.append(("torso_height",
                               ca.vertcat(*[q[root + 2] - s.torso_height_min for q in inner])))
            self._knot_rows("torso_height", self._entry_row(root + 2), [s.torso_height_min],
                            range(1, K + 1))
        if s.joint_limits:
            fn, c = self._limits(s.joint_limits)
            self._ineq.append(("joint_limits", ca.vertcat(*[fn(q, c) for q in inner])))
            self._knot_rows("joint_limits", fn, c, range(1, K + 1))
        for phase, limits in s.phase_joint_limits:
            fn, c = self._limits(limits, f"joint_limits_{phase}")
            knots = [j for j in range(1, K + 1) if phase_names[j] == phase]
            if knots:
                self._ineq.append((f"joint_limits[{phase}]",
                                   ca.vertcat(*[fn(self.q[j], c) for j in knots])))
                self._knot_rows(f"joint_limits[{phase}]", fn, c, knots)
        if s.joint_speed_max > 0 and scene.joints:
            fn, c = joint_speed_margins(mb), ca.DM([s.base_time_step,
                                                   math.radians(s.joint_speed_max)])
            self._ineq.append(("joint_speed", ca.vertcat(
                *[fn(self.q[j], self.q[j + 1], self.h[j], c) for j in range(K)])))
            self._interval_rows("joint_speed", fn, (), np.array(c).ravel(), range(K), 0)
            self._no_elements_left("joint_speed", K * int(fn.size1_out(0)))

    def _entry_row(self, i: int) -> ca.Function:
        """(q, c) -> q[i] - c[0], the form of the torso rows."""
        q, c = ca.SX.sym("q", self.mb.k), ca.SX.sym("c", 1)
        return ca.Function(f"q{i}_above", [q, c], [q[i] - c[0]], ["q", "c"], ["r"])

    def _knot_rows(self, group: str, fn: ca.Function, c, knots):
        """The rows fn(q_j, c) of `group`, one block per knot in `knots`, as elements
        (`knot_element`)."""
        element = self._element_fn("knot", lambda: knot_element(self.model, fn), fn.name())
        size = int(fn.size1_out(0))
        for row, j in enumerate(knots):
            self._element_set.add(element, np.array(c).ravel(), self._theta_at[j],
                                  [(group, size * row + np.arange(size))])
        self._no_elements_left(group, size * len(knots))

    def _interval_rows(self, group: str, fn: ca.Function, key, c, intervals, first: int):
        """The rows fn(q_j, q_{j+1}, h_j, c) of `group` for the intervals j, one block each
        from its local row `first` on, as elements (`knot_pair_element`)."""
        element = self._element_fn("pair", lambda: knot_pair_element(self.model, fn),
                                   fn.name(), key)
        size = int(fn.size1_out(0))
        for row, j in enumerate(intervals):
            self._element_set.add(
                element, np.concatenate([[self._length[j]], np.ravel(c)]),
                np.concatenate([self._theta_at[j], self._theta_at[j + 1], [self._sigma_at[j]]]),
                [(group, first + size * row + np.arange(size))])

    def _limits(self, limits, name: str = "joint_limits"):
        """The joint-range margins (`ocp.posture.joint_limit_margins`, two one-sided rows per
        angle) and their constants. Not the product's one row per angle with two bounds
        (`ocp.posture.joint_limit_rows`): with those this baseline's walker3d plans missed
        work_precision.py's 150 s limit on all four grids, and with the ranges as bounds on
        the knots' angles on 4 intervals per phase (the one grid measured), where the
        margins converge on 4, 6 and 8 (benchmarks/HISTORY.md, 2026-11-26)."""
        return (joint_limit_margins(self.mb, tuple(a for a, _, _ in limits), name),
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

    @property
    def g_without_elements(self):
        """g with the element rows' element parts left out (g minus the `elements`)."""
        return ca.vertcat(*[self._without_elements.get(n, e) for n, e in self._eq + self._ineq])

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
