"""The plan against physics (issue #10): a plan's joint torques and contact schedule applied
to the continuous equations of motion (`gait_planner.verify.constrained`, Pinocchio),
integrated with scipy's DOP853, and how far the simulated motion drifts from the plan.

Works on any `PlanResult` (DMOCC or collocation) of any scene; `physics_error(result,
reset=...)` is the API.

* Schedule: interval n (t_n .. t_{n+1}) holds active_contacts[n] (docs/design.md section 7); a
  segment is a maximal run of intervals holding the same contacts, simulated from its first
  node to its last (nodes 0 .. N, the last interval being the periodic continuation).
* Torques: the node torques tau[n], linear in time between nodes (`result.py`), converted
  to Pinocchio efforts at the simulated configuration (`ConstrainedModel.efforts`).
* Segment start: the contacts it holds are anchored where their points are, and the velocity
  is projected on them by the plastic impact map (a contact established there: its impact;
  a contact released: nothing to project, released points just drop).
* The plan's state at a segment start s: Pinocchio's q of q_s (`continuous.pin_configuration`)
  and a velocity from one-sided second-order differences inside the segment, on the
  configuration group at q_s (xi_i = difference(q_s, q_{s+i}) / offsets, the derivative at
  t_s of the quadratic through 0, xi_1, xi_2; nodes past N from the periodic continuation
  q_{N-1+j} = mirror(q_j), shifted by the step and the ground's rise), then projected on the
  held contacts. One-sided because the velocity jumps at an impact and the acceleration at
  a release; second order like the plan (a segment of a single interval takes node s - 1
  instead when interval s - 1 holds the same contacts, else the two-point difference).
* reset="node": every interval starts from the plan's state at its first node: the drift
  after one interval is the plan's local error against the continuous dynamics (O(h^3) for
  a second-order plan where the motion is smooth), free of any growth.
  reset="phase": every segment starts from the plan's state: the drift over a phase, growth
  of errors within it included, but not the open-loop instability of the whole step.
  reset="none": only the first; the half cycle open loop, the honest drift (instability
  growth included).
* Measured at the nodes (the state arriving at a node from the segment before it):
  joint angles (`gait_planner.model.angles`, both from director coordinates), contact
  points, the root's centre of mass, the ground force on each foot against the sum of the
  plan's point forces on it (nodes away from contact switches only, `physical.near_switch`
  with the switches' periodic images: the plan's node force at a switch holds the impact),
  and the periodicity gap: the configuration at node N-1 against the mirrored start
  (mirror(q_0) + step length e_x + rise e_z), over body centres of mass and contact points.
* A failed integration (blow-up: a velocity above `SPEED_LIMIT`, a singular constraint
  matrix, overflow, a step size underflow or more than `MAX_RHS` evaluations) ends its
  segment with a reason in `failure`; nodes after it are not measured (NaN).

Measured (test/verify/test_verify_drift.py, reset="phase"): where a plan's motion is smooth
the drift falls faster than h^2 (walker2d's and walker3d's first phase, on the right foot:
7.0 -> 1.1 deg and 9.0 -> 1.4 deg from 4 to 8 intervals per phase at equal durations).
Right after a heel or forefoot release the first interval drifts ~2 deg at every grid
(h = 15 and 7.5 ms alike): the push-off torque already acts while the point is held, and
the released light foot then turns faster than the grid resolves, so the plan's lift-off
is not a motion of the continuous model. 3D point-contact phases drift tens of degrees
(the foot rolls freely about a point contact). The Baumgarte rate changed no drift by
more than 1e-6 deg (0, 50, 500 rad/s).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

from gait_planner.model.angles import joint_angles
from gait_planner.result import PlanResult
from gait_planner.verify.constrained import ConstrainedModel
from gait_planner.verify.continuous import effort_names, pin_configuration
from gait_planner.verify.ground import RecordedGround
from gait_planner.verify.mechanics import Mechanics, parse_scene
from gait_planner.verify.physical import near_switch, switch_nodes

RESETS = ("node", "phase", "none")
SPEED_LIMIT = 1e3  # m/s or rad/s: any generalised velocity above it is a blow-up
MAX_RHS = 200_000  # right-hand side evaluations per segment (~30 s)


@dataclass(frozen=True)
class PhysicsError:
    """Drift of the simulated motion from a plan (module docstring). Angles in degrees,
    positions in mm, forces in N and relative to the body weight; angle_drift_deg
    (N+1,) the largest joint-angle drift at each node (NaN where not simulated)."""

    scene: str
    reset: str
    failure: str  # "" when every segment was integrated to its end
    rtol: float
    atol: float
    segments: tuple[tuple[int, int], ...]  # (first, last node) of each contact segment
    angle_drift_deg: np.ndarray
    angle_drift_rms_deg: float  # RMS over nodes and joint angles
    angle_drift_max_deg: float
    contact_drift_max_mm: float  # every contact point at every node
    swing_drift_max_mm: float  # contact points at nodes that do not hold them
    root_drift_max_mm: float  # the root body's centre of mass
    periodicity_gap_mm: float
    periodicity_gap_deg: float
    force_error_max_n: float  # per foot, away from contact switches
    force_error_relative: float  # force_error_max_n / body weight
    constraint_error_max: float  # m (or rad): held constraints in the simulation
    rhs_evaluations: int
    wall_time: float  # s, building the model and integrating

    @property
    def ok(self) -> bool:
        return not self.failure

    @property
    def segment_drift_deg(self) -> tuple[float, ...]:
        """Largest joint-angle drift (deg) at the nodes after each segment's first."""
        return tuple(float(np.max(self.angle_drift_deg[s + 1:e + 1])) for s, e in self.segments)

    def summary(self) -> str:
        """One line: the drift measures, the cost and the failure if any."""
        return (f"physics error ({self.scene}, reset={self.reset}): joint angles RMS "
                f"{self.angle_drift_rms_deg:.3g} deg, max {self.angle_drift_max_deg:.3g} deg; "
                f"contact points {self.contact_drift_max_mm:.3g} mm (swing "
                f"{self.swing_drift_max_mm:.3g} mm), root {self.root_drift_max_mm:.3g} mm; "
                f"periodicity gap {self.periodicity_gap_mm:.3g} mm, "
                f"{self.periodicity_gap_deg:.3g} deg; foot force error "
                f"{self.force_error_max_n:.3g} N = {100 * self.force_error_relative:.3g} % of "
                f"weight; per segment (deg) "
                + ", ".join(f"{d:.3g}" for d in self.segment_drift_deg)
                + f"; {self.rhs_evaluations} rhs evaluations, {self.wall_time:.2f} s"
                + (f"; FAILED: {self.failure}" if self.failure else ""))

    def as_dict(self) -> dict:
        """Plain JSON-ready values (arrays as lists, NaN kept as float('nan'))."""
        out = {k: (v.tolist() if isinstance(v, np.ndarray) else v)
               for k, v in asdict(self).items()}
        return dict(out, ok=self.ok, segment_drift_deg=list(self.segment_drift_deg))


class _Blowup(RuntimeError):
    """The integration left the range of a physical motion (the message says how)."""


@dataclass
class _Run:
    """Simulated nodes (None where not simulated): q, v Pinocchio's state arriving at the
    node (node 0: the start); forces[n] body -> (3,) N; the first failure; the largest
    held-constraint error at the nodes (m, rad)."""

    q: list
    v: list
    forces: list
    failure: str
    rhs_evaluations: int
    constraint_error: float


class PlanSimulation:
    """A plan on the continuous model: its schedule, torques and node states."""

    def __init__(self, result: PlanResult):
        self.result = result
        self.scene = parse_scene(result.scene.source)
        self.cm = ConstrainedModel(self.scene)
        self.mech = Mechanics(self.scene)
        # the next half cycle's rise (ramp, stairs), from the ground the result's metadata names
        self.rise = RecordedGround.of(result.settings).rise(result.step_length)
        self.times = np.asarray(result.times, float)
        self.N = len(self.times) - 1
        names = list(result.joint_angle_names)
        self.tau = np.asarray(result.tau, float)[:, [names.index(n)
                                                     for n in effort_names(self.scene)]]
        self.active = tuple(frozenset(a) for a in result.active_contacts)
        self.segments = []  # (first node, last node, held contacts)
        for n in range(self.N):
            if self.segments and self.active[n] == self.segments[-1][2]:
                self.segments[-1][1] = n + 1
            else:
                self.segments.append([n, n + 1, self.active[n]])
        self.configs = [pin_configuration(self.scene, self.cm.model, row) for row in result.q]
        self.partner = self.scene.contact_partners  # mirror image's contact
        # nodes away from contact switches and from their periodic images (n +- (N - 1))
        switches = switch_nodes(result.active_contacts)
        images = {m for n in switches for m in (n - self.N + 1, n + self.N - 1)
                  if 0 <= m <= self.N}
        self.calm = ~near_switch(self.N + 1, tuple(sorted(set(switches) | images)))

    def _torque(self, t: float) -> np.ndarray:
        """Joint torques (na,) N m at time t, linear between the nodes."""
        i = int(np.clip(np.searchsorted(self.times, t) - 1, 0, self.N - 1))
        w = (t - self.times[i]) / (self.times[i + 1] - self.times[i])
        return (1 - w) * self.tau[i] + w * self.tau[i + 1]

    def _extended(self, n: int) -> tuple[float, np.ndarray, frozenset]:
        """(t_n, Pinocchio q_n, contacts of interval n) for n up to 2N - 1, from N on by the
        periodic continuation q_{N-1+j} = mirror(q_j) + step e_x + rise e_z."""
        if n < self.N:
            return self.times[n], self.configs[n], self.active[n]
        j = n - (self.N - 1)
        q = self.mech.mirror(np.asarray(self.result.q[j], float), self.result.step_length,
                             self.rise)
        return (self.times[j] + self.times[self.N - 1] - self.times[0],
                pin_configuration(self.scene, self.cm.model, q),
                frozenset(self.partner[c] for c in self.active[j]))

    def plan_velocity(self, s: int) -> np.ndarray:
        """The plan's velocity (nv,) at node s < N (module docstring), not yet projected."""
        t0, q0, held = self._extended(s)
        t1, q1, held1 = self._extended(s + 1)
        xi1, tau1 = pin.difference(self.cm.model, q0, q1), t1 - t0
        if held1 != held:  # the segment has a single interval: take node s - 1 instead of
            # s + 2 if interval s - 1 holds the same contacts (no impact at s)
            if s == 0 or self.active[s - 1] != held:
                return xi1 / tau1
            t2, q2 = self.times[s - 1], self.configs[s - 1]
        else:
            t2, q2, _ = self._extended(s + 2)
        xi2, tau2 = pin.difference(self.cm.model, q0, q2), t2 - t0
        return -tau2 / (tau1 * (tau1 - tau2)) * xi1 - tau1 / (tau2 * (tau2 - tau1)) * xi2

    def run(self, reset: str, *, rtol: float, atol: float,
            start_velocities: dict[int, np.ndarray] | None = None) -> _Run:
        """Simulate every segment (module docstring); start_velocities: node -> Pinocchio v
        (nv,) replacing `plan_velocity` there (a plan that has its velocities)."""
        N = self.N
        out = _Run([None] * (N + 1), [None] * (N + 1), [None] * (N + 1), "", 0, 0.0)
        state = None
        pieces = [(n, n + 1, held) if reset == "node" else (s, e, held)
                  for s, e, held in self.segments
                  for n in (range(s, e) if reset == "node" else [s])]
        for s, e, held in pieces:
            if state is None or reset != "none":
                v = (start_velocities or {}).get(s)
                state = (self.configs[s], self.plan_velocity(s) if v is None else v)
            if s == 0:
                out.q[0], out.v[0] = state
            try:
                state = self._segment(s, e, held, *state, out, rtol=rtol, atol=atol)
            except (_Blowup, np.linalg.LinAlgError, FloatingPointError) as error:
                out.failure = out.failure or f"segment of nodes {s}..{e} {sorted(held)}: {error}"
                if reset == "none":
                    break
        return out

    def _segment(self, s: int, e: int, held: frozenset, q: np.ndarray, v: np.ndarray,
                 out: _Run, *, rtol: float, atol: float) -> tuple[np.ndarray, np.ndarray]:
        """Nodes s+1 .. e of the segment (into `out`) from (q, v) at node s, held contacts
        anchored at q and v projected on them; returns the state at node e."""
        cm, nq = self.cm, self.cm.nq
        blocks = cm.blocks(q, held)
        v = cm.impact(q, v, blocks)
        out.forces[s] = cm.foot_forces(cm.forward(q, v, self._torque(self.times[s]), blocks)[1],
                                       blocks)
        calls = [0]

        def rhs(t, y):
            calls[0] += 1
            if calls[0] > MAX_RHS:
                raise _Blowup(f"more than {MAX_RHS} rhs evaluations")
            qn = pin.normalize(cm.model, y[:nq])
            a, _ = cm.forward(qn, y[nq:], self._torque(t), blocks)
            return np.concatenate([cm.configuration_rate(qn, y[nq:]), a])

        def too_fast(t, y):
            return SPEED_LIMIT - np.abs(y[nq:]).max()
        too_fast.terminal = True

        try:
            sol = solve_ivp(rhs, (self.times[s], self.times[e]), np.concatenate([q, v]),
                            method="DOP853", rtol=rtol, atol=atol, events=too_fast,
                            t_eval=self.times[s + 1:e + 1])
        finally:
            out.rhs_evaluations += calls[0]
        reached = np.reshape(sol.y, (nq + cm.nv, -1)).T  # nodes before a failure
        for n, y in enumerate(reached, start=s + 1):
            qn = pin.normalize(cm.model, y[:nq])
            out.q[n], out.v[n] = qn, y[nq:]
            out.constraint_error = max(out.constraint_error, float(np.abs(
                cm.constraint_error(qn, blocks)).max(initial=0.0)))
            lam = cm.forward(qn, y[nq:], self._torque(self.times[n]), blocks)[1]
            out.forces[n] = cm.foot_forces(lam, blocks)
        if sol.status == 1:
            raise _Blowup(f"a velocity above {SPEED_LIMIT:g} at t = {sol.t_events[0][0]:.4g} s")
        if sol.status != 0:
            raise _Blowup(sol.message)
        return out.q[e], out.v[e]


def physics_error(result: PlanResult, *, reset: str = "phase", rtol: float = 1e-10,
                  atol: float = 1e-10,
                  start_velocities: dict[int, np.ndarray] | None = None) -> PhysicsError:
    """Simulate `result` on the continuous dynamics and measure its drift (module
    docstring). reset: "node", "phase" or "none"; rtol, atol: DOP853's tolerances; start_velocities:
    segment start node -> Pinocchio velocity (nv,) to start from instead of the
    differences of the plan's configurations (a motion whose velocities are known, e.g.
    one simulated here). Raises ValueError for an unknown reset or a plan whose scene has
    no source text (the model is built from the scene file, `verify.mechanics`)."""
    if reset not in RESETS:
        raise ValueError(f"reset must be one of {RESETS}, got {reset!r}")
    if not result.scene.source:
        raise ValueError(f"the plan's scene {result.scene.name!r} has no source text")
    start = time.perf_counter()
    sim = PlanSimulation(result)
    run = sim.run(reset, rtol=rtol, atol=atol, start_velocities=start_velocities)
    wall = time.perf_counter() - start
    N, mech, scene = sim.N, sim.mech, sim.scene
    nodes = [n for n in range(N + 1) if run.q[n] is not None]  # simulated nodes
    q_plan = np.asarray(result.q, float)[nodes]
    q_sim = np.array([sim.cm.director_configuration(run.q[n]) for n in nodes])
    drift = _angle_difference(joint_angles(result.scene, q_sim),
                              joint_angles(result.scene, q_plan))  # (nodes, na) deg
    per_node = np.full(N + 1, np.nan)
    per_node[nodes] = drift.max(axis=1, initial=0.0)
    points = {c: mech.contact_matrix(c) for c in scene.contacts}
    point_drift = {c: 1e3 * np.linalg.norm((q_sim - q_plan) @ C.T, axis=1)
                   for c, C in points.items()}  # (nodes,) mm
    swing = [d for c in points for d, n in zip(point_drift[c], nodes)
             if c not in sim.active[n]]
    root = mech.start(scene.root)
    gap_mm = gap_deg = float("nan")
    if N - 1 in nodes:
        end = q_sim[nodes.index(N - 1)]
        image = mech.mirror(q_plan[0], result.step_length, sim.rise)
        pieces = [mech.point_matrix(b.name, np.zeros(3)) for b in scene.bodies]
        gap_mm = max(1e3 * float(np.linalg.norm(C @ (end - image)))
                     for C in pieces + list(points.values()))
        gap_deg = float(_angle_difference(joint_angles(result.scene, end),
                                          joint_angles(result.scene, image)).max())
    force_error = 0.0
    for n in nodes:
        if not sim.calm[n]:
            continue
        for body, F in run.forces[n].items():
            planned = sum(np.asarray(result.contact_forces[c][n], float)
                          for c, (b, _) in scene.contacts.items() if b == body)
            force_error = max(force_error, float(np.linalg.norm(F - planned)))
    return PhysicsError(
        scene=scene.name, reset=reset, failure=run.failure, rtol=rtol, atol=atol,
        segments=tuple((s, e) for s, e, _ in sim.segments), angle_drift_deg=per_node,
        angle_drift_rms_deg=float(np.sqrt(np.mean(drift ** 2))),
        angle_drift_max_deg=float(drift.max()),
        contact_drift_max_mm=float(max(d.max() for d in point_drift.values())),
        swing_drift_max_mm=max(swing, default=0.0),
        root_drift_max_mm=float(1e3 * np.linalg.norm(
            q_sim[:, root:root + 3] - q_plan[:, root:root + 3], axis=1).max()),
        periodicity_gap_mm=gap_mm, periodicity_gap_deg=gap_deg,
        force_error_max_n=force_error, force_error_relative=force_error / sim.cm.weight,
        constraint_error_max=run.constraint_error, rhs_evaluations=run.rhs_evaluations,
        wall_time=wall)


def _angle_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a - b| wrapped to [0, 180] deg, of angles in rad."""
    return np.degrees(np.abs(np.angle(np.exp(1j * (a - b)))))
