"""The checks of one decoded recording (the package docstring lists them)."""

from __future__ import annotations

import math

import numpy as np

from gait_planner.io.mcap_reader import RecordedPlan
from gait_planner.verify.mechanics import MIRROR, Mechanics, SceneData, parse_scene
from gait_planner.verify.actuation import (effort_couples, effort_slots, joint_couples,
                                           periodic_torque_error)
from gait_planner.verify.recorded import certificate_of_recording
from gait_planner.verify.ground import RecordedGround
from gait_planner.verify.joined import verify_joined
from gait_planner.verify.transition import verify_transition
from gait_planner.verify.effort_limits import effort_limit_failures, effort_shares
from gait_planner.verify.legs import judge_legs, legs_of_recording
from gait_planner.verify.physical import check_physical
from gait_planner.verify.limits import LIMITS
from gait_planner.verify.report import VerificationReport


def _norm(v) -> float:
    return float(np.linalg.norm(v))


def _safe_ratio(a: float, b: float) -> float:
    return a / b if b > 0 else (0.0 if a == 0 else math.inf)


def _metadata_float(meta: dict, key: str) -> float:
    try:
        return float(meta[key])
    except (KeyError, ValueError):
        return math.nan


def verify_plan(rec: RecordedPlan) -> VerificationReport:
    """Check an already decoded recording (module docstring); a recording of several
    joined half cycles goes through `gait_planner.verify.joined`."""
    if "transition_nodes" in rec.metadata:
        return verify_transition(rec, verify_plan)
    if int(rec.metadata.get("steps", "1")) > 1:
        return verify_joined(rec, verify_plan)
    scene = parse_scene(rec.scene_text)
    mech = Mechanics(scene)
    meta = rec.metadata
    ground = RecordedGround.of(meta)
    normal = ground.normal
    failures: list[str] = []
    notes: list[str] = []
    L = LIMITS

    def fail(text: str) -> None:
        failures.append(text)

    q = np.asarray(rec.q, dtype=float)
    times = np.asarray(rec.times, dtype=float)
    n_nodes = q.shape[0]
    N = n_nodes - 1
    body_names = tuple(b.name for b in scene.bodies)
    if tuple(rec.body_names) != body_names:
        raise ValueError(f"{rec.path}: recorded bodies {rec.body_names} differ from the "
                         f"attached scene's {body_names}")
    if q.shape != (n_nodes, mech.k) or N < 3:
        raise ValueError(f"{rec.path}: q has shape {q.shape}; expected (N+1, {mech.k}), N >= 3")
    gen = np.asarray(rec.generalized_force, dtype=float)
    planner_success = meta.get("success", "true") == "true"
    if not planner_success:
        fail(f"the planner reported failure: {meta.get('message', '')}")
    h = np.diff(times)
    if not np.all(h > 0):
        fail(f"times are not strictly increasing (first bad interval "
             f"{int(np.argmin(h > 0))})")
        h = np.where(h > 0, h, np.nan)
    if not np.array_equal(rec.nodes, np.arange(n_nodes)):
        fail("the state messages are not numbered 0..N in order")

    # ---- holonomic constraints
    groups = mech.groups
    g = np.array([mech.constraint_values(qn) for qn in q])
    sizes = np.cumsum([0] + [s for _, s in groups])
    worst = {name: (float(np.abs(g[:, a:b]).max()), int(np.abs(g[:, a:b]).max(axis=1).argmax()))
             for (name, _), a, b in zip(groups, sizes, sizes[1:])}
    internal = worst["internal"][0]
    joint_names = [name for name, _ in groups if name.startswith("joint ")]
    joint = max((worst[n][0] for n in joint_names), default=0.0)
    planar = worst.get("planar root", (0.0, 0))[0]
    for name, (value, node) in worst.items():
        if value > L["constraint"]:
            fail(f"{name} constraints are violated by {value:.3e} at node {node} "
                 f"(limit {L['constraint']:.0e})")

    # ---- contacts
    held = [tuple(rec.active_contacts[n]) for n in range(N)]  # interval n
    C = {name: mech.contact_matrix(name) for name in scene.contacts}
    unknown = {c for cs in rec.active_contacts for c in cs} - set(C)
    if unknown:
        raise ValueError(f"{rec.path}: active contacts {sorted(unknown)} are not in the scene")
    drift = height = roll = 0.0
    drift_at = height_at = roll_at = None
    for n in range(N):
        bodies_points: dict[str, list[str]] = {}
        for c in held[n]:
            bodies_points.setdefault(scene.contacts[c][0], []).append(c)
            x0, x1 = C[c] @ q[n], C[c] @ q[n + 1]
            if _norm(x1 - x0) > drift:
                drift, drift_at = _norm(x1 - x0), (c, n)
            for node, x in ((n, x0), (n + 1, x1)):  # on the ground: its height is 0
                off = abs(float(ground.above(x)))
                if off > height:
                    height, height_at = off, (c, node)
        for body, points in bodies_points.items():
            if len(points) < 2:
                continue
            s = mech.start(body)
            move = float(np.abs(q[n + 1, s:s + 12] - q[n, s:s + 12]).max())
            if move > drift:
                drift, drift_at = move, (f"{body} (full contact)", n)
            if not scene.planar:
                for node in (n, n + 1):  # n . d2 = 0: flat on the ground
                    tilt = abs(float(normal @ q[node, s + 6:s + 9]))
                    if tilt > roll:
                        roll, roll_at = tilt, (body, node)
    if drift > L["contact"]:
        fail(f"held contact {drift_at[0]} moves by {drift:.3e} m over interval {drift_at[1]} "
             f"(limit {L['contact']:.0e} m)")
    if height > L["contact"]:
        fail(f"held contact {height_at[0]} is {height:.3e} m off the ground at node "
             f"{height_at[1]} (limit {L['contact']:.0e} m)")
    if roll > L["contact"]:
        fail(f"{roll_at[0]} in full contact is not flat at node {roll_at[1]}: n . d2 = "
             f"{roll:.3e} (limit {L['contact']:.0e})")
    point_error = 0.0
    for n in range(n_nodes):
        names = tuple(rec.contact_names[n])
        if set(names) != set(rec.active_contacts[n]):
            fail(f"node {n}: contact_forces lists {names}, the state message "
                 f"{tuple(rec.active_contacts[n])}")
        for c, x in zip(names, rec.contact_points[n]):
            point_error = max(point_error, _norm(x - C[c] @ q[n]))
    if point_error > L["contact"]:
        fail(f"published contact points differ from phi + X_i d_i by {point_error:.3e} m")
    z_all = np.array([[ground.above(C[c] @ q[n]) for c in C] for n in range(n_nodes)])
    lowest = float(z_all.min())
    if lowest < -L["ground"]:
        n, i = np.unravel_index(int(z_all.argmin()), z_all.shape)
        text = (f"contact point {list(C)[i]} is {-lowest:.3e} m below the ground at node {n}")
        if scene.options.get("ground_clearance", True) is False:
            notes.append(text + " (the scene sets ground_clearance: false)")
        else:
            fail(text + f" (limit {L['ground']:.0e} m)")

    # ---- forces
    mu = _metadata_float(meta, "friction_coefficient")
    forces = [dict(zip(rec.contact_names[n], np.asarray(rec.contact_force_vectors[n])))
              for n in range(n_nodes)]
    min_fz, ratio, excess = math.inf, 0.0, -math.inf
    force_fail = None
    for n in range(n_nodes):
        net: dict[str, np.ndarray] = {}
        for c, F in forces[n].items():
            fn = float(normal @ F)
            if fn < min_fz:
                min_fz = fn
            if fn < -L["force"] * max(1.0, _norm(F)) and force_fail is None:
                force_fail = f"contact {c} pulls on the ground at node {n}: n . F = {fn:.6g} N"
            body = scene.contacts[c][0]
            net[body] = net.get(body, np.zeros(3)) + F
        for body, F in net.items():  # the cone about the ground's normal n
            fn, tangential = float(normal @ F), float(ground.tangential(F))
            ratio = max(ratio, _safe_ratio(tangential, mu * fn) if fn > 0 else
                        (math.inf if tangential > 0 else 0.0))
            over = tangential - mu * fn
            excess = max(excess, over)
            if over > L["force"] * max(1.0, _norm(F)):
                fail(f"the ground force on {body} at node {n} leaves the friction cone: "
                     f"|F_t| = {tangential:.6g} N > mu n . F = {mu * fn:.6g} N (mu = {mu:g})")
    if force_fail:
        fail(force_fail)
    if min_fz == math.inf:
        min_fz = math.nan

    # ---- discrete Euler-Lagrange equations
    roll_bodies = []  # per node: bodies in 3D full contact
    worst_res, worst_abs, worst_node = 0.0, 0.0, -1
    max_roll, max_offset = 0.0, 0.0
    for n in range(1, N):
        w = 0.5 * (h[n - 1] + h[n])
        d2 = mech.d2_ld(q[n - 1], q[n], h[n - 1])
        d1 = mech.d1_ld(q[n], q[n + 1], h[n])
        contact = np.zeros(mech.k)
        per_body: dict[str, list[str]] = {}
        for c, F in forces[n].items():
            contact += w * C[c].T @ F
            per_body.setdefault(scene.contacts[c][0], []).append(c)
        full = [b for b, pts in per_body.items() if len(pts) == 2 and not scene.planar]
        roll_bodies.append(full)
        E = np.zeros((mech.k, len(full)))
        for i, body in enumerate(full):  # the roll row n . d2 (e_z . d2 on level ground)
            E[mech.start(body) + 6:mech.start(body) + 9, i] = normal
        b = d2 + d1 + gen[n] + contact
        A = np.hstack([mech.constraint_jacobian(q[n]).T, -w * E])
        x, *_ = np.linalg.lstsq(A, b, rcond=None)
        res = b - A @ x
        moments = x[mech.m:]
        contact_total = contact + w * E @ moments
        scale = max(_norm(d2), _norm(d1), _norm(gen[n]), _norm(contact_total))
        rel = _safe_ratio(_norm(res), scale)
        if rel > worst_res or worst_node < 0:
            worst_res, worst_node = rel, n
        worst_abs = max(worst_abs, _norm(res))
        for body, m_roll in zip(full, moments):
            max_roll = max(max_roll, abs(float(m_roll)))
            fz = sum(float(normal @ forces[n][c]) for c in per_body[body])
            max_offset = max(max_offset, _safe_ratio(abs(float(m_roll)), fz))
    if worst_res > L["dynamics"]:
        fail(f"the discrete Euler-Lagrange equation of node {worst_node} has a relative "
             f"residual {worst_res:.3e} (limit {L['dynamics']:.0e}) with least-squares "
             f"multipliers")

    # ---- actuation
    gen_scale = float(np.abs(gen).max()) or 1.0
    phi_rows = np.concatenate([np.arange(12 * i, 12 * i + 3) for i in range(mech.nb)])
    act_phi = float(np.abs(gen[:, phi_rows]).max()) / gen_scale
    if act_phi > L["actuation"]:
        fail(f"generalized_force has phi entries of {act_phi:.3e} (relative; limit "
             f"{L['actuation']:.0e}): actuation is not internal")
    couples = np.zeros((n_nodes, mech.nb, 3))  # body couples m_b = sum_i d_i x f_di
    form = 0.0
    for n in range(n_nodes):
        for bi, body in enumerate(body_names):
            s = 12 * bi
            D = [q[n, s + 3 + 3 * i:s + 6 + 3 * i] for i in range(3)]
            f = [gen[n, s + 3 + 3 * i:s + 6 + 3 * i] for i in range(3)]
            m = sum(np.cross(D[i], f[i]) for i in range(3))
            couples[n, bi] = m
            form = max(form, max(_norm(f[i] - 0.5 * np.cross(m, D[i])) for i in range(3)))
    form /= gen_scale
    if form > L["actuation"]:
        fail(f"generalized_force is not made of couples 1/2 m x d_i: off by {form:.3e} "
             f"(relative; limit {L['actuation']:.0e})")
    couple_scale = float(np.abs(couples).max()) or 1.0
    net = float(np.abs(couples.sum(axis=1)).max()) / couple_scale
    if net > L["actuation"]:
        node = int(np.abs(couples.sum(axis=1)).max(axis=1).argmax())
        fail(f"the actuation has a net moment at node {node}: {net:.3e} of the largest body "
             f"couple (limit {L['actuation']:.0e})")
    couples_j = joint_couples(scene, couples)  # (N+1, nj, 3)
    off_axis, mismatch = 0.0, 0.0
    off_at = mismatch_at = None
    for n in range(n_nodes):
        for ji, j in enumerate(scene.joints):
            if j.axis is not None:
                axis = mech.directors(q[n], j.parent) @ j.axis
                m = couples_j[n, ji]
                off = _norm(m - (m @ axis) * axis) / couple_scale
                if off > off_axis:
                    off_axis, off_at = off, (j.name, n)
    if off_axis > L["actuation"]:
        fail(f"the couple of revolute joint {off_at[0]} at node {off_at[1]} is not along its "
             f"axis: off by {off_axis:.3e} (relative; limit {L['actuation']:.0e})")
    effort = np.asarray(rec.effort, dtype=float)
    slots = effort_slots(scene, tuple(rec.joint_names))
    torques = None  # (N+1, nj, 3): the couple of node n in its parent's directors
    if isinstance(slots, str):
        fail(slots)
    elif effort.shape != (n_nodes, len(rec.joint_names)):
        fail(f"JointTrajectory effort has shape {effort.shape}, expected "
             f"({n_nodes}, {len(rec.joint_names)})")
    else:
        couples_e = effort_couples(scene, mech, q, effort, slots)  # (N+1, nj, 3)
        torques = np.array([[mech.directors(q[n], j.parent).T @ couples_e[n, ji]
                             for ji, j in enumerate(scene.joints)] for n in range(n_nodes)])
        half = 0.5 * (np.concatenate([[0.0], h]) + np.concatenate([h, [0.0]]))  # w_n
        for n in range(n_nodes):
            for ji, j in enumerate(scene.joints):
                expected = half[n] * couples_e[n, ji]
                error = _norm(couples_j[n, ji] - expected) / couple_scale
                if error > mismatch:
                    mismatch, mismatch_at = error, (j.name, n)
        if mismatch > L["actuation"]:
            fail(f"the recorded efforts of joint {mismatch_at[0]} do not produce the recorded "
                 f"generalized_force at node {mismatch_at[1]}: off by {mismatch:.3e} "
                 f"(relative; limit {L['actuation']:.0e})")

    # ---- periodicity (a transition's recording declares none: `verify.transition`)
    periodic = "N-1" in meta.get("periodicity", "N-1")
    if not periodic:
        notes.append(f"the recording declares periodicity {meta['periodicity']!r}; the checks "
                     f"that pair nodes N-1, N with 0, 1 (paper eqs. 7-9) are not run")
    step = _metadata_float(meta, "step_length")
    rise = ground.rise(step)
    period = periodic_force = periodic_torque = math.nan
    if periodic:
        if ground.stairs and not abs(ground.tread - step) <= L["time"] * step:
            fail(f"the stairs' tread depth {ground.tread!r} m (metadata stair_tread) differs from "
                 f"the step length {step!r} m: the mirror images would not land a tread further "
                 f"on each half cycle")
        period = max(float(np.abs(q[N - 1] - mech.mirror(q[0], step, rise)).max()),
                     float(np.abs(q[N] - mech.mirror(q[1], step, rise)).max()))
        if not period <= L["periodicity"]:
            fail(f"nodes N-1, N are not the mirror images of nodes 0, 1 shifted by the step "
                 f"length {step:g} m and the rise {rise:g} m ({ground.describe()}): off by "
                 f"{period:.3e} m (limit {L['periodicity']:.0e} m)")
        partner = scene.contact_partners
        force_scale = max([1.0] + [_norm(F) for fs in forces for F in fs.values()])
        periodic_force = 0.0
        for src, dst in ((N - 1, 0), (1, N)):
            expected = {partner[c]: MIRROR * F for c, F in forces[src].items()}
            if set(expected) != set(forces[dst]):
                fail(f"node {dst} lists contacts {sorted(forces[dst])}, the mirror image of node "
                     f"{src} {sorted(expected)}")
                continue
            for c, F in expected.items():
                periodic_force = max(periodic_force, _norm(forces[dst][c] - F) / force_scale)
        if periodic_force > L["periodic_force"]:
            fail(f"the contact forces of nodes 0, N are not the mirror images of those of nodes "
                 f"N-1, 1: off by {periodic_force:.3e} (relative; limit {L['periodic_force']:.0e})")
        periodic_torque = 0.0
        if torques is not None:
            periodic_torque = periodic_torque_error(scene, couples_e, N)
            if periodic_torque > L["actuation"]:
                fail(f"the joint couples of nodes N-1, N are not the mirror images of those of "
                     f"nodes 0, 1: off by {periodic_torque:.3e} (relative; limit "
                     f"{L['actuation']:.0e})")

    # ---- time, cost, energy
    duration = float(times[N - 1] - times[0])
    duration_recorded = _metadata_float(meta, "duration")
    if not abs(duration - duration_recorded) <= L["time"] * max(1.0, abs(duration)):
        fail(f"metadata duration {duration_recorded!r} s differs from t_(N-1) - t_0 = "
             f"{duration!r} s")
    speed, pace = _metadata_float(meta, "speed"), _safe_ratio(step, duration)
    if speed > 0 and not abs(pace - speed) <= L["time"] * speed:  # 0 or absent: free
        fail(f"the half cycle's mean speed step_length / (t_(N-1) - t_0) = {pace!r} m/s "
             f"differs from the requested speed {speed!r} m/s (metadata speed; relative "
             f"limit {L['time']:.0e})")
    cost_name = meta.get("cost", "")
    if cost_name == "kinetic_energy":
        v = np.diff(q, axis=0)[: N - 1] / h[: N - 1, None]
        cost = float(np.sum(h[: N - 1] * 0.5 * np.einsum("ni,i,ni->n", v, mech.mass_diagonal,
                                                         v)))
    elif cost_name == "torque_squared" and torques is not None:
        # |tau|^2 of the planner's node torques (parent-director components, revolute:
        # about the axis) = |couple|^2 of every joint, trapezoidal over t_0 .. t_(N-1)
        squares = np.sum(torques[:N] ** 2, axis=(1, 2))
        cost = float(np.sum(h[: N - 1] * 0.5 * (squares[: N - 1] + squares[1:N])))
    else:
        cost = math.nan
        fail(f"unknown cost name {cost_name!r} in the metadata")
    cost_recorded = _metadata_float(meta, "cost_value")
    cost_error = abs(cost - cost_recorded) / max(abs(cost), 1e-300)
    if not cost_error <= L["cost"]:
        fail(f"metadata cost_value {cost_recorded!r} differs from the recomputed {cost_name} "
             f"{cost!r} (relative {cost_error:.3e}, limit {L['cost']:.0e})")
    excesses: list[float] = []
    interval_error = _interval_error(scene, rec, meta, h, fail, excesses)
    v_rec = np.asarray(rec.potential_energy, dtype=float)
    v_own = np.array([mech.potential_energy(qn) for qn in q])
    energy_error = float(np.abs(v_rec - v_own).max()) / max(1.0, float(np.abs(v_own).max()))
    if energy_error > L["energy"]:
        fail(f"recorded potential energy differs from sum m g phi_z by {energy_error:.3e} "
             f"(relative)")

    physical = check_physical(rec, scene, mu)
    failures += physical.failures
    shares = effort_shares(rec.urdf, rec.joint_names, effort) \
        if scene.robot_root is not None else None
    failures += effort_limit_failures(shares or {})
    continuous = certificate_of_recording(rec)
    failures += [f"continuous dynamics: {f}" for f in continuous.failures]
    legs = legs_of_recording(rec, scene)
    judge_legs(legs, failures, notes)

    return VerificationReport(
        path=str(rec.path), scene=scene.name, ground=ground.describe(), cost_name=cost_name,
        n_nodes=n_nodes, planner_success=planner_success,
        max_internal_violation=internal, max_joint_violation=joint,
        max_planar_violation=planar, max_contact_drift=drift, max_contact_height=height,
        max_full_contact_roll=roll, max_contact_point_error=point_error,
        min_contact_point_height=lowest, max_dynamics_residual=worst_res,
        worst_dynamics_node=worst_node, max_dynamics_residual_absolute=worst_abs,
        max_roll_moment=max_roll, max_roll_offset=max_offset,
        max_actuation_phi=act_phi, max_couple_form_error=form, max_net_moment=net,
        max_revolute_off_axis=off_axis, max_effort_mismatch=mismatch,
        min_normal_force=min_fz, max_friction_ratio=ratio, max_friction_excess=excess,
        friction_coefficient=mu, max_periodicity_error=period,
        max_periodic_force_error=periodic_force, max_periodic_torque_error=periodic_torque,
        cost_recorded=cost_recorded, cost_recomputed=cost, cost_relative_error=cost_error,
        duration_recorded=duration_recorded, duration_recomputed=duration,
        max_interval_error=interval_error,
        max_scaling_bound_excess=max(excesses, default=math.nan),
        max_potential_energy_error=energy_error,
        failures=tuple(failures), notes=tuple(notes), physical=physical, continuous=continuous,
        effort_shares=shares, legs=legs,
    )


def _interval_error(scene: SceneData, rec: RecordedPlan, meta: dict, h: np.ndarray,
                    fail, excesses: list) -> float:
    """Interval lengths vs base_time_step * sigma of their phase; sigma within bounds. A
    transition's phases (metadata ``transition_half_cycles``, `ocp.transition.
    transition_scene`) are "<phase>~<j>" from its second half cycle on: copy j's sigma is
    the scene's index + (j-1) n_sigma, its contacts mirrored for even j (all flipped once
    more in a motion mirrored, ``transition_mirrored``), and its last interval has a sigma
    of its own, the last; a standing start's phases (``transition_standing``, the scene's
    gait.start) come first and a stop's (``transition_stop``, gait.stop, mirrored after an
    even number of half cycles) last, each with a sigma of its own after the copies'."""
    try:
        sigma = [float(s) for s in meta["phase_scaling"].split(",") if s.strip()]
    except (KeyError, ValueError):
        fail("the metadata holds no readable phase_scaling")
        return math.nan
    bounds = scene.scaling_bounds
    if "scaling_bounds" in meta:
        bounds = tuple(float(b) for b in meta["scaling_bounds"].split(","))
    if bounds:
        excess = max(max(bounds[0] - s, s - bounds[1]) / bounds[1] for s in sigma)
        excesses.append(excess)
        if excess > LIMITS["scaling"]:
            fail(f"phase scaling {sigma} leaves the bounds {bounds} by {excess:.3e} "
                 f"(relative; limit {LIMITS['scaling']:.0e})")
    base = _metadata_float(meta, "base_time_step")
    if math.isnan(base):
        base = scene.base_time_step if scene.base_time_step is not None else math.nan
    if math.isnan(base):
        return math.nan
    error = 0.0
    transition = "transition_half_cycles" in meta
    n_sigma = 1 + max((i for i, _ in scene.phases.values()), default=0)
    flipped = meta.get("transition_mirrored") == "true"
    partner = scene.contact_partners
    phases = {name: (index, contacts, False) for name, (index, contacts) in scene.phases.items()}
    if transition:
        halves = int(meta["transition_half_cycles"])
        ends = [(p, False) for p in scene.start_phases
                if meta.get("transition_standing") == "true"]
        ends += [(p, halves % 2 == 0) for p in scene.stop_phases
                 if meta.get("transition_stop") == "true"]
        phases.update({name: (halves * n_sigma + i, contacts, flip)
                       for i, ((name, contacts), flip) in enumerate(ends)})
    for n, hn in enumerate(h):
        phase, _, copy = rec.phases[n].partition("~")
        if phase not in phases or (copy and not (transition and copy.isdigit())):
            fail(f"node {n} is in phase {rec.phases[n]!r}, which the scene does not declare")
            return math.nan
        index, contacts, flip = phases[phase]
        j = int(copy) if copy else 1
        index += (j - 1) * n_sigma
        if transition and n == len(h) - 1:  # the transition's last interval: its own sigma
            index = len(sigma) - 1
        if transition and (j - 1 + flipped + flip) % 2:
            contacts = tuple(partner[c] for c in contacts)
        if index >= len(sigma):
            fail(f"phase {phase!r} uses sigma_{index + 1}, the metadata gives {len(sigma)}")
            return math.nan
        if set(contacts) != set(rec.active_contacts[n]):
            fail(f"node {n} (phase {phase}) lists contacts {rec.active_contacts[n]}, the "
                 f"phase holds {contacts}")
        error = max(error, abs(hn - base * sigma[index]) / (base * sigma[index]))
    if error > LIMITS["time"]:
        fail(f"interval lengths differ from base_time_step * sigma by {error:.3e} (relative)")
    return error

