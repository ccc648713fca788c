"""The continuous-dynamics certificate on a robot's own URDF (a scene drafted from it).

A scene drafted by `gait_planner.model.urdf_import` is the URDF's legs with every other
joint locked and merged, its right side written as the left's mirror image within the
importer's tolerances. Its plan is certified here on the URDF itself, not on the draft:
Pinocchio's model of the original text on a free-flyer (``buildModelFromXML``), every joint
of it moving, the planned joints at their published angles, the locked ones at their
locked angle with zero rate. Inverse dynamics as for any plan
(`gait_planner.verify.continuous.inverse_dynamics`: central differences, averaged velocity
terms, the published foot wrenches on the feet's joints), so a certificate that passes
says the published motion, efforts and ground forces are a motion of the robot the user
described — including what the draft changed to make it symmetric.

A link whose URDF gives a mass but a zero inertia tensor (iCub's right leg links in
example-robot-data: the URDF lacks them) has no inertia to certify against: it is
certified with the draft's body (its twin's mirror image, as the draft's header lists),
placed by the robot section's link pose. Every other link is the URDF's.

The locked joints' generalized forces are what holds them: their efforts in the
JointTrajectory (`held_efforts`). At a node where a contact is established the base's
velocity jumps and central differences turn the impact's impulse into an effort divided
by the node's time step (G1's waist yaw: 104 N m against 15 at its neighbours, issue
#61), which a controller must not feed forward: there the effort published is its
neighbours' mean and the rest is published apart as the impulse, N m s
(`split_impulses`; MultibodyState.held_joint_impulses).
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin

from gait_planner.verify.continuous import (ContinuousCertificate, switch_mask,
                                            effort_names, inverse_dynamics, local_force)
from gait_planner.verify.mechanics import SceneData

__all__ = ["robot_certificate", "split_impulses", "urdf_configurations"]

MISSING_INERTIA = 1e-12  # kg m^2: a link whose URDF inertia is this small has none


def _set(model: pin.Model, q: np.ndarray, name: str, angle: float) -> None:
    joint = model.joints[model.getJointId(name)]
    if joint.nq == 2:  # continuous: (cos, sin)
        q[joint.idx_q:joint.idx_q + 2] = np.cos(angle), np.sin(angle)
    else:
        q[joint.idx_q] = angle


def split_impulses(held: np.ndarray, times: np.ndarray,
                   active_contacts: Sequence[Sequence[str]]) -> tuple[np.ndarray, np.ndarray]:
    """(efforts, impulses), each like `held` (N+1, m) N m and N m s: at every node n in
    1..N-1 where a contact is established (not active at n-1), the effort becomes the mean
    of its neighbours' and the impulse (held_n - that mean) w_n, w_n = (t_{n+1} -
    t_{n-1}) / 2; zero impulse elsewhere (module docstring)."""
    efforts, impulses = np.array(held, dtype=float), np.zeros_like(held, dtype=float)
    for n in range(1, len(times) - 1):
        if set(active_contacts[n]) - set(active_contacts[n - 1]):
            mean = 0.5 * (efforts[n - 1] + efforts[n + 1])
            impulses[n] = (efforts[n] - mean) * 0.5 * (times[n + 1] - times[n - 1])
            efforts[n] = mean
    return efforts, impulses


def urdf_configurations(scene: SceneData, model: pin.Model, q: np.ndarray,
                        angles: np.ndarray) -> list[np.ndarray]:
    """The URDF configurations (model.nq,) of a drafted scene's nodes: the base link placed
    by the root body's centre of mass and directors in q (N+1, 12 nb) (`SceneData.robot_root`),
    the planned joints at their angles (N+1, na) (`effort_names` order), the locked ones at
    their locked angle."""
    names, locked = effort_names(scene), dict(scene.robot_locked or {})
    position, rotation = scene.robot_root
    root = scene.body_index(scene.root)
    configs = []
    for row, angle_row in zip(q, angles):
        phi, D = row[12 * root:12 * root + 3], row[12 * root + 3:12 * root + 12].reshape(3, 3).T
        U, _, Vt = np.linalg.svd(D @ rotation)  # nearest rotation (round-off)
        config = pin.neutral(model)
        config[:3], config[3:7] = phi + D @ position, pin.Quaternion(U @ Vt).coeffs()
        for name, angle in zip(names, angle_row):
            _set(model, config, name, float(angle))
        for name, angle in locked.items():
            _set(model, config, name, angle)
        configs.append(config)
    return configs


def _complete_inertias(model: pin.Model, scene: SceneData) -> None:
    """Give each joint whose URDF inertia is missing (a zero tensor, `MISSING_INERTIA`,
    with its fixed links merged) and which carries a scene body the body's mass and
    inertia, in its frame through the robot section's link pose (module docstring)."""
    bodies = {b.name: b for b in scene.bodies}
    for frame in model.frames:
        joint = int(frame.parentJoint)
        body = bodies.get(frame.name)
        if (frame.type != pin.FrameType.BODY or body is None or joint < 1
                or np.abs(model.inertias[joint].inertia).max() > MISSING_INERTIA
                or not frame.placement.isIdentity()):  # the joint's own link
            continue
        position, rotation = scene.robot_links[frame.name]  # the link frame in the body's
        model.inertias[joint] = pin.Inertia(body.mass, -rotation.T @ position,
                                            rotation.T @ np.diag(body.inertia) @ rotation)


def robot_certificate(scene: SceneData, urdf: str, times: np.ndarray, q: np.ndarray,
                      angles: np.ndarray, efforts: np.ndarray,
                      foot_wrenches: Mapping[str, np.ndarray],
                      active_contacts: Sequence[Sequence[str]],
                      wrench_source: str = "recorded"
                      ) -> tuple[ContinuousCertificate, dict[str, np.ndarray]]:
    """(certificate, raw held efforts) of a drafted scene's plan on its URDF text `urdf`
    (the impacts' impulses still in them: `split_impulses`).

    times (N+1,) s; q (N+1, 12 nb) director coordinates (the root's COM and directors place
    the base link: `SceneData.robot_root`); angles, efforts (N+1, na) rad, N m in the order
    of `effort_names(scene)` (the URDF's joints); foot_wrenches: link -> (N+1, 6) ground
    force and moment about the world origin (world); held efforts: locked joint ->
    (N+1,) N m, nodes 0 and N taking their neighbours' values (central differences need
    both neighbours). ValueError naming a joint the URDF lacks or neither plans nor locks."""
    if scene.robot_root is None:
        raise ValueError(f"scene {scene.name!r} has no robot: section (not drafted from a URDF)")
    times, q, angles, efforts = (np.asarray(a, dtype=float) for a in (times, q, angles, efforts))
    names, locked = effort_names(scene), dict(scene.robot_locked or {})
    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    model.gravity = pin.Motion(np.array([0.0, 0.0, -scene.gravity]), np.zeros(3))
    _complete_inertias(model, scene)
    moving = [model.names[j] for j in range(2, model.njoints)]
    unknown = [n for n in list(names) + list(locked) if n not in moving]
    loose = [n for n in moving if n not in names and n not in locked]
    if unknown or loose:
        raise ValueError(f"the URDF does not match scene {scene.name!r}: "
                         + (f"no joints {unknown}" if unknown else
                            f"joints {loose} are neither planned nor locked"))
    configs = urdf_configurations(scene, model, q, angles)
    root = scene.body_index(scene.root)
    joint_of = {body: model.frames[model.getFrameId(body)].parentJoint for body in foot_wrenches}

    def external(n: int, data) -> list:
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        for body, wrench in foot_wrenches.items():
            placement = data.oMi[joint_of[body]]
            fext[joint_of[body]] = local_force(placement.rotation, placement.translation,
                                               wrench[n])
        return fext

    v_index = {n: model.joints[model.getJointId(n)].idx_v for n in moving}
    data = model.createData()
    torque, force, moment, held = [], [], [], []
    for n, tau in enumerate(inverse_dynamics(model, configs, times, external), start=1):
        pin.forwardKinematics(model, data, configs[n])
        base = data.oMi[1]
        f, m_origin = base.rotation @ tau[:3], base.rotation @ tau[3:6]
        com = q[n, 12 * root:12 * root + 3]
        force.append(np.linalg.norm(f))
        moment.append(np.linalg.norm(m_origin + np.cross(base.translation - com, f)))
        torque.append([tau[v_index[name]] for name in names])
        held.append([tau[v_index[name]] for name in locked])
    error = np.array(torque) - efforts[1:-1]
    peak = float(np.abs(efforts).max()) or 1.0
    held = np.array(held).reshape(len(torque), len(locked))
    held = np.vstack([held[:1], held, held[-1:]])
    weight = sum(inertia.mass for inertia in model.inertias) * scene.gravity
    cert = ContinuousCertificate(
        scene=f"{scene.name} on its URDF", planar=False, nodes=np.arange(1, len(q) - 1),
        times=times[1:-1], joint_names=names, torque_error=error,
        torque_error_relative=error / peak, base_force=np.array(force),
        base_moment=np.array(moment), near_switch=switch_mask(active_contacts)[1:-1],
        peak_effort=peak, weight=weight, wrench_source=wrench_source)
    return cert, {name: held[:, i] for i, name in enumerate(locked)}
