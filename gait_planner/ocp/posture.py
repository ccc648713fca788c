"""Joint-range path constraints: every joint angle of `gait_planner.model.angles` kept in
a declared interval, written as smooth margins of the relative rotation.

Minimal kinetic energy alone leaves light bodies free to turn far (DESIGN.md section 5: a
foot spun 143 deg about the shank when nothing held it), so a scene declares ranges,
e.g. ``joint_limits: {ankle_r_yaw: [-20, 20], knee_r: [0, 70]}`` (degrees) in its gait
options. An angle theta is never computed (atan2 would put a branch cut into the NLP):
with R = D_p^T D_c the rotation of the child relative to the parent (D = [d1 d2 d3]),

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
from collections.abc import Mapping

import casadi as ca
import numpy as np

from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import JointType, Scene


class JointLimitError(ValueError):
    """A joint range that names no angle of the scene or cannot be expressed."""


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


def check_joint_limits(scene: Scene, limits) -> tuple[tuple[str, float, float], ...]:
    """Validated ((angle name, lo rad, hi rad), ...) from {name: (lo deg, hi deg)}."""
    if not isinstance(limits, Mapping):
        raise JointLimitError(f"joint_limits: need a mapping {{angle name: [lower, upper]}} "
                              f"in degrees, got {type(limits).__name__}")
    parts = _angle_parts(scene)
    out = []
    for name, bounds in limits.items():
        if name not in parts:
            raise JointLimitError(f"joint_limits: {name!r} is not a joint angle of scene "
                                  f"{scene.name!r}; known: {', '.join(parts)}")
        try:
            lo, hi = (float(v) for v in bounds)
        except (TypeError, ValueError):
            raise JointLimitError(f"joint_limits.{name}: need [lower, upper] in degrees, "
                                  f"got {bounds!r}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi and hi - lo < 180):
            raise JointLimitError(f"joint_limits.{name}: need finite lower < upper within "
                                  f"180 deg, got [{lo}, {hi}]")
        if parts[name][3] is None and not -90 <= lo < hi <= 90:
            raise JointLimitError(f"joint_limits.{name}: a roll range must lie in "
                                  f"[-90, 90] deg, got [{lo}, {hi}]")
        out.append((name, math.radians(lo), math.radians(hi)))
    return tuple(out)


def joint_limit_margins(mb: Multibody, limits: tuple[tuple[str, float, float], ...]):
    """CasADi Function `joint_limit_margins`: q (k,) -> margins (2 * len(limits),), each
    >= 0 exactly when its angle lies in its range (module docstring); limits in radians,
    as returned by `check_joint_limits`."""
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
