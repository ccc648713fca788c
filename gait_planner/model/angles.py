"""Joint angles: the output convention, and configurations built from angles.

Let R = [d1 d2 d3] be a body's director triad and R_rel = R_parent^T R_child the relative
rotation of a joint (child directors in parent components); every angle is zero in the
upright pose, where all triads equal the world axes (x forward, y left, z up).

* Spherical joint ``j``: angles (``j_pitch``, ``j_roll``, ``j_yaw``) with
  R_rel = Ry(pitch) Rx(roll) Rz(yaw): pitch about the parent's lateral axis d2 first
  (flexion/extension, the large motion of walking), then roll about the once-rotated d1
  (ab/adduction, inversion/eversion), then yaw about the child's own d3 (axial rotation).
  Positive angles are right-handed rotations: a positive hip pitch swings the foot backward.
  The sequence is singular at roll = +-90 deg (gimbal lock). There `joint_angles` returns
  yaw = 0 and puts the whole rotation about the remaining axis into pitch; at and next to
  it the angles still reproduce R_rel to round-off (tested), but pitch and yaw jump, so no
  optimiser works in them there.
* Revolute joint (knee): one angle, right-handed about the joint axis (knees: about d2, so a
  bent knee has a positive angle): R_rel = Rot(axis, angle) R0 with the joint's zero-angle
  reference R0 (`Joint.reference`; the identity for the built-in walkers, the URDF's zero
  pose for an imported robot, whose angles are then the URDF's).
* Root orientation (for /tf only): R = Rz(yaw) Ry(pitch) Rx(roll).
"""

from __future__ import annotations

import numpy as np

from gait_planner.model.rotations import GIMBAL_LOCK, matrix_rpy, rot_axis, rot_x, rot_y, rot_z
from gait_planner.model.scene import InitialPose, JointType, Scene



def angle_names(scene: Scene) -> tuple[str, ...]:
    """All joint angle names in joint (tree) order; also the order of the torques."""
    return tuple(name for j in scene.joints for name in j.angle_names)


def spherical_rotation(pitch: float, roll: float, yaw: float) -> np.ndarray:
    return rot_y(pitch) @ rot_x(roll) @ rot_z(yaw)


def spherical_angles(R: np.ndarray) -> tuple[float, float, float]:
    """(pitch, roll, yaw) of R = Ry(pitch) Rx(roll) Rz(yaw); roll in [-pi/2, pi/2]
    (`spherical_angles_rows` of one rotation)."""
    pitch, roll, yaw = spherical_angles_rows(np.asarray(R, dtype=float)[None])[0]
    return float(pitch), float(roll), float(yaw)


def spherical_angles_rows(R: np.ndarray) -> np.ndarray:
    """(pitch, roll, yaw) (n, 3) of rotations R (n, 3, 3) = Ry(pitch) Rx(roll) Rz(yaw).

    roll = atan2(-R12, cos(roll)) is accurate to round-off everywhere (arcsin(-R12) is not
    near +-90 deg); yaw is taken from the remainder Rx(roll)^T Ry(pitch)^T R = Rz(yaw), so the
    three angles rebuild R to round-off even next to the gimbal lock, where pitch and yaw
    separately are ill-determined.
    """
    c_roll = np.hypot(R[:, 0, 2], R[:, 2, 2])
    roll = np.arctan2(-R[:, 1, 2], c_roll)
    # gimbal lock: only pitch -/+ yaw is defined; put it all into pitch
    pitch = np.where(c_roll > GIMBAL_LOCK, np.arctan2(R[:, 0, 2], R[:, 2, 2]),
                     np.arctan2(-R[:, 2, 0], R[:, 0, 0]))
    cp, sp, cr, sr = np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    # first column of the remainder: (Ry(pitch)^T R) then Rx(roll)^T, rows 0 and 1
    rest_00 = cp * R[:, 0, 0] - sp * R[:, 2, 0]
    rest_10 = cr * R[:, 1, 0] + sr * (sp * R[:, 0, 0] + cp * R[:, 2, 0])
    return np.stack([pitch, roll, np.arctan2(rest_10, rest_00)], axis=1)


def revolute_angle(R: np.ndarray, axis) -> float:
    """Angle of the rotation R about the unit vector `axis` (R assumed to fix axis)."""
    return float(revolute_angle_rows(np.asarray(R, dtype=float)[None], axis)[0])


def revolute_angle_rows(R: np.ndarray, axis) -> np.ndarray:
    """Angles (n,) of rotations R (n, 3, 3) about the unit vector `axis` (each R assumed to
    fix it): the components of R - R^T give 2 sin(theta) a, the trace 1 + 2 cos(theta)."""
    a = np.asarray(axis, dtype=float)
    w = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]],
                 axis=1)
    return np.arctan2(0.5 * w @ a, 0.5 * (np.trace(R, axis1=1, axis2=2) - 1.0))


def _frames(scene: Scene, q: np.ndarray) -> dict[str, np.ndarray]:
    """Per body its triads (n, 3, 3) of configurations q (n, k)."""
    return {b.name: q[:, 12 * i + 3 : 12 * i + 12].reshape(-1, 3, 3).transpose(0, 2, 1)
            for i, b in enumerate(scene.bodies)}


def joint_angles(scene: Scene, q: np.ndarray) -> np.ndarray:
    """Joint angles (rad) of configurations q: (k,) -> (na,) or (n, k) -> (n, na)."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        return joint_angles(scene, q[None])[0]
    frames = _frames(scene, q)
    out = []
    for joint in scene.joints:
        R = np.einsum("nji,njk->nik", frames[joint.parent], frames[joint.child])
        out.append(spherical_angles_rows(R) if joint.type is JointType.SPHERICAL
                   else revolute_angle_rows(R @ joint.reference.T, joint.axis)[:, None])
    return np.concatenate(out, axis=1) if out else np.zeros((q.shape[0], 0))


def root_angles(R: np.ndarray) -> tuple[float, float, float]:
    """(yaw, pitch, roll) of R = Rz(yaw) Ry(pitch) Rx(roll); pitch in [-pi/2, pi/2]
    (`gait_planner.model.rotations.matrix_rpy`, reversed): the angles rebuild R to
    round-off; at the gimbal lock (pitch = +-90 deg) roll is 0."""
    roll, pitch, yaw = matrix_rpy(R)
    return yaw, pitch, roll


def configuration(scene: Scene, pose: InitialPose | None = None) -> np.ndarray:
    """Director coordinates q (k,) of a pose given by root position/angles and joint angles.

    Satisfies every internal and joint constraint exactly (up to round-off).
    """
    pose = pose or scene.initial_pose
    yaw, pitch, roll = pose.root_angles
    frames = {scene.root.body: (np.asarray(pose.root_position, float),
                                rot_z(yaw) @ rot_y(pitch) @ rot_x(roll))}
    for joint in scene.joints:
        values = pose.joint_angles.get(joint.name, (0.0,) * joint.dof)
        if joint.type is JointType.SPHERICAL:
            R_rel = spherical_rotation(*values)
        else:
            R_rel = rot_axis(np.asarray(joint.axis, float), values[0]) @ joint.reference
        phi_p, D_p = frames[joint.parent]
        D_c = D_p @ R_rel
        rho_p = np.asarray(scene.body(joint.parent).points[joint.parent_point])
        rho_c = np.asarray(scene.body(joint.child).points[joint.child_point])
        frames[joint.child] = (phi_p + D_p @ rho_p - D_c @ rho_c, D_c)
    q = np.zeros(12 * len(scene.bodies))
    for i, b in enumerate(scene.bodies):
        phi, D = frames[b.name]
        q[12 * i : 12 * i + 12] = np.concatenate([phi, D.T.reshape(-1)])
    return q


def pose_of(scene: Scene, q: np.ndarray) -> InitialPose:
    """The pose of director coordinates q (k,): the root body's centre of mass and Cardan
    angles (`root_angles`) and every joint's angles; `configuration` of it is q again, to
    round-off, where q meets the joint constraints."""
    i = [b.name for b in scene.bodies].index(scene.root.body)
    phi, D = q[12 * i : 12 * i + 3], q[12 * i + 3 : 12 * i + 12].reshape(3, 3).T
    values, angles, at = joint_angles(scene, np.asarray(q)[None, :])[0], {}, 0
    for joint in scene.joints:
        angles[joint.name] = tuple(float(v) for v in values[at : at + joint.dof])
        at += joint.dof
    return InitialPose(tuple(float(v) for v in phi), root_angles(D), angles)


def blended(scene: Scene, qa: np.ndarray, qb: np.ndarray, s: float) -> np.ndarray:
    """(k,): the configuration a fraction s in [0, 1] of the way from qa (k,) to qb (k,)
    in pose coordinates (`pose_of`: root position, root angles and joint angles, each
    linearly), so that it meets the joint constraints as `configuration` makes it."""
    a, b = pose_of(scene, qa), pose_of(scene, qb)

    def mix(u, v):
        return tuple((1 - s) * x + s * y for x, y in zip(u, v))

    return configuration(scene, InitialPose(
        mix(a.root_position, b.root_position), mix(a.root_angles, b.root_angles),
        {name: mix(a.joint_angles[name], b.joint_angles[name]) for name in a.joint_angles}))


def conjugate_torques(scene: Scene, angles: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Torques conjugate to the joint angles (N m): tau_angle . angle_rate = power.

    `tau` holds the planner's joint torques (spherical: the couple's components along the
    parent's directors; revolute: about the axis); `angles` the joint angles at the same
    node. For R_rel = Ry(p) Rx(r) Rz(y) the relative angular velocity in parent components
    is e_y p' + Ry(p) e_x r' + Ry(p) Rx(r) e_z y', so the conjugate torques are the couple's
    projections on those three axes. Shapes (na,) or (n, na) for both inputs.
    """
    angles, tau = np.asarray(angles, float), np.asarray(tau, float)
    if angles.ndim == 2:
        return np.array([conjugate_torques(scene, a, t) for a, t in zip(angles, tau)])
    out = tau.copy()
    i = 0
    for joint in scene.joints:
        if joint.type is JointType.SPHERICAL:
            pitch, roll = angles[i], angles[i + 1]
            m = tau[i : i + 3]
            axes = (np.array([0.0, 1.0, 0.0]), rot_y(pitch) @ np.array([1.0, 0.0, 0.0]),
                    rot_y(pitch) @ rot_x(roll) @ np.array([0.0, 0.0, 1.0]))
            out[i : i + 3] = [m @ a for a in axes]
        i += joint.dof
    return out
