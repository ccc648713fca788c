"""Rotation helpers, symbolic (CasADi SX/MX) and numeric (numpy).

Rotation matrices act on column vectors; a body's director triad D = [d1 d2 d3] is the
rotation from body-fixed components to world components.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

# Below this squared angle the Rodrigues coefficients use their Taylor series, so that the
# map and all its derivatives stay finite at zero rotation (|theta| < 1e-2 rad: the
# truncation error of the series used is below 1e-17).
_SMALL_ANGLE_SQ = 1e-4
# cos(middle angle) at or below this counts as gimbal lock (within ~1e-15 rad of 90 deg).
GIMBAL_LOCK = 4 * np.finfo(float).eps


def skew(w):
    """The 3x3 matrix w^ with w^ x = w cross x (works for SX, MX and DM)."""
    return ca.vertcat(
        ca.horzcat(0, -w[2], w[1]),
        ca.horzcat(w[2], 0, -w[0]),
        ca.horzcat(-w[1], w[0], 0),
    )


def exp_so3(w):
    """Rodrigues' formula exp(w^) = I + a(s) w^ + b(s) w^2, s = |w|^2, for a 3-vector w (rad).

    a = sin|w|/|w| and b = (1 - cos|w|)/|w|^2 switch to their Taylor series for small |w|,
    so the result is exactly orthogonal in exact arithmetic and smooth (all derivatives
    finite) at w = 0. Returns a 3x3 expression of the same CasADi type as w.
    """
    s = ca.dot(w, w)
    r = ca.sqrt(ca.fmax(s, _SMALL_ANGLE_SQ))  # the unused branch never divides by 0
    a_big = ca.sin(r) / r
    b_big = (1 - ca.cos(r)) / (r * r)
    a_small = 1 - s / 6 + s**2 / 120 - s**3 / 5040
    b_small = 0.5 - s / 24 + s**2 / 720 - s**3 / 40320
    big = s > _SMALL_ANGLE_SQ
    a = ca.if_else(big, a_big, a_small)
    b = ca.if_else(big, b_big, b_small)
    W = skew(w)
    return ca.DM.eye(3) + a * W + b * ca.mtimes(W, W)


def axis_rotation(k, angle):
    """Rotation by `angle` (rad) about the axis k (3-vector, normalised here):
    I + sin(angle) n^ + (1 - cos(angle)) n^2 with n = k/|k|. No branch, unlike exp_so3:
    the axis is never zero. Returns a 3x3 expression of the type of k and angle."""
    N = skew(k / ca.norm_2(k))
    return ca.DM.eye(3) + ca.sin(angle) * N + (1 - ca.cos(angle)) * ca.mtimes(N, N)


# ---- numeric (numpy) -------------------------------------------------------------------


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b of two 3-vectors (3,), as np.cross without its general-axis machinery (1 us a
    call instead of 13: a plan's per-node foot wrenches take thousands)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_matrix(rpy) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) of rpy = (roll, pitch, yaw) rad, URDF's convention."""
    roll, pitch, yaw = (float(a) for a in rpy)
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def matrix_rpy(R: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) rad of a rotation R = Rz(yaw) Ry(pitch) Rx(roll), pitch in
    [-pi/2, pi/2]; at pitch = +-pi/2 roll is 0. Rebuilds R to round-off (roll from the
    remainder Ry(pitch)^T Rz(yaw)^T R, as `gait_planner.model.angles.root_angles`)."""
    R = np.asarray(R, dtype=float)
    c_pitch = float(np.hypot(R[0, 0], R[1, 0]))
    pitch = float(np.arctan2(-R[2, 0], c_pitch))
    yaw = float(np.arctan2(R[1, 0], R[0, 0])) if c_pitch > GIMBAL_LOCK else \
        float(np.arctan2(-R[0, 1], R[1, 1]))
    rest = rot_y(pitch).T @ rot_z(yaw).T @ R
    return float(np.arctan2(rest[2, 1], rest[1, 1])), pitch, yaw


def rot_axis(axis: np.ndarray, a: float) -> np.ndarray:
    """Numeric rotation by angle a about the unit vector axis."""
    n = np.asarray(axis, dtype=float)
    N = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
    return np.eye(3) + np.sin(a) * N + (1.0 - np.cos(a)) * N @ N


def log_so3(R: np.ndarray) -> np.ndarray:
    """The rotation vector w (3,) rad with exp_so3(w) = R, |w| <= pi (numpy), for a rotation
    matrix R (3, 3): the angle from the trace, the axis from the skew part (near pi from
    R + I, whose columns are then multiples of the axis)."""
    cos = np.clip(0.5 * (np.trace(R) - 1.0), -1.0, 1.0)
    angle = float(np.arccos(cos))
    axial = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle < 1e-6:
        return axial  # sin(angle) ~ angle
    if angle < np.pi - 1e-3:
        return angle / np.sin(angle) * axial
    S = R + np.eye(3)
    axis = S[:, int(np.argmax(np.linalg.norm(S, axis=0)))]
    axis = axis / np.linalg.norm(axis)
    return angle * (axis if axis @ axial >= 0 else -axis)
