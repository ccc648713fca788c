"""Crocoddyl peer: problem.json -> plan.npz, run in the peer env from the repository root:

    .venv-peers/crocoddyl/bin/python -m benchmarks.peers.crocoddyl_peer PROBLEM OUT.npz \
        [--solver fddp|csqp] [--integrator euler|rk4] [--setup project|example] \
        [--threads 1] [--max-iterations 2000] [--time-limit 300]

The gait written as Crocoddyl's biped examples write one (crocoddyl/utils/biped.py,
SimpleBipedGaitProblem; mim_solvers/examples/solo12.py for constraints):
* the walker: Pinocchio's model of the project's URDF on a free flyer (continuous joints
  as (cos, sin)), the scene's own principal moments where the URDF holds realisable ones
  instead (problem.json inertia_overrides: walker3d's torso), a sole frame midway between
  heel and forefoot of each foot; ActuationModelFloatingBase (every joint actuated);
* DMOCC's schedule: per phase, its interval count of running models of duration
  duration / intervals (DifferentialActionModelContactFwdDynamics, IntegratedActionModel
  Euler or RK4, zero-order-hold control); a body holding two points (heel and forefoot) a
  ContactModel6D at its sole frame, a single point a ContactModel3D, both LOCAL_WORLD_ALIGNED
  with the examples' gains [0, 30] (velocity damping; no position feedback); at a phase
  whose contacts include a touchdown, an ActionModelImpulseFwdDynamics with impulse models
  of every contact held after it (perfectly plastic), the striking points' placement
  (DMOCC's) tracked there by a cost of weight SETUPS[setup]["placement"] (FDDP) or held by
  an equality constraint (CSQP);
* cost: sum over running models of dt |tau|^2 (the squared-torque cost) plus the
  regularisation the examples carry: ResidualModelState to the kinematic guess. The
  weights are a setup (SETUPS, --setup): "project" (the default) keeps the regularisation
  small against the squared torque (weight 1) and reads DMOCC's hard constraints as stiff
  penalties (1e7 periodicity and ground, 1e6 placement, 1e5 limits); "example" gives every
  term the magnitude the biped example gives its counterpart (control 0.1, state 10 with
  500/0.01/10 per coordinate, wrench cone 10, strike placement 1e8, task 1e6) — the row
  "FDDP euler example weights" of run.py, with the example's Euler integrator;
* DMOCC's inequalities: friction cones (linearised, 4 facets, inner approximation; a full
  foot's WrenchCone over its heel-forefoot length and the scene's foot breadth: CoP inside
  the sole), joint ranges and joint speed limits (state bounds), free contact points at or
  above the ground: quadratic-barrier costs (as the examples' wrench cones) for FDDP; hard
  constraints for mim_solvers' CSQP (--solver csqp, with its README's settings,
  CSQP_SETTINGS). On walker2d at 4 per phase from DMOCC's start (2026-11-28) CSQP fails:
  its ADMM QP does not converge within max_qp_iters (primal residual ~1e3, dual ~1e10 at
  1000 QP iterations, then 1e158), the trial step's cost is NaN, and mim_solvers 0.3.0
  raises "step_error" inside an OpenMP region of tryStep, which aborts the process (exit
  -6, SIGABRT) instead of letting the line search try a shorter step; with the example
  weights it stops after 25 iterations without an acceptable step (J 2e9). Crocoddyl
  3.2.1 fills a ConstraintModelManager's bounds only in calc (uninitialised before): the
  shooting problem is evaluated once before the solver is made;
* the start: Crocoddyl's shooting problem starts from a fixed state x0: the kinematic
  guess's first node (moved along x so its stance heel stands on DMOCC's placement) made
  feasible (`feasible_start`), or (--start dmocc, a warm row) DMOCC's optimal start state;
  periodicity as a terminal cost of weight SETUPS[setup]["periodic"] on the state against
  mirror(x0) + step (hard periodicity needs x0 free, which a shooting problem lacks).
Not expressed: free phase durations, DMOCC's torso lean bound (only the orientation
regularisation), its swing clearance (1 cm) and strike speed bound, kinetic-energy cost.

Threads: the shooting problem's calc/calcDiff run on `ShootingProblem.nthreads` OpenMP
threads, by default the build's CROCODDYL_WITH_NTHREADS (2 in the 3.2.1 wheel; not read from
OMP_NUM_THREADS); --threads sets it (default 1, 0 the library's default) and the plan's
meta says it ("threads"). The solve is one call, stopped at the time limit by a callback
(`_solve_until`).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import crocoddyl
import mim_solvers
import numpy as np
import pinocchio as pin

from benchmarks.peers import exchange

# regularises J M^-1 J^T: walker2d's planar legs make some double-support rows redundant
# (without it FDDP's gradient reached 1e16 on walker2d at 4 per phase)
INV_DAMPING = 1e-8
# Baumgarte gains (kp 1/s^2, kd 1/s) of the contacts towards DMOCC's placements: the
# examples' [0, 30] (velocity damping alone) let held points sink 16 to 34 mm on walker2d
# at 4 intervals per phase (Euler); critically damped at 20 rad/s instead
BAUMGARTE_GAINS = np.array([400.0, 40.0])
# the penalty weights of a setup: the project's (a stiff reading of DMOCC's hard
# constraints) or the magnitudes Crocoddyl's own biped examples give their terms
# (crocoddyl/utils/biped.py, SimpleBipedGaitProblem, which bipedal_gaits_fwddyn.py solves):
# --setup project|example
SETUPS = {
    "project": {
        "torque": 1.0,  # the squared-torque objective itself
        "state_reg": 1.0,
        # per-coordinate weights of the state regularisation (base orientation, joints,
        # velocities), the same at impulses
        "state_weights": {"base_orientation": 10.0, "joints": 0.1, "velocities": 0.1},
        "impulse_state_weights": None,  # the running ones
        # quadratic-barrier weights: per N^2 (cones, as the examples' 10), rad^2 and
        # (rad/s)^2 (joint ranges and speeds), m^2 (contact points above the ground)
        "cone": 10.0, "limits": 1e5, "ground": 1e7,
        "placement": 1e6,
        # terminal periodicity weight per start: from DMOCC's start 1e7 holds the end within
        # 0.7 mm of mirror(x0) (1e5: 45 mm; walker2d, 4 per phase); from the guess's start no
        # periodic gait is near, and 1e7 keeps FDDP from converging (2000 iterations, stop
        # 5.4), so 1e5 there
        "periodic": {"dmocc": 1e7, "guess": 1e5},
    },
    "example": {
        "torque": 1e-1,  # ctrlReg
        "state_reg": 1e1,  # stateReg, running: [0]*3 + [500]*3 + [0.01]*nj + [10]*nv
        "state_weights": {"base_orientation": 500.0, "joints": 0.01, "velocities": 10.0},
        # impulse stateReg: [1]*6 + [0.1]*nj + [10]*nv
        "impulse_state_weights": {"base": 1.0, "joints": 0.1, "velocities": 10.0},
        "cone": 1e1,  # wrenchCone barrier
        "limits": 1e3,  # humanoid_taichi.py's limitCost (biped.py has no joint limits)
        # no counterpart in biped.py: its task weight (comTrack, footTrack 1e6)
        "ground": 1e6,
        "placement": 1e8,  # the impulse model's footTrack
        "periodic": {"dmocc": 1e6, "guess": 1e6},  # task weight (a terminal task here)
    },
}
FOOT_BREADTH = 0.0915  # m, the scene's foot (DMOCC's foot_half_width x 2)
_LWA = pin.LOCAL_WORLD_ALIGNED


class Walker:
    """The Pinocchio model and the names the problem needs."""

    def __init__(self, problem: dict):
        model = pin.buildModelFromXML(Path(problem["urdf"]).read_text(),
                                      pin.JointModelFreeFlyer())
        for link, moments in problem.get("inertia_overrides", {}).items():
            joint = model.frames[model.getFrameId(link)].parentJoint
            old = model.inertias[joint]
            model.inertias[joint] = pin.Inertia(old.mass, old.lever, np.diag(moments))
        self.joint_nqs = [model.joints[j].nq for j in range(2, model.njoints)]
        self.contact = {c: model.getFrameId(c) for c in problem["contact_frames"]}
        self.body_of = {c: model.frames[f].parentJoint for c, f in self.contact.items()}
        self.sole = {}
        for c in problem["contact_frames"]:
            mates = [d for d in problem["contact_frames"] if self.body_of[d] == self.body_of[c]]
            if len(mates) == 2 and c == mates[0]:
                a, b = (model.frames[self.contact[d]].placement for d in mates)
                self.sole[self.body_of[c]] = model.addFrame(pin.Frame(
                    f"{c}_sole", self.body_of[c],
                    pin.SE3(a.rotation, 0.5 * (a.translation + b.translation)),
                    pin.FrameType.OP_FRAME))
                self.sole_length = float(np.linalg.norm(a.translation - b.translation))
        self.model = model
        self.state = crocoddyl.StateMultibody(model)
        self.actuation = crocoddyl.ActuationModelFloatingBase(self.state)
        self.nu = self.actuation.nu

    def groups(self, active: list[str]) -> list[tuple[int, list[str]]]:
        """(frame, contacts) per body holding `active`: its sole for two points, else the point."""
        out = {}
        for c in active:
            out.setdefault(self.body_of[c], []).append(c)
        return [(self.sole[b] if len(cs) == 2 else self.contact[cs[0]], cs)
                for b, cs in out.items()]


def node_states(walker: Walker, problem: dict, source: str) -> tuple[np.ndarray, np.ndarray]:
    """(times (K+1,), states (K+1, nx)) of problem[source] ("guess": the kinematic guess,
    moved along x so that its first held heel stands on DMOCC's placement; "dmocc": DMOCC's
    plan), velocities by one-sided second-order differences on the configuration group
    (node K: backward)."""
    times, q = problem[source]["times"], problem[source]["q"].copy()
    data = walker.model.createData()
    if source == "guess":
        first = problem["phases"][0]["active"][0]
        pin.framesForwardKinematics(walker.model, data,
                                    exchange.to_pinocchio(q[0], walker.joint_nqs))
        q[:, 0] += (problem["placements"][0][first][0]
                    - data.oMf[walker.contact[first]].translation[0])
    q_pin = exchange.to_pinocchio(q, walker.joint_nqs)
    K = len(times) - 1
    v = []
    for n in range(K + 1):
        a, b = (n + 1, n + 2) if n + 2 <= K else (n - 1, n - 2)
        xi1 = pin.difference(walker.model, q_pin[n], q_pin[a])
        xi2 = pin.difference(walker.model, q_pin[n], q_pin[b])
        h1, h2 = times[a] - times[n], times[b] - times[n]
        v.append((h2 * h2 * xi1 - h1 * h1 * xi2) / (h1 * h2 * (h2 - h1)))
    return times, np.array([np.concatenate([qp, vn]) for qp, vn in zip(q_pin, v)])


def feasible_start(walker: Walker, problem: dict, x: np.ndarray, steps: int = 50) -> np.ndarray:
    """The state nearest to x (the guess's first) whose first-phase contacts stand on their
    placements with every joint within its range: Gauss-Newton on the contact positions
    with a small pull (1e-2) to x's configuration, the angles clipped to their ranges after
    each step; the velocity x's, less its part that moves the held points (least squares).
    What a Crocoddyl user does to make x0 (the kinematic guess bends the knee backwards)."""
    model, data, nq = walker.model, walker.model.createData(), walker.model.nq
    q_ref, q = x[:nq], x[:nq].copy()
    held = problem["phases"][0]["active"]
    ranges = [problem["joint_ranges"].get(n) for n in problem["joint_names"]]
    locked = np.zeros(model.nv, dtype=bool)  # joints held at a bound (revolute: v index 6 + k)
    for _ in range(steps):
        pin.computeJointJacobians(model, data, q)
        pin.framesForwardKinematics(model, data, q)
        r = [data.oMf[walker.contact[c]].translation - problem["placements"][0][c] for c in held]
        J = [pin.getFrameJacobian(model, data, walker.contact[c], _LWA)[:3] for c in held]
        r.append(1e-2 * pin.difference(model, q_ref, q))
        J.append(1e-2 * np.eye(model.nv))
        J = np.vstack(J)
        J[:, locked] = 0.0
        q = pin.integrate(model, q, -np.linalg.lstsq(J, np.concatenate(r), rcond=None)[0])
        angles = exchange.from_pinocchio(q, walker.joint_nqs)
        for k, bounds in enumerate(ranges):
            if bounds is not None:
                a = angles[exchange.BASE_NQ + k]
                angles[exchange.BASE_NQ + k] = np.clip(a, *bounds)
                locked[6 + k] |= not bounds[0] <= a <= bounds[1]
        q = exchange.to_pinocchio(angles, walker.joint_nqs)
    pin.computeJointJacobians(model, data, q)
    J = np.vstack([pin.getFrameJacobian(model, data, walker.contact[c], _LWA)[:3]
                   for c in held])
    v = x[nq:] - np.linalg.pinv(J) @ (J @ x[nq:])
    return np.concatenate([q, v])


def mirror_state(walker: Walker, problem: dict, x: np.ndarray, back: bool = False
                 ) -> np.ndarray:
    """The next half cycle's state of x (back: the previous one's, the inverse):
    configuration by `exchange.mirror_configuration`; base velocity (local frame) linear
    S v, angular -S w; joint rates like the angles."""
    nq = walker.model.nq
    q = exchange.from_pinocchio(x[:nq], walker.joint_nqs)
    v = x[nq:]
    S = np.array([1.0, -1.0, 1.0])
    v_out = np.concatenate([S * v[:3], -S * v[3:6],
                            exchange.mirror_efforts(problem, v[6:])])
    q_out = exchange.mirror_configuration(problem, q)
    if back:
        q_out[0] -= 2.0 * problem["mirror"]["base"]["x_shift"]
    return np.concatenate([exchange.to_pinocchio(q_out, walker.joint_nqs), v_out])


class GaitBuilder:
    """Action models of the gait (module docstring) for one solver kind."""

    def __init__(self, walker: Walker, problem: dict, hard: bool, integrator: str,
                 setup: dict):
        self.w, self.p, self.hard, self.integrator = walker, problem, hard, integrator
        self.setup = setup
        self.mu = problem["friction_coefficient"]
        nv = walker.model.nv
        names = problem["joint_names"]
        lo = np.full(2 * nv, -np.inf)
        hi = np.full(2 * nv, np.inf)
        for k, name in enumerate(names):
            if name in problem["joint_ranges"]:
                lo[6 + k], hi[6 + k] = problem["joint_ranges"][name]
        if problem["joint_speed_limit"] > 0:
            lo[nv + 6:], hi[nv + 6:] = -problem["joint_speed_limit"], problem["joint_speed_limit"]
        self.state_bounds = (lo, hi)
        self.x_neutral = walker.state.zero()
        running = setup["state_weights"]
        weights = np.concatenate([[0.0] * 3, [running["base_orientation"]] * 3,
                                  [running["joints"]] * (nv - 6), [running["velocities"]] * nv])
        self.reg_activation = weights ** 2
        impulse = setup["impulse_state_weights"]
        self.impulse_reg_activation = self.reg_activation if impulse is None else \
            np.concatenate([[impulse["base"]] * 6, [impulse["joints"]] * (nv - 6),
                            [impulse["velocities"]] * nv]) ** 2

    def _bounded(self, costs, constraints, name: str, kind: str, residual, lo, hi) -> None:
        """residual within [lo, hi]: a constraint (CSQP) or a quadratic barrier (FDDP)."""
        if self.hard:
            constraints.addConstraint(name, crocoddyl.ConstraintModelResidual(
                self.w.state, residual, lo, hi))
        else:
            finite = 1e20
            bounds = crocoddyl.ActivationBounds(np.maximum(lo, -finite), np.minimum(hi, finite))
            costs.addCost(name, crocoddyl.CostModelResidual(
                self.w.state, crocoddyl.ActivationModelQuadraticBarrier(bounds), residual),
                self.setup[kind])

    def _common(self, costs, constraints, x_ref: np.ndarray, free: list[str], nu: int) -> None:
        w = self.w
        activation = self.reg_activation if nu else self.impulse_reg_activation
        costs.addCost("state_reg", crocoddyl.CostModelResidual(
            w.state, crocoddyl.ActivationModelWeightedQuad(activation),
            crocoddyl.ResidualModelState(w.state, x_ref, nu)), self.setup["state_reg"])
        self._bounded(costs, constraints, "limits", "limits",
                      crocoddyl.ResidualModelState(w.state, self.x_neutral, nu),
                      *self.state_bounds)
        for c in free:
            self._bounded(costs, constraints, f"{c}_ground", "ground",
                          crocoddyl.ResidualModelFrameTranslation(w.state, w.contact[c],
                                                                  np.zeros(3), nu),
                          np.array([-np.inf, -np.inf, 0.0]), np.full(3, np.inf))

    def running(self, phase: int, dt: float, x_ref: np.ndarray):
        w, nu = self.w, self.w.nu
        active, placed = self.p["phases"][phase]["active"], self.p["placements"][phase]
        contacts = crocoddyl.ContactModelMultiple(w.state, nu)
        costs = crocoddyl.CostModelSum(w.state, nu)
        constraints = crocoddyl.ConstraintModelManager(w.state, nu)
        for frame, cs in w.groups(active):
            name = w.model.frames[frame].name
            if len(cs) == 2:
                heel, toe = (placed[c] for c in cs)
                yaw = np.arctan2(toe[1] - heel[1], toe[0] - heel[0])
                contacts.addContact(name, crocoddyl.ContactModel6D(
                    w.state, frame, pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, yaw),
                                            0.5 * (heel + toe)), _LWA, nu, BAUMGARTE_GAINS))
                cone = crocoddyl.WrenchCone(np.eye(3), self.mu,
                                            np.array([w.sole_length, FOOT_BREADTH]), 4, True)
                residual = crocoddyl.ResidualModelContactWrenchCone(w.state, frame, cone, nu)
            else:
                contacts.addContact(name, crocoddyl.ContactModel3D(
                    w.state, frame, placed[cs[0]], _LWA, nu, BAUMGARTE_GAINS))
                cone = crocoddyl.FrictionCone(np.eye(3), self.mu, 4, True)
                residual = crocoddyl.ResidualModelContactFrictionCone(w.state, frame, cone, nu)
            self._bounded(costs, constraints, f"{name}_cone", "cone", residual, cone.lb, cone.ub)
        costs.addCost("torque", crocoddyl.CostModelResidual(
            w.state, crocoddyl.ResidualModelControl(w.state, nu)), self.setup["torque"])
        free = [c for c in self.p["contact_frames"] if c not in active]
        self._common(costs, constraints, x_ref, free, nu)
        dmodel = crocoddyl.DifferentialActionModelContactFwdDynamics(
            w.state, w.actuation, contacts, costs, constraints, INV_DAMPING, True)
        if self.integrator == "rk4":
            return crocoddyl.IntegratedActionModelRK(dmodel, crocoddyl.RKType.four, dt)
        return crocoddyl.IntegratedActionModelEuler(dmodel, dt)

    def impulse(self, active: list[str], strikes: dict[str, np.ndarray], x_ref: np.ndarray):
        w = self.w
        impulses = crocoddyl.ImpulseModelMultiple(w.state)
        for frame, cs in w.groups(active):
            kind = crocoddyl.ImpulseModel6D if len(cs) == 2 else crocoddyl.ImpulseModel3D
            impulses.addImpulse(w.model.frames[frame].name, kind(w.state, frame, _LWA))
        costs = crocoddyl.CostModelSum(w.state, 0)
        constraints = crocoddyl.ConstraintModelManager(w.state, 0)
        for c, target in strikes.items():
            residual = crocoddyl.ResidualModelFrameTranslation(w.state, w.contact[c], target, 0)
            if self.hard:
                constraints.addConstraint(f"{c}_strike", crocoddyl.ConstraintModelResidual(
                    w.state, residual, target, target))  # mim_solvers: equality as lb = ub
            else:
                costs.addCost(f"{c}_strike", crocoddyl.CostModelResidual(w.state, residual),
                              self.setup["placement"])
        free = [c for c in self.p["contact_frames"] if c not in active]
        self._common(costs, constraints, x_ref, free, 0)
        return crocoddyl.ActionModelImpulseFwdDynamics(w.state, impulses, costs, constraints,
                                                       0.0, 1e-12, True)

    def terminal(self, x_periodic: np.ndarray, weight: float):
        w = self.w
        costs = crocoddyl.CostModelSum(w.state, w.nu)
        costs.addCost("periodic", crocoddyl.CostModelResidual(
            w.state, crocoddyl.ResidualModelState(w.state, x_periodic, w.nu)), weight)
        contacts = crocoddyl.ContactModelMultiple(w.state, w.nu)
        dmodel = crocoddyl.DifferentialActionModelContactFwdDynamics(
            w.state, w.actuation, contacts, costs, 0.0, True)
        return crocoddyl.IntegratedActionModelEuler(dmodel, 0.0)


def build(problem: dict, solver: str, integrator: str, start: str, setup: str = "project"):
    """(shooting problem, walker, knots (kind, plan node) per action model, initial xs,
    us); x0 from `start` ("guess" or "dmocc"), the initial trajectory the guess's, the
    weights SETUPS[setup]."""
    walker = Walker(problem)
    builder = GaitBuilder(walker, problem, solver == "csqp", integrator, SETUPS[setup])
    times, xs_guess = node_states(walker, problem, "guess")
    models, knots, n = [], [], 0  # knots: (kind, plan node) per action model
    for p, phase in enumerate(problem["phases"]):
        if problem["touchdown"][p]:
            strikes = {c: problem["placements"][p][c] for c in problem["touchdown"][p]}
            models.append(builder.impulse(phase["active"], strikes, xs_guess[n]))
            knots.append(("impulse", n))
        dt = phase["duration"] / phase["intervals"]
        for _ in range(phase["intervals"]):
            models.append(builder.running(p, dt, xs_guess[n]))
            knots.append(("running", n))
            n += 1
    x0 = (feasible_start(walker, problem, xs_guess[0]) if start == "guess" else
          node_states(walker, problem, "dmocc")[1][0])
    shooting = crocoddyl.ShootingProblem(x0, models,
                                         builder.terminal(mirror_state(walker, problem, x0),
                                                          SETUPS[setup]["periodic"][start]))
    xs = [x0] + [xs_guess[k] for _, k in knots[1:]] + [xs_guess[n]]
    us = shooting.quasiStatic(xs[:-1])
    return shooting, walker, knots, xs, us


def contact_forces(walker: Walker, shooting, knots, K: int) -> dict[str, np.ndarray]:
    """contact -> (K+1, 3) world force on the body of each running knot's contacts (a full
    foot's on its first point); node K repeats node K-1."""
    out = {c: np.zeros((K + 1, 3)) for c in walker.contact}
    for (kind, n), model, data in zip(knots, shooting.runningModels, shooting.runningDatas):
        if kind != "running":
            continue
        diff = data.differential
        diff = diff[0] if hasattr(diff, "__len__") else diff  # RK: the first stage's
        pdata = diff.multibody.pinocchio
        for name, contact in diff.multibody.contacts.contacts.todict().items():
            frame = model.differential.contacts.contacts[name].contact.id
            parent = walker.model.frames[frame].parentJoint
            world = pdata.oMi[parent].act(contact.fext)
            first = next(c for c in walker.contact if walker.body_of[c] == parent)
            out[first][n] = world.linear
    for f in out.values():
        f[K] = f[K - 1]
    return out


# mim_solvers' README settings for SolverCSQP (termination on the KKT residual, the ADMM
# QP's iteration cap and tolerances, the filter line search)
CSQP_SETTINGS = {"termination_tolerance": 1e-3, "max_qp_iters": 1000, "eps_abs": 1e-5,
                 "eps_rel": 0.0, "use_filter_line_search": True}


class TimeLimit(Exception):
    """The solve's wall-clock deadline passed (raised from the solver's callback)."""


class Deadline(crocoddyl.CallbackAbstract):
    """FDDP's per-iteration callback that stops the solve at a wall-clock deadline by
    raising TimeLimit; the solver keeps its last accepted iterate."""

    def __init__(self, deadline: float):
        crocoddyl.CallbackAbstract.__init__(self)
        self.deadline = deadline

    def __call__(self, solver) -> None:
        if time.perf_counter() > self.deadline:
            raise TimeLimit


def _solve_until(solver, xs, us, max_iterations: int, deadline: float,
                 init_reg: float = math.nan) -> tuple[bool, int]:
    """(converged, iterations) of one `solve` call from (xs, us) and regularisation
    `init_reg` (NaN: the solver's own start, `reg_min`), stopped at max_iterations or the
    deadline (time.perf_counter()): FDDP by the Deadline callback, CSQP by its own
    `max_solve_time`. One call, not chunks of calls: a new call restarts FDDP's
    regularisation (`init_reg`) and forgets that its iterate was feasible, which a
    convergence test needs (on walker2d at 4 per phase, RK4, from DMOCC's start: 142
    iterations in chunks of 50 against 129 in one call; Euler: 1389 against 613)."""
    if isinstance(solver, crocoddyl.SolverFDDP):
        solver.setCallbacks([Deadline(deadline)])
    else:
        solver.max_solve_time = max(deadline - time.perf_counter(), 0.0)
    try:
        converged = solver.solve(xs, us, max_iterations, False, init_reg)
    except TimeLimit:
        converged = False
    return bool(converged), int(solver.iter)


def solve(problem: dict, solver_name: str, integrator: str, start_state: str,
          max_iterations: int, time_limit: float, rounds: int, threads: int = 1,
          setup: str = "project") -> exchange.Plan:
    """The plan (exchange.Plan) of the problem by Crocoddyl; after the first solve, each
    of `rounds` more starts from the previous half cycle's end mapped back by the mirror
    (x0 <- mirror^-1(x_K)), warm, towards a periodic gait (a fixed point). `threads`: the
    shooting problem's `nthreads` (its OpenMP threads for calc/calcDiff; 0 leaves the
    library's default, CROCODDYL_WITH_NTHREADS, which OMP_NUM_THREADS does not change)."""
    start = time.perf_counter()
    shooting, walker, knots, xs, us = build(problem, solver_name, integrator, start_state,
                                            setup)
    if threads > 0:
        shooting.nthreads = threads
    if solver_name == "csqp":
        # crocoddyl 3.2.1 fills a ConstraintModelManager's bounds (g_lb, g_ub) only in
        # calc: before it they are uninitialised memory
        shooting.calc(xs, us)
        solver = mim_solvers.SolverCSQP(shooting)
        for key, value in CSQP_SETTINGS.items():
            setattr(solver, key, value)
    else:
        solver = crocoddyl.SolverFDDP(shooting)
        solver.th_stop = 1e-7  # the biped example's
    build_time = time.perf_counter() - start
    start = time.perf_counter()
    deadline = start + time_limit
    converged, iterations = _solve_until(solver, xs, us, max_iterations, deadline)
    periodic = shooting.terminalModel.differential.costs.costs["periodic"].cost.residual
    for _ in range(rounds):
        x0 = mirror_state(walker, problem, solver.xs[-1], back=True)
        shooting.x0 = x0
        periodic.reference = mirror_state(walker, problem, x0)
        converged, more = _solve_until(solver, [x0] + list(solver.xs[1:]), list(solver.us),
                                       max_iterations, deadline, float(solver.preg))
        iterations += more
    solve_time = time.perf_counter() - start
    K = sum(1 for kind, _ in knots if kind == "running")
    node_state = {}
    for k, (kind, n) in enumerate(knots):
        node_state[n] = solver.xs[k + 1] if kind == "impulse" else solver.xs[k]
    node_state[K] = solver.xs[-1]
    nq = walker.model.nq
    q = exchange.from_pinocchio(np.array([node_state[n][:nq] for n in range(K + 1)]),
                                walker.joint_nqs)
    tau = np.array([u for (kind, _), u in zip(knots, solver.us) if kind == "running"])
    phase_of_node = np.array([p for p, ph in enumerate(problem["phases"])
                              for _ in range(ph["intervals"])] + [len(problem["phases"]) - 1])
    times = np.concatenate([[0.0], np.cumsum([ph["duration"] / ph["intervals"]
                                              for ph in problem["phases"]
                                              for _ in range(ph["intervals"])])])
    dts = np.diff(times)
    meta = {
        "peer": "crocoddyl", "version": crocoddyl.__version__,
        "solver": "crocoddyl FDDP" if solver_name == "fddp" else "mim_solvers CSQP",
        "formulation": f"multiple shooting, {integrator}, zero-order-hold torques, "
                       "contact forward dynamics, impulses at touchdown",
        "grid": [ph["intervals"] for ph in problem["phases"]],
        "cost": "squared_torque", "build_time": build_time, "solve_time": solve_time,
        "iterations": int(iterations), "rounds": rounds, "converged": bool(converged),
        "status": f"{'converged' if converged else 'not converged'}: stop {solver.stop:.3g}, "
                  f"gap {solver.ffeas:.3g}",
        "objective": float(dts @ (tau ** 2).sum(axis=1)),
        "total_cost": float(solver.cost), "dynamic_gap": float(solver.ffeas),
        "start": start_state, "threads": int(shooting.nthreads), "setup": setup,
        "integrator": integrator,
        "notes": "durations fixed (DMOCC's); start state fixed ("
                 + ("the kinematic guess's" if start_state == "guess" else
                    "DMOCC's optimum: a warm row") + "); "
                 "periodicity a terminal cost; "
                 + ("cones, limits, ground hard (CSQP)" if solver_name == "csqp" else
                    "cones, limits, ground as barrier costs (FDDP)")
                 + "; no torso lean bound, swing clearance or strike speed bound",
    }
    return exchange.Plan(times=times, q=q, tau=tau, phase_of_node=phase_of_node, meta=meta,
                         forces=contact_forces(walker, shooting, knots, K))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problem", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--solver", choices=("fddp", "csqp"), default="fddp")
    parser.add_argument("--integrator", choices=("euler", "rk4"), default="euler")
    parser.add_argument("--start", choices=("guess", "dmocc"), default="guess",
                        help="x0: the kinematic guess's first state, or DMOCC's (warm row)")
    parser.add_argument("--max-iterations", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=0,
                        help="re-solves from the mirrored end state (towards periodicity)")
    parser.add_argument("--time-limit", type=float, default=300.0)
    parser.add_argument("--threads", type=int, default=1,
                        help="ShootingProblem.nthreads (0: the library's default)")
    parser.add_argument("--setup", choices=tuple(SETUPS), default="project",
                        help="penalty weights: the project's, or the biped example's")
    args = parser.parse_args()
    plan = solve(exchange.read_problem(args.problem), args.solver, args.integrator,
                 args.start, args.max_iterations, args.time_limit, args.rounds,
                 args.threads, args.setup)
    exchange.write_plan(args.out, plan)
    print(f"{args.out}: {plan.meta['status']}, {plan.meta['iterations']} iterations, "
          f"{plan.meta['solve_time']:.2f} s, objective {plan.meta['objective']:.4g}, "
          f"{plan.meta['threads']} thread(s)")


if __name__ == "__main__":
    main()
