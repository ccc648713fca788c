"""Joint-range path constraints: every joint angle of `gait_planner.model.angles` kept in
a declared interval, written as smooth margins of the relative rotation.

Minimal kinetic energy alone leaves light bodies free to turn far (DESIGN.md section 5: a
foot spun 143 deg about the shank when nothing held it), so a scene declares ranges,
e.g. ``joint_limits: {ankle_r_yaw: [-20, 20], knee_r: [0, 70]}`` (degrees) in its gait
options, checked (and converted to radians) by `gait_planner.model.posture` when the scene
loads and when a request overrides them. An angle theta is never computed (atan2 would put
a branch cut into the NLP): with R = D_p^T D_c the rotation of the child relative to the
parent (D = [d1 d2 d3]),

* spherical joints, R = Ry(pitch) Rx(roll) Rz(yaw) (`angles.spherical_rotation`):
  cos(roll) (sin pitch, cos pitch) = (R02, R22), sin roll = -R12,
  cos(roll) (sin yaw, cos yaw) = (R10, R11);
* revolute joints about the unit axis a, with b, c = a x b completing a right-handed
  basis: (sin theta, cos theta) = (c^T R b, b^T R b),

and theta in [lo, hi] is k sin(theta - lo) >= 0 and k sin(hi - theta) >= 0 with the
positive factor k (cos roll, or 1), exact for hi - lo < 180 deg and |roll| < 90 deg; a roll
range is sin(roll) in [sin lo, sin hi]. All margins are bilinear in the directors.
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
            b, c = _basis(j.axis)
            parts = [(np.outer(c, b), np.outer(b, b))]
        for name, (S, C) in zip(j.angle_names, parts):
            out[name] = (j.parent, j.child, S, C)
    return out


def joint_limit_margins(mb: Multibody, limits: tuple[tuple[str, float, float], ...]):
    """CasADi Function `joint_limit_margins`: q (k,) -> margins (2 * len(limits),), each
    >= 0 exactly when its angle lies in its range (module docstring); limits in radians,
    as returned by `gait_planner.model.posture.check_joint_limits`."""
    parts = _angle_parts(mb.scene)
    q = ca.SX.sym("q", mb.k)

    def directors(body):
        start = mb.block(body).start
        return ca.reshape(q[start + 3 : start + 12], 3, 3)  # columns d1, d2, d3

    rows = []
    for name, lo, hi in limits:
        parent, child, S, C = parts[name]
        R = ca.mtimes(directors(parent).T, directors(child))
        s = ca.sum1(ca.sum2(ca.DM(S) * R))
        if C is None:
            rows += [s - math.sin(lo), math.sin(hi) - s]
            continue
        c = ca.sum1(ca.sum2(ca.DM(C) * R))
        rows += [s * math.cos(lo) - c * math.sin(lo), c * math.sin(hi) - s * math.cos(hi)]
    return ca.Function("joint_limit_margins", [q], [ca.vertcat(*rows)], ["q"], ["margins"])
