"""Checks of a recording that joins K half cycles (metadata ``steps`` = K > 1,
``half_cycle_nodes`` = H = N + 1 of the plan; `gait_planner.ocp.walk_on`).

The first half cycle, nodes 0 .. H-1, gets every check of a single plan (`checks`), its
periodic continuation included. Half cycle k (nodes k (H-2) .. k (H-2) + H-1) must then be
the first one mirrored k times: configurations (mirror about y = 0, k step lengths along x
and k rises of the ground up, `gait_planner.verify.ground`), contact forces (partner points,
y negated), efforts (partner joints; pitch and revolute angles keep their sign, roll and yaw
change it, a joint whose mirror swaps parent and child changes it too) and times (k
half-cycle durations later). Since the first half cycle
satisfies the discrete equations with its mirrored neighbours, so does every join. The
physical checks and the continuous-dynamics certificate run on the whole joined motion.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from gait_planner.verify.recorded import certificate_of_recording
from gait_planner.verify.ground import RecordedGround
from gait_planner.verify.mechanics import MIRROR, Mechanics, SceneData, parse_scene
from gait_planner.verify.physical import check_physical
from gait_planner.verify.limits import LIMITS
from gait_planner.verify.report import VerificationReport


def node_fields(rec, nodes: slice) -> dict:
    """The fields of a recording that hold one entry per node (and per node of a topic's
    log and header times), restricted to `nodes`: changes for `dataclasses.replace`."""
    n = rec.n_nodes
    changes = {}
    for f in dataclasses.fields(rec):
        value = getattr(rec, f.name)
        if isinstance(value, (tuple, np.ndarray)) and len(value) == n and f.name != "body_names":
            changes[f.name] = value[nodes]
        elif isinstance(value, dict) and f.name in ("log_times_ns", "header_stamps_ns"):
            changes[f.name] = {k: (v[nodes] if len(v) == n else v) for k, v in value.items()}
    return changes


def half_cycle(rec, nodes: int):
    """The recording restricted to its first `nodes` nodes (fewer than it has), as one
    plan: metadata steps = 1, the last node's discrete force that of its last interval."""
    changes = node_fields(rec, slice(None, nodes))
    changes["metadata"] = dict(rec.metadata, steps="1")
    # a plan's last node carries the discrete force of its last interval only (f+_{N-1});
    # in the joined motion that node is inner and carries both intervals' (w_n B^T tau_n)
    t = np.asarray(rec.times, dtype=float)
    gen = np.array(rec.generalized_force[:nodes], dtype=float)
    gen[-1] *= (t[nodes - 1] - t[nodes - 2]) / (t[nodes] - t[nodes - 2])
    changes["generalized_force"] = gen
    return dataclasses.replace(rec, **changes)


def angle_mirror(scene: SceneData, names) -> np.ndarray:
    """Signed permutation P (na, na) of the published joint angles (and efforts) under the
    mirror: angles(mirror q) = P angles(q)."""
    names = list(names)
    by_bodies = {(j.parent, j.child): j for j in scene.joints}
    P = np.zeros((len(names), len(names)))
    for j in scene.joints:
        p, c = scene.mirror[j.parent], scene.mirror[j.child]
        partner, swapped = (by_bodies[(p, c)], 1.0) if (p, c) in by_bodies else \
            (by_bodies[(c, p)], -1.0)
        if j.axis is not None:  # a pseudo-vector component: axis n -> -F n (F = diag(1, -1, 1))
            P[names.index(partner.name), names.index(j.name)] = \
                swapped * float((-MIRROR * j.axis) @ partner.axis)
            continue
        for mine, theirs, sign in zip(j.angles, partner.angles, (1.0, -1.0, -1.0)):
            P[names.index(theirs), names.index(mine)] = swapped * sign  # pitch, roll, yaw
    return P


def verify_joined(rec, verify_plan) -> VerificationReport:
    """Check a joined recording (module docstring); `verify_plan` checks one half cycle."""
    meta = rec.metadata
    steps, H = int(meta["steps"]), int(meta["half_cycle_nodes"])
    M = H - 2
    if rec.n_nodes != steps * M + 2:
        raise ValueError(f"{rec.path}: {rec.n_nodes} nodes, but {steps} half cycles of {H} "
                         f"nodes join to {steps * M + 2}")
    first = verify_plan(half_cycle(rec, H))
    scene = parse_scene(rec.scene_text)
    mech = Mechanics(scene)
    step = float(meta["step_length"])
    rise = RecordedGround.of(meta).rise(step)
    P = angle_mirror(scene, rec.joint_names)
    partner = scene.contact_partners
    q0, effort0 = np.asarray(rec.q[:H]), np.asarray(rec.effort[:H])
    forces0 = [dict(zip(rec.contact_names[n], np.asarray(rec.contact_force_vectors[n])))
               for n in range(H)]
    period = rec.times[H - 2] - rec.times[0]
    errors = {"configuration": 0.0, "effort": 0.0, "force": 0.0, "time": 0.0}
    q_k, effort_k, forces_k = q0, effort0, forces0
    for k in range(1, steps):
        q_k = np.array([mech.mirror(row, step, rise) for row in q_k])
        effort_k = effort_k @ P.T
        forces_k = [{partner[c]: MIRROR * f for c, f in node.items()} for node in forces_k]
        nodes = range(k * M, k * M + H)
        errors["configuration"] = max(errors["configuration"],
                                      float(np.abs(rec.q[nodes.start:nodes.stop] - q_k).max()))
        scale = max(1.0, float(np.abs(effort0).max()))
        errors["effort"] = max(errors["effort"], float(np.abs(
            rec.effort[nodes.start:nodes.stop] - effort_k).max()) / scale)
        errors["time"] = max(errors["time"], float(np.abs(
            rec.times[nodes.start:nodes.stop] - rec.times[:H] - k * period).max()))
        for n, expected in zip(nodes, forces_k):
            listed = dict(zip(rec.contact_names[n], np.asarray(rec.contact_force_vectors[n])))
            if set(listed) != set(expected):
                errors["force"] = np.inf
                continue
            for c, f in expected.items():
                errors["force"] = max(errors["force"], float(np.linalg.norm(listed[c] - f))
                                      / max(1.0, float(np.linalg.norm(f))))
    limits = {"configuration": LIMITS["periodicity"], "effort": LIMITS["actuation"],
              "force": LIMITS["periodic_force"], "time": LIMITS["time"]}
    failures = [f for f in first.failures
                if f not in first.physical.failures and not f.startswith("continuous dynamics:")]
    failures += [f"half cycles 2..{steps} are not the mirror images of the first: "
                 f"{what} off by {value:.3e} (limit {limits[what]:.0e})"
                 for what, value in errors.items() if not value <= limits[what]]
    physical = check_physical(rec, scene, float(meta["friction_coefficient"]))
    continuous = certificate_of_recording(rec)
    failures += list(physical.failures)
    failures += [f"continuous dynamics: {f}" for f in continuous.failures]
    notes = list(first.notes) + [
        f"{steps} half cycles of {H} nodes joined by the mirror; every check of one plan ran "
        f"on the first, the joins and the physical and continuous checks on all {rec.n_nodes} "
        f"nodes (largest join differences: " + ", ".join(f"{k} {v:.1e}" for k, v in
                                                           errors.items()) + ")"]
    return dataclasses.replace(first, path=str(rec.path), n_nodes=rec.n_nodes,
                               failures=tuple(failures), notes=tuple(notes),
                               physical=physical, continuous=continuous)
