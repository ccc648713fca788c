"""The Drake peer's gait problem (drake env only): a MathematicalProgram of the walker of a
problem.json (benchmarks/peers/drake_walker.py) on a grid of n intervals per phase.

Formulation (MathematicalProgram, generic constraints evaluated with AutoDiffXd, as the
littledog gait optimisation of the Underactuated Robotics course and Drake's
multibody/optimization ManipulatorEquationConstraint write it; benchmarks/peers/
drake_walker.py has the residuals):
* nodes 0..K (K = phases x intervals, uniform within a phase at problem.json's durations,
  as `exchange.phase_grid`) carry q, v; node K ends the half cycle;
* per interval n (0..K-1): backward Euler kinematics v_{n+1} = N+(q_{n+1})(q_{n+1}-q_n)/h
  and dynamics M(q_{n+1})(v_{n+1} - v_n+) = h (B tau_n + sum J^T f_n + tau_g - C v_{n+1})
  (evaluated by Drake's recursive inverse dynamics) with torques tau_n and contact forces
  f_n of the interval's contacts (zero-order hold);
  --scheme midpoint evaluates both at the interval's midpoint instead (second order, not
  from Drake's examples: what a second-order transcription buys the peer);
* contacts (Drake's PositionConstraint in 3D): every contact point held in a phase sits at
  its DMOCC placement at each node of the phase (heel and forefoot of one foot: the
  forefoot's x row dropped, it repeats the fixed heel-forefoot distance; node K: none, it
  is node 0's mirror image); points not held stay above the ground, by
  problem["swing_clearance"] except at the nodes next to their release or strike (z >= 0
  there);
* touch-down (a phase whose touchdown list is not empty): plastic impact at its first
  node, M(q)(v+ - v-) = sum J^T Lambda over the phase's held points, J v+ = 0 on their rows,
  impulses in the friction cone; v+ starts the phase's first interval;
* friction cones: f_z >= 0 and |f_x| <= mu f_z in the plane (exact); in 3D an inscribed
  8-sided pyramid (linear, at most 7.6 % inside the exact cone);
* mirror periodicity: q_K = mirror(q_0), v_K = mirror(v_0) (linear equalities);
* joint ranges and joint speed limit as bounds; the torso's lean (its z axis within
  problem["torso_lean_max_deg"] of vertical); unit quaternion at every node;
* durations: DMOCC's (bounds fixed), or free (--free-durations: one time step per phase
  within STEP_BOUNDS of DMOCC's, the half cycle's duration free);
* cost: sum_n h tau_n^2 over the K intervals (N^2 m^2 s; DMOCC's torque_squared at
  zero-order hold), or --cost kinetic_energy: sum_n h T(q_{n+1}, v_{n+1}) (J s) plus DMOCC's
  torque regulariser TORQUE_WEIGHT sum h tau^2; either plus FORCE_WEIGHT sum h |f|^2 for
  the split of a full contact's force along the foot that no equation fixes.
The start is problem["guess"] (the kinematic guess DMOCC starts from) at the new grid,
velocities from its differences, torques zero, forces the weight shared by the held points.
"""

from __future__ import annotations

import numpy as np
from pydrake.multibody.inverse_kinematics import PositionConstraint
from pydrake.solvers import MathematicalProgram

from benchmarks.peers.drake_walker import Walker

FORCE_WEIGHT = 1e-6  # (N m / N)^2: forces' weight against torques in the cost
CONE_SIDES = 8  # inscribed friction pyramid in 3D
TORQUE_WEIGHT = 1e-4  # kinetic-energy cost: DMOCC's default torque regulariser
STEP_BOUNDS = (0.5, 1.5)  # free durations: time step / DMOCC's, per phase
SCHEMES = {"backward_euler": "backward Euler (ManipulatorEquationConstraint form)",
           "midpoint": "implicit midpoint (second order)"}


class GaitProgram:
    """The MathematicalProgram of one problem at `intervals` per phase (module docstring).
    Attributes after construction: prog, walker, K, contexts (K, one per node: Drake's
    constraints cache kinematics in them); variables q (nq, K+1), v (nv, K+1), v_plus
    {node: (nv,)}, tau (nj, K), forces {(interval, contact): (d,)}, impulses {(node,
    contact): (d,)}, steps (P,) per phase."""

    def __init__(self, problem: dict, intervals: int, free_durations: bool, scheme: str,
                 cost: str):
        self.problem, self.m, self.free_durations = problem, intervals, free_durations
        self.scheme, self.cost = scheme, cost
        self.walker = w = Walker(problem)
        phases = problem["phases"]
        self.P, self.K = len(phases), len(phases) * intervals
        self.active = [list(p["active"]) for p in phases]
        self.prog = prog = MathematicalProgram()
        self.contexts = [w.plant.CreateDefaultContext() for _ in range(self.K)]
        self.q = prog.NewContinuousVariables(w.nq, self.K + 1, "q")
        self.v = prog.NewContinuousVariables(w.nv, self.K + 1, "v")
        self.tau = prog.NewContinuousVariables(w.nj, self.K, "tau")
        self.steps = prog.NewContinuousVariables(self.P, "h")
        d = len(w.dims)
        self.forces = {(n, c): prog.NewContinuousVariables(d, f"f_{c}_{n}")
                       for n in range(self.K) for c in self.active[n // self.m]}
        self.touchdowns = [p * intervals for p in range(1, self.P)
                           if problem["touchdown"][p]]
        self.v_plus = {s: prog.NewContinuousVariables(w.nv, f"vplus_{s}")
                       for s in self.touchdowns}
        self.impulses = {(s, c): prog.NewContinuousVariables(d, f"imp_{c}_{s}")
                         for s in self.touchdowns for c in self.active[s // self.m]}
        self._durations()
        self._dynamics()
        self._contacts()
        self._impacts()
        self._cones()
        self._periodicity()
        self._bounds()
        self._cost()

    # --- helpers ------------------------------------------------------------------------
    def step(self, n: int):
        """The time step variable of interval n."""
        return self.steps[n // self.m]

    def dmocc_step(self, p: int) -> float:
        """The time step (s) of phase p at problem.json's durations on this grid."""
        return self.problem["phases"][p]["duration"] / self.m

    def held(self, n: int) -> dict[str, np.ndarray]:
        """Contacts held at node n (0..K-1, closed phases), with their placements (3,)."""
        out = {}
        for p in sorted({max(n - 1, 0) // self.m, n // self.m}):
            for c in self.active[p]:
                out.setdefault(c, self.problem["placements"][p][c])
        return out

    def rows(self, contacts) -> dict[str, list[int]]:
        """Position rows per held point: the walker's dims, a forefoot's x dropped when its
        foot's heel is held too (the fixed distance would repeat a row)."""
        out = {}
        for c in contacts:
            dims = list(self.walker.dims)
            if c.endswith("_forefoot") and c.replace("_forefoot", "_heel") in contacts:
                dims = dims[1:]
            out[c] = dims
        return out

    # --- constraints --------------------------------------------------------------------
    def _durations(self):
        for p in range(self.P):
            step = self.dmocc_step(p)
            lo, hi = (STEP_BOUNDS[0] * step, STEP_BOUNDS[1] * step) \
                if self.free_durations else (step, step)
            self.prog.AddBoundingBoxConstraint(lo, hi, self.steps[p])
            self.prog.SetInitialGuess(self.steps[p], step)

    def _dynamics(self):
        w, prog = self.walker, self.prog
        nq, nv, nj = w.nq, w.nv, w.nj
        zeros = np.zeros(nv)

        midpoint = self.scheme == "midpoint"
        # backward Euler's kinematics needs no v_n, its dynamics no q_n: left out of the
        # bindings, whose size sets the AutoDiffXd gradients' length
        kin_sizes = [nq, nq, nv, nv] if midpoint else [nq, nq, 0, nv]
        dyn_sizes = [nq, nq, nv, nv, nj] if midpoint else [0, nq, nv, nv, nj]

        def kinematics(x):
            q0, q1, v0, v1 = np.split(x[1:], np.cumsum(kin_sizes[:-1]))
            return w.kinematics_residual(x[0], q0, q1, v0, v1, midpoint)

        for n in range(self.K):
            contacts = self.active[n // self.m]

            def dynamics(x, contacts=contacts):
                q0, q1, v0, v1, tau, rest = np.split(x[1:], np.cumsum(dyn_sizes))
                forces = dict(zip(contacts, np.split(rest, len(contacts)))) \
                    if contacts else {}
                return w.dynamics_residual(x[0], q0, q1, v0, v1, tau, forces, midpoint)

            state = [[self.step(n)], self.q[:, n], self.q[:, n + 1],
                     self.v_plus.get(n, self.v[:, n]), self.v[:, n + 1]]
            prog.AddConstraint(kinematics, zeros, zeros, np.concatenate(
                [part for part, size in zip(state, [1] + kin_sizes) if size]))
            prog.AddConstraint(dynamics, zeros, zeros, np.concatenate(
                [part for part, size in zip(state, [1] + dyn_sizes) if size]
                + [self.tau[:, n]] + [self.forces[(n, c)] for c in contacts]))

    def _contacts(self):
        clearance = float(self.problem.get("swing_clearance", 0.0))
        held_at = [self.held(n) for n in range(self.K)] + [{}]
        for n in range(self.K):  # node K is node 0's mirror image: no rows of its own
            held = held_at[n]
            for c, rows in self.rows(held).items():
                lower, upper = np.full(3, -np.inf), np.full(3, np.inf)
                lower[rows] = upper[rows] = held[c][rows]
                self._position(n, c, lower, upper)
        for n in range(1, self.K):
            for c in self.walker.frames:
                if c in held_at[n]:
                    continue
                near = c in held_at[n - 1] or c in held_at[n + 1]
                self._position(n, c, np.array([-np.inf, -np.inf, 0.0 if near else clearance]),
                               np.full(3, np.inf))

    def _position(self, n: int, contact: str, lower: np.ndarray, upper: np.ndarray):
        """lower <= world position of the contact at node n <= upper: Drake's
        PositionConstraint in 3D (gradients in C++; a row with both bounds infinite stays,
        free), a Python constraint of the finite rows on a planar walker's reduced
        coordinates."""
        w = self.walker
        rows = np.flatnonzero(np.isfinite(lower) | np.isfinite(upper))
        if not w.planar:
            self.prog.AddConstraint(PositionConstraint(
                w.plant, w.plant.world_frame(), lower, upper, w.frames[contact],
                np.zeros(3), self.contexts[n]), self.q[:, n])
            return
        self.prog.AddConstraint(lambda q: w.point(q, contact)[rows], lower[rows],
                                upper[rows], self.q[:, n])

    def _impacts(self):
        w, prog = self.walker, self.prog
        nq, nv = w.nq, w.nv
        for s in self.touchdowns:
            contacts = self.active[s // self.m]
            rows = self.rows(contacts)
            n_rows = nv + sum(len(r) for r in rows.values())

            def impact(x, contacts=contacts, rows=rows):
                q, vm, vp, rest = np.split(x, np.cumsum([nq, nv, nv]))
                impulses = dict(zip(contacts, np.split(rest, len(contacts))))
                held = [w.point_jacobian(q, c)[rows[c]] @ vp for c in contacts]
                return np.concatenate([w.impact_residual(q, vm, vp, impulses)] + held)
            prog.AddConstraint(impact, np.zeros(n_rows), np.zeros(n_rows), np.concatenate(
                [self.q[:, s], self.v[:, s], self.v_plus[s]]
                + [self.impulses[(s, c)] for c in contacts]))

    def _cones(self):
        mu = float(self.problem["friction_coefficient"])
        for f in list(self.forces.values()) + list(self.impulses.values()):
            normal = f[-1]
            self.prog.AddBoundingBoxConstraint(0.0, np.inf, normal)
            if self.walker.planar:
                self.prog.AddLinearConstraint(f[0] <= mu * normal)
                self.prog.AddLinearConstraint(-f[0] <= mu * normal)
                continue
            inner = mu * np.cos(np.pi / CONE_SIDES)
            for k in range(CONE_SIDES):
                a = 2 * np.pi * k / CONE_SIDES
                self.prog.AddLinearConstraint(
                    np.cos(a) * f[0] + np.sin(a) * f[1] <= inner * normal)

    def _periodicity(self):
        a, b, a_v = self.walker.mirror_matrices()
        nq, nv = self.walker.nq, self.walker.nv
        self.prog.AddLinearEqualityConstraint(
            np.hstack([np.eye(nq), -a]), b,
            np.concatenate([self.q[:, self.K], self.q[:, 0]]))
        self.prog.AddLinearEqualityConstraint(
            np.hstack([np.eye(nv), -a_v]), np.zeros(nv),
            np.concatenate([self.v[:, self.K], self.v[:, 0]]))

    def _bounds(self):
        w, prog, problem = self.walker, self.prog, self.problem
        lean = problem.get("torso_lean_max_deg")
        for n in range(self.K):  # node K's quaternion is node 0's mirror image
            z = self.q[w.quat, n]
            prog.AddConstraint(lambda z: np.array([z @ z]), [1.0], [1.0], z)
            if lean:
                prog.AddConstraint(lambda z: np.array([w.torso_up(z)]),
                                   [np.cos(np.radians(lean))], [np.inf], z)
        ranges = problem.get("joint_ranges", {})
        for j, name in enumerate(problem["joint_names"]):
            if name in ranges:
                lo, hi = ranges[name]
                prog.AddBoundingBoxConstraint(lo, hi, self.q[w.joint_q[j], :])
        limit = problem.get("joint_speed_limit")
        if limit:
            for vel in [self.v] + [v[:, None] for v in self.v_plus.values()]:
                prog.AddBoundingBoxConstraint(-limit, limit, vel[w.joint_v, :])

    def _cost(self):
        """Per interval n: FORCE_WEIGHT h |f|^2 and h |tau|^2 (squared_torque), or
        h T(q_{n+1}, v_{n+1}) + TORQUE_WEIGHT h |tau|^2 (kinetic_energy: DMOCC's cost
        with its default torque regulariser). The torque and force terms are a quadratic
        cost at fixed durations, a Python cost of (h, tau, f) when h is free."""
        w = self.walker
        tau_weight = 1.0 if self.cost == "squared_torque" else TORQUE_WEIGHT
        for n in range(self.K):
            weights = np.concatenate([np.full(w.nj, tau_weight)] + [
                np.full(len(w.dims), FORCE_WEIGHT) for _ in self.active[n // self.m]])
            x = np.concatenate([self.tau[:, n]] + [self.forces[(n, c)]
                                                   for c in self.active[n // self.m]])
            if self.free_durations:
                self.prog.AddCost(lambda z, weights=weights: z[0] * (weights @ (z[1:] ** 2)),
                                  np.concatenate([[self.step(n)], x]))
            else:
                h = self.dmocc_step(n // self.m)
                self.prog.AddQuadraticCost(np.diag(2 * h * weights), np.zeros(len(x)), x,
                                           is_convex=True)
            if self.cost == "kinetic_energy":
                self.prog.AddCost(
                    lambda z: z[0] * w.kinetic_energy(z[1:1 + w.nq], z[1 + w.nq:]),
                    np.concatenate([[self.step(n)], self.q[:, n + 1], self.v[:, n + 1]]))

    # --- start ----------------------------------------------------------------------------
    def set_guess(self):
        """problem["guess"] at this grid: configurations interpolated at the same fraction
        of each phase, velocities their backward differences, torques zero, each interval's
        held points sharing the weight."""
        w, prog, problem = self.walker, self.prog, self.problem
        guess = problem["guess"]["q"]
        starts = np.concatenate([[0], np.cumsum([p["intervals"] for p in problem["phases"]])])
        q = np.zeros((w.nq, self.K + 1))
        for n in range(self.K + 1):
            p, s = divmod(n, self.m)
            if p == self.P:
                p, s = self.P - 1, self.m
            x = starts[p] + s / self.m * problem["phases"][p]["intervals"]
            i = min(int(np.floor(x)), len(guess) - 2)
            q[:, n] = w.from_pin((1 - (x - i)) * guess[i] + (x - i) * guess[i + 1])
        prog.SetInitialGuess(self.q, q)
        v = np.zeros((w.nv, self.K + 1))
        for n in range(1, self.K + 1):
            v[:, n] = w.velocity(self.dmocc_step((n - 1) // self.m), q[:, n - 1], q[:, n],
                                 q[:, n])
        v[:, 0] = w.mirror_v(v[:, self.K])
        prog.SetInitialGuess(self.v, v)
        for s, vp in self.v_plus.items():
            prog.SetInitialGuess(vp, v[:, s])
        prog.SetInitialGuess(self.tau, np.zeros(self.tau.shape))
        weight = -float(problem["gravity"][2]) * w.plant.CalcTotalMass(w.context)
        for (n, c), f in self.forces.items():
            share = np.zeros(len(w.dims))
            share[-1] = weight / len(self.active[n // self.m])
            prog.SetInitialGuess(f, share)
