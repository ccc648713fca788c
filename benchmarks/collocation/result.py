"""From a collocation solution to the product's `PlanResult`, so that the project's own
checks (`gait_planner.verify`: recording checks, physical checks, the Pinocchio
certificate) and the simulators run on it exactly as on a DMOCC plan.

Nodes are the knots 0..K plus one node K+1, the mirror image of knot 1 (shifted by the
step length): nodes N-1 = K and N = K+1 are then the images of nodes 0 and 1 as in the
product (paper eqs. 7-9), and the half cycle lasts t_K. What each field holds:

* q: q(theta) at the knots (exact: every internal and joint constraint to round-off);
* tau: the knot torques (linear in time between knots, as the product's node torques);
* joint_velocities, joint_accelerations: the collocation's own w and a (joint entries;
  not the product's central differences); at an impact knot the values after it;
* contact_forces, roll_moments, active_contacts, phases: at knot j those of the phase of
  interval j (at a switch the new phase's: a released point is not listed). The
  collocation's force is a function of time with a jump at switches; where a plastic
  impact acts (impulse Lambda, N s) the node's force is lambda + Lambda / w_j with
  w_j = (h_{j-1} + h_j)/2, the impulse spread over the node's dual interval as the
  product's node force carries it, so that the central differences of the verifier see
  the velocity jump and the force that makes it. Node 0 is the image of node K, node K+1
  of node 1 (`ocp.solution._mirror_forces`);
* generalized_force: w_n B^T(q_n) tau_n (N s), the product's definition (docs/design.md section
  7), so the actuation checks read the torques the same way; it is not a quantity of the
  collocation's equations, which apply tau continuously;
* kinetic_energy: 1/2 w^T M(theta) w at the knots (after impacts), not interval averages;
* settings "impacts": per plastic impact "knot:T before:T after:largest contact speed
  after" (J, J, m/s), comma-separated;
* cost_value: the collocation's own J (Simpson's rule), also in settings; settings
  "kinetic_energy_discrete" holds the product's formula sum_n h_n 1/2 |dq/h_n|_M^2 on the
  knots, which is what the verifier recomputes.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from benchmarks.collocation.transcription import CollocationTranscription
from gait_planner.model.angles import angle_names
from gait_planner.ocp.solution import (CONSTRAINT_LIMIT, SOLVED, STATUS_WORDS, _mirror_forces,
                                       violations)
from gait_planner.result import PlanResult, SolverStats


def _extractor(tr: CollocationTranscription) -> ca.Function:
    K, phase_of = tr.K, tr.mesh.phase_of_interval
    forces = [tr.knot_forces[(phase_of[j], j - tr.mesh.starts[phase_of[j]])] for j in range(K)]
    forces.append(tr.knot_forces[(len(tr.mesh.phases) - 1, tr.mesh.intervals[-1])])
    accel = [tr.knot_accelerations[(phase_of[j], j - tr.mesh.starts[phase_of[j]])]
             for j in range(K)]
    impulses = [lam for _, lam in tr.impulses.values()]
    parts = tr.cost_parts
    return ca.Function("collocation_extract", [tr.x, tr.p], [
        ca.horzcat(*tr.theta), ca.horzcat(*tr.w), ca.horzcat(*tr.tau), ca.vertcat(*tr.h),
        ca.horzcat(*accel), ca.vertcat(*forces), ca.vertcat(*impulses, ca.DM.zeros(0)),
        parts["kinetic_energy"], parts["torque_squared"],
        ca.horzcat(*[tr.w_minus[j] for j in tr.impulses], ca.DM.zeros(tr.model.n, 0))])


def build_result(tr: CollocationTranscription, x: np.ndarray, p: np.ndarray, g: np.ndarray, *,
                 status: str, iterations: int, solve_time: float, build_time: float,
                 evaluation_time: float, origin: str, sizes: dict[str, int]) -> PlanResult:
    model, mb, s, K = tr.model, tr.mb, tr.settings, tr.K
    scene, step = mb.scene, float(p[0])
    theta, w, tau, h, accel, lam, imp, kinetic, torque, w_minus = (
        np.array(v) for v in _extractor(tr)(x, p))
    impacts = []  # (knot, T before, T after (J), largest contact speed after (m/s))
    for (j, (contacts, _)), before in zip(tr.impulses.items(), w_minus.T):
        C = np.vstack([bc.rows for bc in contacts])
        speed = C @ np.array(model.velocity(theta[:, j], w[:, j])).ravel()
        impacts.append(f"{j}:{float(model.kinetic_energy(theta[:, j], before))!r}:"
                       f"{float(model.kinetic_energy(theta[:, j], w[:, j]))!r}:"
                       f"{float(np.abs(speed).max())!r}")
    h = h.ravel()
    theta, w, tau = theta.T, w.T, tau.T  # (K+1, .)
    # node K+1: the image of knot 1
    theta = np.vstack([theta, np.array(model.mirror(theta[1], step)).ravel()])
    w = np.vstack([w, np.array(model.mirror_velocity(theta[1], w[1])).ravel()])
    tau = np.vstack([tau, tr.B @ tau[1]])
    h = np.concatenate([h, [h[0]]])
    times = np.concatenate([[0.0], np.cumsum(h)])
    q = np.array([np.array(model.configuration(t)).ravel() for t in theta])
    accel = np.vstack([accel.T, [np.array(model.mirror_velocity(theta[j], accel[:, i])).ravel()
                                 for i, j in ((0, 0), (1, 1))]])
    phases = scene.gait.phases
    phase_of = list(tr.mesh.phase_of_interval) + [0, 0]  # nodes K, K+1: images of 0, 1
    node_contacts = [tr.contacts[c] for c in phase_of]
    node_contacts[K] = node_contacts[K + 1] = tr.contacts_after_end
    node_phase = [phases[tr.mesh.phases[c]].name for c in phase_of]
    node_phase[K] = node_phase[K + 1] = phases[-1].name
    active = tuple(tuple(pt for bc in cs for pt in bc.points) for cs in node_contacts)

    forces = {c.name: np.zeros((K + 2, 3)) for c in scene.contacts}
    rolls = {c.body: np.zeros(K + 2) for c in scene.contacts}

    def add(j: int, contacts, values: np.ndarray, factor: float = 1.0):
        inner = 0
        for bc in contacts:
            own = factor * values[inner : inner + bc.n_multipliers]
            inner += bc.n_multipliers
            for name, f in bc.point_forces(own, q[j]).items():
                forces[name][j] += f
            rolls[bc.body][j] += bc.roll_moment(own)

    lam, imp, offset = lam.ravel(), imp.ravel(), 0
    for j in range(K + 1):
        contacts = tr.contacts[phase_of[j]] if j < K else tr.contacts[-1]
        size = sum(bc.n_multipliers for bc in contacts)
        if j < K or K not in tr.impulses:
            add(j, contacts, lam[offset : offset + size])
        offset += size
    if K in tr.impulses:  # node K: the image of knot 0 (the compass: before the impulse)
        _mirror_forces(tr, forces, rolls, 0, K)
    offset = 0
    for j, (contacts, _) in tr.impulses.items():
        size = sum(bc.n_multipliers for bc in contacts)
        add(j, contacts, imp[offset : offset + size], 1.0 / (0.5 * (h[j - 1] + h[j])))
        offset += size
    _mirror_forces(tr, forces, rolls, K, 0)
    _mirror_forces(tr, forces, rolls, 1, K + 1)

    half = 0.5 * (np.concatenate([[0.0], h]) + np.concatenate([h, [0.0]]))
    gen = np.array([half[n] * np.array(mb.actuation(q[n])) @ tau[n] for n in range(K + 2)])
    kinetic_nodes = np.array([float(model.kinetic_energy(t, v)) for t, v in zip(theta, w)])
    dq = np.diff(q[: K + 1], axis=0) / h[:K, None]
    discrete = float(np.sum(h[:K] * 0.5 * np.einsum("ni,i,ni->n", dq, mb.mass_diagonal, dq)))

    viol = violations(tr, g)
    holonomic = max(float(np.abs(np.array(mb.constraints(qn))).max()) for qn in q)
    constraint = max([holonomic] + [v for k, v in viol.items() if k.startswith(
        ("contact_hold", "contact_establish", "pin_x"))])
    dynamics = 1000.0 * max((v for k, v in viol.items() if k.startswith("dynamics")), default=0.0)
    friction = max((v for k, v in viol.items() if "cone" in k), default=0.0)
    worst = max(viol, key=viol.get) if viol else ""
    success = status in SOLVED and max(viol.values(), default=0.0) <= CONSTRAINT_LIMIT
    message = f"IPOPT: {STATUS_WORDS.get(status, status)} ({status}) after {iterations} iterations"
    if not success:
        message += f"; most violated: {worst} ({viol.get(worst, 0.0):.3e})"
    kinetic, torque = float(kinetic.item()), float(torque.item())
    na = mb.nt
    return PlanResult(
        success=success, message=message, scene=scene, cost_name=s.cost,
        cost_value=kinetic if s.cost == "kinetic_energy" else torque, step_length=step,
        friction_coefficient=float(p[1]), times=times, q=q, tau=tau,
        joint_angle_names=angle_names(scene), joint_angles=theta[:, -na:],
        joint_velocities=w[:, -na:], joint_accelerations=accel[:, -na:] if na else accel,
        phases=tuple(node_phase), active_contacts=active, contact_forces=forces,
        roll_moments=rolls, generalized_force=gen, kinetic_energy=kinetic_nodes,
        potential_energy=q @ model.gravity_gradient,
        phase_scaling=x[tr.variables.index("sigma")].copy(), duration=float(times[K]),
        stats=SolverStats(
            status=status, iterations=iterations, solve_time=solve_time, build_time=build_time,
            evaluation_time=evaluation_time, max_constraint_violation=constraint,
            max_dynamics_residual=dynamics, max_friction_violation=friction,
            most_violated=worst),
        settings={
            "method": "Hermite-Simpson direct collocation, minimal coordinates "
                      "(benchmarks.collocation)",
            "periodicity": "nodes K, K+1 mirror knots 0, 1 (paper eqs. 7-9); node K+1 is "
                           "the image of knot 1",
            "initial_guess": origin,
            "collocation_intervals_per_phase": ",".join(map(str, tr.mesh.intervals)),
            "intervals_per_phase": ",".join(str(i) for i in s.intervals),
            "base_time_step": repr(s.base_time_step),
            "scaling_bounds": ",".join(repr(b) for b in s.scaling_bounds),
            "torque_regularisation": repr(s.torque_regularisation),
            "foot_half_width": repr(s.foot_half_width),
            "strike_speed_max": repr(s.strike_speed_max),
            "speed": repr(s.speed),
            "kinetic_energy": repr(kinetic), "torque_squared": repr(torque),
            "kinetic_energy_discrete": repr(discrete),
            "impacts": ",".join(impacts),
            **{key: str(value) for key, value in sizes.items()},
        },
    )
