"""From an NLP solution vector to a plain `PlanResult` (and failed results)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from gait_planner.model.angles import angle_names, joint_angles
from gait_planner.model.scene import Scene
from gait_planner.ocp.held_efforts import held_effort_excess, impact_nodes
from gait_planner.ocp.mirror import configuration_mirror, contact_partners
from gait_planner.ocp.settings import GaitSettings, ground_of
from gait_planner.ocp.transcription import FORCE_SCALE, Transcription
from gait_planner.result import PlanResult, PlanStatus, SolverStats

STATUS_WORDS = {
    "Solve_Succeeded": "converged",
    "Solved_To_Acceptable_Level": "converged to the acceptable optimality tolerance 1e-6",
    "Infeasible_Problem_Detected": "the constraints cannot be satisfied (locally infeasible)",
    "Restoration_Failed": "no feasible point found (restoration failed)",
    "Maximum_Iterations_Exceeded": "iteration limit reached",
    "Maximum_CpuTime_Exceeded": "time limit reached",
    "Maximum_WallTime_Exceeded": "time limit reached",
    "User_Requested_Stop": "time limit reached",
    "Search_Direction_Becomes_Too_Small": "search direction became too small",
    "Diverging_Iterates": "iterates diverged",
    "Invalid_Number_Detected": "NaN or Inf in a function evaluation",
    "Error_In_Step_Computation": "the step computation failed (singular KKT system)",
}
# a converged solve must also meet these (the checks of recordings judge 1e-8 m)
CONSTRAINT_LIMIT = 1e-8
# IPOPT statuses that count as solved: optimal to tol, or to acceptable_tol (1e-6) when the
# scaled optimality error stalls above tol; both with constraints at constr_viol_tol
SOLVED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def violations(tr: Transcription, g: np.ndarray) -> dict[str, float]:
    """Largest violation of each constraint group (equalities |g|, inequalities below 0 or
    above their upper bound: the product's joint-range rows lie in [0, 2]); tr: a
    transcription, with constraint_groups() and bounds() (also the collocation baseline's)."""
    groups, upper = tr.constraint_groups(), tr.bounds()[3]
    out, offset = {}, 0
    for name, size, equality in groups:
        part, bound = g[offset : offset + size], upper[offset : offset + size]
        offset += size
        v = np.abs(part) if equality else np.maximum(0.0, np.maximum(-part, part - bound))
        out[name] = max(out.get(name, 0.0), float(v.max()) if size else 0.0)
    return out


def _extractor(tr: Transcription) -> ca.Function:
    if not hasattr(tr, "_extract"):
        tr._extract = ca.Function(
            "extract", [tr.x, tr.p],
            [tr.Q, tr.TAU, tr.h, tr.cost_parts["kinetic_energy"], tr.cost_parts["torque_squared"]])
    return tr._extract


def _mirror_forces(tr: Transcription, forces: dict[str, np.ndarray],
                   rolls: dict[str, np.ndarray], src: int, dst: int):
    """Forces at node dst = mirror images of those at node src on the partner points; roll
    moments change sign (the mirror turns d2 into -S d2, so M (d2 x n) into -S times it
    with -M)."""
    scene = tr.mb.scene
    mirror = dict(scene.gait.mirror)
    S = np.array([1.0, -1.0, 1.0])
    for name, partner in contact_partners(scene).items():
        forces[partner][dst] = S * forces[name][src]
    for body in rolls:
        rolls[mirror.get(body, body)][dst] = -rolls[body][src]


def joint_rates(scene, mirror: tuple[np.ndarray, np.ndarray, np.ndarray], q: np.ndarray,
                times: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Joint-angle velocities and accelerations (N+1, na), rad/s and rad/s^2, of a half
    cycle q (N+1, k) at times (N+1,): `central_rates` with the periodic continuation as the
    outer neighbours of nodes 0 and N: q_{-1} = A (q_{N-2} - s e - c) and
    q_{N+1} = A q_2 + s e + c, with mirror = (A, e, c) (`ocp.mirror.configuration_mirror`,
    eqs. 7-9), h_{-1} = h_{N-2}, h_N = h_1."""
    A, shift, lift = mirror
    N = len(q) - 1
    h = np.diff(times)
    before = A @ (q[N - 2] - step * shift - lift)
    after = A @ q[2] + step * shift + lift
    return central_rates(scene, np.vstack([before, q, after]),
                         np.concatenate([[times[0] - h[N - 2]], times, [times[-1] + h[1]]]))


def central_rates(scene, q: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Three-point central differences (second order on a non-uniform grid) of the joint
    angles of configurations q (n, k) at times t (n,): velocities and accelerations at the
    inner nodes 1 .. n-2, (n-2, na). The accelerations are the second differences that the
    discrete equations see."""
    theta = np.unwrap(joint_angles(scene, q), axis=0)
    dt = np.diff(t)[:, None]
    slope = np.diff(theta, axis=0) / dt  # interval rates
    w = dt[:-1] + dt[1:]
    velocity = (dt[1:] * slope[:-1] + dt[:-1] * slope[1:]) / w
    acceleration = 2.0 * (slope[1:] - slope[:-1]) / w
    return velocity, acceleration


def end_rates(scene: Scene, q: np.ndarray, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint-angle velocities and accelerations (n, na) of a motion q (n, k) with given
    ends: `central_rates` at the inner nodes, one-sided differences at the two ends (whose
    outer neighbours are not part of the motion), their accelerations the nearest inner
    node's."""
    velocity, acceleration = central_rates(scene, q, times)
    theta = np.unwrap(joint_angles(scene, q), axis=0)
    h = np.diff(times)
    first, last = (theta[1] - theta[0]) / h[0], (theta[-1] - theta[-2]) / h[-1]
    return (np.vstack([first, velocity, last]),
            np.vstack([acceleration[:1], acceleration, acceleration[-1:]]))


def node_kinetic_energy(mass_diagonal: np.ndarray, q: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Kinetic energy (n,) J at the nodes of configurations q (n, k) with interval lengths
    h (n-1,) s: each interval's 1/2 v^T M v with v = (q_{n+1} - q_n) / h_n and the director
    mass matrix M = diag(mass_diagonal) (k,), averaged over a node's two intervals (an end
    node takes its one interval's)."""
    v = np.diff(q, axis=0) / h[:, None]
    T = 0.5 * np.einsum("ni,i,ni->n", v, mass_diagonal, v)
    return np.concatenate([[T[0]], 0.5 * (T[:-1] + T[1:]), [T[-1]]])


def build_result(tr: Transcription, settings: GaitSettings, x: np.ndarray, p: np.ndarray,
                 g: np.ndarray, *, status: str, iterations: int, solve_time: float,
                 build_time: float, evaluation_time: float, origin: str) -> PlanResult:
    """The plan of request `settings` (solved on `tr`, a problem of its shape) from the
    NLP's x, p (`Transcription.parameters`) and g."""
    mb, mech, s, N = tr.mb, tr.mech, settings, tr.N
    scene = mb.scene
    ground = ground_of(scene, settings)
    step = float(p[tr.layout.step_index])
    Q, TAU, h, kinetic, torque = (np.array(v) for v in _extractor(tr)(x, p))
    q, tau, h = Q.T, TAU.T, h.ravel()
    times = np.concatenate([[0.0], np.cumsum(h)])
    phases = scene.gait.phases
    node_phase = [tr.phase_of_interval[min(n, N - 1)] for n in range(N + 1)]
    active = tuple(tuple(pt for bc in tr.contacts[k] for pt in bc.points) for k in node_phase)

    forces = {c.name: np.zeros((N + 1, 3)) for c in scene.contacts}
    rolls = {c.body: np.zeros(N + 1) for c in scene.contacts}
    for n, lam in tr.node_multipliers(x).items():
        values, inner = FORCE_SCALE * lam, 0
        for bc in tr.contacts[tr.phase_of_interval[n]]:
            own = values[inner : inner + bc.n_multipliers]
            for name, f in bc.point_forces(own, q[n]).items():
                forces[name][n] = f
            rolls[bc.body][n] = bc.roll_moment(own)
            inner += bc.n_multipliers
    if not tr.transition:  # nodes 0 and N: the images of N-1 and 1 (a transition's are given)
        _mirror_forces(tr, forces, rolls, N - 1, 0)
        _mirror_forces(tr, forces, rolls, 1, N)

    half = 0.5 * (np.concatenate([[0.0], h]) + np.concatenate([h, [0.0]]))  # w_n; ends h/2
    gen = half[:, None] * np.array(mb.actuation_force.map(N + 1)(q.T, tau.T)).T
    angles = joint_angles(scene, q)
    if tr.transition:
        rates = end_rates(scene, q, times)
    else:
        rates = joint_rates(scene, configuration_mirror(mb, ground), q, times, step)

    viol = violations(tr, g)
    constraint = max(float(np.abs(np.array(mb.constraints.map(N + 1)(q.T))).max()),
                     *(v for k, v in viol.items() if not k.startswith("dynamics")
                       and k in ("contact_hold", "contact_establish", "pin_x",
                                 "end_scaling")))
    dynamics = FORCE_SCALE * max((v for k, v in viol.items()
                                  if k.startswith("dynamics") or k == "start_momentum"),
                                 default=0.0)
    worst = max(viol, key=viol.get) if viol else ""
    success = status in SOLVED and max(viol.values(), default=0.0) <= CONSTRAINT_LIMIT
    words = STATUS_WORDS.get(status, status)
    message = f"IPOPT: {words} ({status}) after {iterations} iterations"
    if not success:
        message += f"; most violated: {worst} ({viol.get(worst, 0.0):.3e})"
        if worst == "held_effort":
            message += ": " + held_effort_excess(
                mb, q, h, impact_nodes(tr.contacts, tr.phase_of_interval))
    cost_value = float((kinetic if s.cost == "kinetic_energy" else torque).item())
    stats = SolverStats(
        status=status, iterations=iterations, solve_time=solve_time, build_time=build_time,
        evaluation_time=evaluation_time,
        max_constraint_violation=float(constraint), max_dynamics_residual=float(dynamics),
        max_friction_violation=float(viol.get("friction_cone", 0.0)), most_violated=worst,
    )
    return PlanResult(
        success=success, message=message, scene=scene, cost_name=s.cost,
        cost_value=cost_value, step_length=step,
        friction_coefficient=float(p[tr.layout.mu_index]),
        times=times, q=q, tau=tau, joint_angle_names=angle_names(scene), joint_angles=angles,
        joint_velocities=rates[0], joint_accelerations=rates[1],
        phases=tuple(phases[k].name for k in node_phase), active_contacts=active,
        contact_forces=forces, roll_moments=rolls, generalized_force=gen,
        kinetic_energy=node_kinetic_energy(mb.mass_diagonal, q, h),
        potential_energy=q @ mech.gravity_gradient, phase_scaling=x[-int(tr.S.shape[0]):].copy(),
        duration=float(times[N - 1] - times[0]), stats=stats, ground=ground,
        settings={
            "periodicity": ("none: the first node given, the last two the gait's "
                            "(ocp.transition)"
                            if tr.transition else
                            "nodes N-1, N mirror nodes 0, 1 (paper eqs. 7-9)"),
            "initial_guess": origin,
            "intervals_per_phase": ",".join(str(i) for i in s.intervals),
            "base_time_step": repr(s.base_time_step),
            "scaling_bounds": ",".join(repr(b) for b in s.scaling_bounds),
            "torque_regularisation": repr(s.torque_regularisation),
            "foot_half_width": repr(s.foot_half_width),
            "strike_speed_max": repr(s.strike_speed_max),
            **({"strike_deceleration_max": repr(s.strike_deceleration_max)}
               if s.strike_deceleration_max > 0 else {}),
            **({"torque_smoothness": repr(s.torque_smoothness)}
               if s.torque_smoothness > 0 else {}),
            **({"leg_clearance": repr(s.leg_clearance)}
               if any(name == "leg_clearance" for name, _, _ in tr.constraint_groups())
               else {}),
            "speed": repr(s.speed),
            **ground.metadata(),
            "joint_limits_deg": ",".join(f"{name}:{np.degrees(lo):.6g}:{np.degrees(hi):.6g}"
                                         for name, lo, hi in s.joint_limits),
            "torque_squared": repr(float(torque.item())),
            "kinetic_energy": repr(float(kinetic.item())),
        },
    )


def failed_result(scene: Scene, settings: GaitSettings | None, message: str,
                  status: PlanStatus = PlanStatus.FAILED) -> PlanResult:
    """A result with no trajectory, success False, the reason and how it ended."""
    empty = np.zeros((0,))
    k = 12 * len(scene.bodies)
    return PlanResult(
        success=False, message=message, scene=scene,
        cost_name=settings.cost if settings else "", cost_value=float("nan"),
        step_length=settings.step_length if settings else float("nan"),
        friction_coefficient=settings.friction_coefficient if settings else float("nan"),
        times=empty, q=np.zeros((0, k)), tau=np.zeros((0, 0)),
        joint_angle_names=angle_names(scene), joint_angles=np.zeros((0, 0)),
        joint_velocities=np.zeros((0, 0)), joint_accelerations=np.zeros((0, 0)), phases=(), active_contacts=(), contact_forces={},
        roll_moments={},
        generalized_force=np.zeros((0, k)), kinetic_energy=empty, potential_energy=empty,
        phase_scaling=empty, duration=float("nan"),
        stats=SolverStats(status="not solved", iterations=0, solve_time=0.0), status=status,
    )
