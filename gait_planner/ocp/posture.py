"""Joint-range path constraints: every joint angle of `gait_planner.model.angles` kept in
a declared interval, written as one row with two bounds per angle of the relative rotation.

Minimal kinetic energy alone leaves light bodies free to turn far (docs/design.md section 5: a
foot spun 143 deg about the shank when nothing held it), so a scene declares ranges,
e.g. ``joint_limits: {ankle_r_yaw: [-20, 20], knee_r: [0, 70]}`` (degrees) in its gait
options, checked (and converted to radians) by `gait_planner.model.posture` when the scene
loads and when a request overrides them. With R = D_p^T D_c the rotation of the child
relative to the parent (D = [d1 d2 d3]),

* spherical joints, R = Ry(pitch) Rx(roll) Rz(yaw) (`angles.spherical_rotation`):
  cos(roll) (sin pitch, cos pitch) = (R02, R22), sin roll = -R12,
  cos(roll) (sin yaw, cos yaw) = (R10, R11);
* revolute joints about the unit axis a, with b, c = a x b completing a right-handed
  basis: (sin theta, cos theta) = (c^T R b, b^T R b),

and theta in [lo, hi] is one row per angle, (theta - lo) / w in [0, JOINT_RANGE_ROW_UPPER
= 2] with the half width w = (hi - lo) / 2 (< 90 deg): the distance from the lower bound
in half widths, computed as 1 + atan2(k sin(theta - m), k cos(theta - m)) / w about the
range's middle m with the positive factor k (cos roll, or 1). atan2's branch cut lies at
theta = m +- 180 deg, where the row is below 0 on one side and above 2 on the other: never
in or next to the range. A roll range is (sin roll - sin lo) / w_s in [0, 2] with
w_s = (sin hi - sin lo) / 2. One row with two bounds per angle: IPOPT gives every
inequality row a slack and a row of its KKT system, and the earlier two rows per angle,
k sin(theta - lo) >= 0 and k sin(hi - theta) >= 0, were 1092 of walker3d's 1565
inequality rows (14 of them active at the optimum; benchmarks/HISTORY.md). Those two rows
remain as `joint_limit_margins`, the form the collocation baseline converges with
(`collocation.transcription`).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import JointType, Scene


def _basis(axis) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    trial = np.eye(3)[int(np.argmin(np.abs(a)))]
    b = np.cross(a, trial)
    b /= np.linalg.norm(b)
    return b, np.cross(a, b)


def _angle_parts(scene: Scene) -> dict[str, tuple[str, str, np.ndarray, np.ndarray | None]]:
    """angle name -> (parent, child, S, C) with S, C (3, 3) weights such that
    sum(S * R) = k sin(theta), sum(C * R) = k cos(theta); C is None for a roll angle,
    whose sum(S * R) = sin(roll)."""
    out = {}
    for j in scene.joints:
        if j.type is JointType.SPHERICAL:
            pitch_s, pitch_c, roll, yaw_s, yaw_c = (np.zeros((3, 3)) for _ in range(5))
            pitch_s[0, 2], pitch_c[2, 2] = 1.0, 1.0
            roll[1, 2] = -1.0
            yaw_s[1, 0], yaw_c[1, 1] = 1.0, 1.0
            parts = [(pitch_s, pitch_c), (roll, None), (yaw_s, yaw_c)]
        else:
            b, c = _basis(j.axis)  # Rot(n, theta) = R_rel R0^T (gait_planner.model.angles)
            b_child = j.reference.T @ b
            parts = [(np.outer(c, b_child), np.outer(b, b_child))]
        for name, (S, C) in zip(j.angle_names, parts):
            out[name] = (j.parent, j.child, S, C)
    return out


# Upper bound of every joint-range row (`joint_limit_rows`); the lower bound is 0.
JOINT_RANGE_ROW_UPPER = 2.0


def joint_limit_rows(mb: Multibody, names: tuple[str, ...],
                     function_name: str = "joint_limits") -> ca.Function:
    """CasADi Function `function_name`: (q (k,), c (3 len(names),)) -> rows (len(names),),
    each in [0, JOINT_RANGE_ROW_UPPER] exactly when its angle lies in its range: (theta -
    lo) / w, or (sin roll - sin lo) / w_s for a roll (module docstring), with the ranges
    given by c = `joint_limit_constants(limits)` (an input, so that one compiled function
    serves any range of the same angles)."""
    q, c = ca.SX.sym("q", mb.k), ca.SX.sym("c", 3 * len(names))
    rows = []
    for i, (sin_part, cos_part) in enumerate(_sin_cos_parts(mb, q, names)):
        a = c[3 * i : 3 * i + 3]
        if cos_part is None:  # a roll: (sin roll - sin lo) / w_s
            rows.append((sin_part - a[0]) * a[1])
        else:  # 1 + atan2(k sin(theta - m), k cos(theta - m)) / w
            rows.append(1 + a[2] * ca.atan2(a[0] * sin_part - a[1] * cos_part,
                                            a[0] * cos_part + a[1] * sin_part))
    return ca.Function(function_name, [q, c], [ca.vertcat(*rows)], ["q", "c"], ["rows"])


def joint_limit_constants(mb: Multibody, limits: tuple[tuple[str, float, float], ...]) -> np.ndarray:
    """c (3 len(limits),) of `joint_limit_rows` for (angle, lower rad, upper rad) ranges,
    as returned by `gait_planner.model.posture.check_joint_limits` (0 < hi - lo < 180 deg):
    per angle (cos m, sin m, 1 / w) with the range's middle m and half width w, or for a
    roll (sin lo, 1 / w_s, 0)."""
    parts = _angle_parts(mb.scene)
    out = []
    for name, lo, hi in limits:
        if parts[name][3] is None:
            out += [math.sin(lo), 2.0 / (math.sin(hi) - math.sin(lo)), 0.0]
        else:
            middle, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
            out += [math.cos(middle), math.sin(middle), 1.0 / half]
    return np.array(out)


def joint_limit_margins(mb: Multibody, names: tuple[str, ...],
                        function_name: str = "joint_limits") -> ca.Function:
    """CasADi Function `function_name`: (q (k,), c (6 len(names),)) -> margins
    (2 len(names),), the collocation baseline's form of the ranges (`collocation.transcription`):
    two one-sided rows per angle, k sin(theta - lo) >= 0 and k sin(hi - theta) >= 0, or
    sin(roll) - sin lo and sin hi - sin(roll), each >= 0 exactly when its angle lies in its
    range (hi - lo < 180 deg, |roll| < 90 deg), with the ranges given by
    c = `joint_margin_constants(limits)`."""
    q, c = ca.SX.sym("q", mb.k), ca.SX.sym("c", 6 * len(names))
    rows = []
    for i, (sin_part, cos_part) in enumerate(_sin_cos_parts(mb, q, names)):
        cos_part = 0 if cos_part is None else cos_part
        a = c[6 * i : 6 * i + 6]
        rows += [a[0] * sin_part + a[1] * cos_part + a[2],
                 a[3] * sin_part + a[4] * cos_part + a[5]]
    return ca.Function(function_name, [q, c], [ca.vertcat(*rows)], ["q", "c"], ["margins"])


def joint_margin_constants(mb: Multibody, limits: tuple[tuple[str, float, float], ...]) -> np.ndarray:
    """c (6 len(limits),) of `joint_limit_margins`: per angle the coefficients (a, b, d) of
    the lower and the upper margin a k sin + b k cos + d."""
    parts = _angle_parts(mb.scene)
    out = []
    for name, lo, hi in limits:
        if parts[name][3] is None:
            out += [1.0, 0.0, -math.sin(lo), -1.0, 0.0, math.sin(hi)]
        else:
            out += [math.cos(lo), -math.sin(lo), 0.0, -math.cos(hi), math.sin(hi), 0.0]
    return np.array(out)


def _sin_cos_parts(mb: Multibody, q, names: tuple[str, ...]) -> list:
    """[(k sin theta, k cos theta)] of each angle at configuration q (SX), (sin roll, None)
    for a roll (`_angle_parts`)."""
    parts, out = _angle_parts(mb.scene), []
    for name in names:
        parent, child, S, C = parts[name]
        R = _rotation_between(mb, q, parent, child)
        out.append((ca.sum1(ca.sum2(ca.DM(S) * R)),
                    None if C is None else ca.sum1(ca.sum2(ca.DM(C) * R))))
    return out


def _rotation_between(mb: Multibody, q, parent: str, child: str):
    """R = D_parent^T D_child (3, 3) at configuration q (SX), D = [d1 d2 d3] of a body."""
    D = [ca.reshape(q[mb.block(b).start + 3 : mb.block(b).start + 12], 3, 3)
         for b in (parent, child)]
    return ca.mtimes(D[0].T, D[1])


def joint_speed_margins(mb: Multibody) -> ca.Function:
    """CasADi Function (q_n, q_{n+1}, h_n, c) -> one margin (>= 0) per joint of interval n,
    c = (base time step s, speed_max rad/s): settings enter as an input, so one compiled
    function serves every limit.

    The rotation R_rel(q_n)^T R_rel(q_{n+1}) of the child relative to its parent, by an angle
    theta, has |R_rel(q_{n+1}) - R_rel(q_n)|_F^2 = 8 sin^2(theta/2), so
    8 sin^2(w h_n / 2) - |dR_rel|_F^2 >= 0 bounds theta by w h_n (w = speed_max): a mean
    relative angular speed, whatever the joint's axes. Rows are divided by
    (w base_time_step)^2 to be O(1)."""
    q0, q1, h = ca.SX.sym("q", mb.k), ca.SX.sym("q_next", mb.k), ca.SX.sym("h")
    c = ca.SX.sym("c", 2)
    w = c[1]
    bound = 8 * ca.sin(0.5 * w * h) ** 2
    rows = [(bound - ca.sumsqr(_rotation_between(mb, q1, j.parent, j.child)
                               - _rotation_between(mb, q0, j.parent, j.child)))
            / (w * c[0]) ** 2 for j in mb.scene.joints]
    return ca.Function("joint_speed", [q0, q1, h, c], [ca.vertcat(*rows)],
                       ["q", "q_next", "h", "c"], ["margin"])


def joint_speeds_margins(mb: Multibody, joints: tuple[str, ...]) -> ca.Function:
    """`joint_speed_margins` of the joints named only, each with its own bound: c = (base
    time step s, w_1 .. w_m rad/s), w_i the bound of joints[i], row i divided by
    (w_i base_time_step)^2 (the joint_speed_limits option; one bound for every joint is
    `joint_speed_margins`, whose compiled function the shipped scenes share)."""
    q0, q1, h = ca.SX.sym("q", mb.k), ca.SX.sym("q_next", mb.k), ca.SX.sym("h")
    c = ca.SX.sym("c", 1 + len(joints))
    by_name = {j.name: j for j in mb.scene.joints}
    rows = []
    for i, name in enumerate(joints):
        j, w = by_name[name], c[1 + i]
        rows.append((8 * ca.sin(0.5 * w * h) ** 2
                     - ca.sumsqr(_rotation_between(mb, q1, j.parent, j.child)
                                 - _rotation_between(mb, q0, j.parent, j.child)))
                    / (w * c[0]) ** 2)
    return ca.Function("joint_speeds", [q0, q1, h, c], [ca.vertcat(*rows)],
                       ["q", "q_next", "h", "c"], ["margin"])


def twist_squares(mb: Multibody) -> ca.Function:
    """CasADi Function (q_n, q_{n+1}, h_n, c) -> c[1] h_n sum over joints of
    1 - (d2_parent . d2_child)^2 at q_n (J s for the weight c[1] in J; c[0] the base time
    step, unused): the squared sine of the angle between each joint's two lateral axes,
    zero for any pure pitch (and for a revolute joint about d2), sin^2 of roll or yaw alone
    otherwise (the twist regulariser's term of interval n)."""
    q, q_next, h, c = ca.SX.sym("q", mb.k), ca.SX.sym("q_next", mb.k), ca.SX.sym("h"), \
        ca.SX.sym("c", 2)
    total = 0
    for j in mb.scene.joints:
        p, ch = (mb.block(b).start + 6 for b in (j.parent, j.child))
        total += 1 - ca.dot(q[p : p + 3], q[ch : ch + 3]) ** 2
    return ca.Function("twist", [q, q_next, h, c], [c[1] * h * total],
                       ["q", "q_next", "h", "c"], ["twist"])
