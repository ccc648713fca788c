"""The walker's frame of a drafted URDF (`gait_planner.model.urdf_import`): the scene's
world, x forward, y left, z up, found from the robot itself at its draft pose (the URDF's
zero with the locked joints at their angles, its base at the identity), whatever axes the
URDF's links use (iCub's base x points backwards).

* **Up** is the URDF's z (REP 103): the feet must lie below the hips along it.
* **The mirror plane** is normal to the horizontal line between the two feet's joints
  (their origins are mirror images in a symmetric robot, however the feet turn out) and
  passes half way between them; it contains up and forward.
* **Forward** is one of the two horizontal directions in that plane, told by the first
  clear cue of
  1. the soles: the toes reach further ahead of the ankle (the foot's joint) than the heel
     behind it, by at least `SOLE_CUE` of the sole's length, summed over both feet (G1,
     Romeo, Alexander, iCub);
  2. the knees: a knee (the leg joint about a lateral axis farthest from both the hip and
     the ankle) whose range lies mostly on one side (`KNEE_CUE`) flexes so that the foot
     moves backwards (Talos, whose ankle is mid-sole);
  3. the URDF's x axis (Bolt's point feet and unlimited knees).
* **Left** = up x forward; the left foot is the one on that side.

A frame within `SNAP` of the URDF's own axes is snapped to them, as the draft writes
mirror images within its tolerances (`gait_planner.model.urdf_mirror`): a robot drafted
in its own axes (G1, Talos, Bolt) is not turned by round-off, and iCub, whose feet stand
4.7e-5 rad off its base's y axis (its rpy of 1.5708), walks along its base's -x. The
angle and distance snapped (`snapped`) are listed in the draft's header. `--feet LEFT,RIGHT` fixes
left and right; a clear cue that says otherwise is refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gait_planner.model.urdf_errors import UrdfError
from gait_planner.model.urdf_read import leg_path

__all__ = ["WalkFrame", "walking_frame"]

SOLE_CUE = 0.2  # (toe reach - heel reach) / sole length that makes the soles a clear cue
KNEE_CUE = 1.0 / 3.0  # a knee's range is one-sided when its smaller side is at most this
#                       fraction of the larger one (G1 0.03, iCub 0.18, Talos 0)
KNEE_RANGE = np.pi  # rad: a limit this far from zero is no limit (Bolt's +-10 rad)
SNAP = 1e-4  # rad and m: a frame this close to the URDF's axes and origin is theirs
#             (iCub's feet, 4.7e-5 rad and 2 um off its axes by its rpy of 1.5708)
_LATERAL = np.cos(np.radians(30.0))  # a knee's axis within 30 deg of the lateral line
_UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class WalkFrame:
    """The walker's world in the URDF's (base at the identity): `W` (3, 3), columns
    forward, left, up; `origin` (3,) m, a point of the mirror plane; `cue` what told
    forward (module docstring)."""

    W: np.ndarray
    origin: np.ndarray
    cue: str
    snapped: tuple[float, float] = (0.0, 0.0)  # rad and m the frame was moved by (SNAP)

    def point(self, p) -> np.ndarray:
        """A URDF-world point (3,) m in the walker's world."""
        return self.W.T @ (np.asarray(p, float) - self.origin)

    def rotation(self, R) -> np.ndarray:
        """A URDF-world rotation (3, 3) (columns: a frame's axes) in the walker's world."""
        return self.W.T @ np.asarray(R, float)


def walking_frame(model, data, feet: tuple[int, int], soles: dict[int, np.ndarray],
                  axes: dict[str, np.ndarray], given: bool
                  ) -> tuple[WalkFrame, tuple[int, int]]:
    """(the frame, (left, right) foot joints) of the module docstring. `model`, `data`: a
    Pinocchio model and its forward kinematics at the draft pose; `feet` two foot joint
    ids (LEFT, RIGHT when `given`); `soles`: foot joint -> its sole's points (n, 3), URDF
    world, m; `axes`: joint name -> unit axis in its joint frame."""
    a, b = feet
    ankle = {f: np.array(data.oMi[f].translation) for f in feet}
    for f in feet:
        hip = leg_path(model, f)[0]
        if not data.oMi[hip].translation[2] > soles[f][:, 2].min():
            raise UrdfError(f"foot {model.names[f]!r} is not below its hip along the URDF's "
                            f"z axis: the importer takes z as up (REP 103)")
    across = ankle[a] - ankle[b]
    across -= (across @ _UP) * _UP
    if np.linalg.norm(across) < 1e-3:
        raise UrdfError(f"the feet {model.names[a]!r} and {model.names[b]!r} are not side by "
                        f"side: their joints are {np.linalg.norm(across) * 1e3:.3g} mm apart "
                        f"across")
    lateral = across / np.linalg.norm(across)  # from b to a
    ahead = np.cross(lateral, _UP)  # forward if a is the left foot
    cues = [("the soles (toes further ahead of the ankles than the heels behind)",
             _sole_cue(soles, ankle, ahead)),
            ("the knees (flexing moves the feet backwards)",
             _knee_cue(model, data, feet, axes, lateral, ahead))]
    cue, sign = next(((c, s) for c, s in cues if s), ("the URDF's x axis",
                                                     1.0 if ahead[0] >= 0 else -1.0))
    if given and sign < 0 and cue != "the URDF's x axis":
        raise UrdfError(f"--feet gives the foot below joint {model.names[a]!r} as the left "
                        f"one, but {cue} make it the right one: give the feet as LEFT,RIGHT "
                        f"of the walking direction")
    if given:
        sign = 1.0
    forward = _snap(sign * ahead)
    turned = float(np.arccos(np.clip(forward @ (sign * ahead), -1.0, 1.0)))
    W = np.column_stack([forward, np.cross(_UP, forward), _UP])
    left, right = (a, b) if sign > 0 else (b, a)
    middle = 0.5 * (ankle[a] + ankle[b])
    origin = (middle @ W[:, 1]) * W[:, 1]
    shift = float(np.abs(origin).max())
    if shift < SNAP:
        origin = np.zeros(3)
    return WalkFrame(W, origin, cue, (turned, shift if shift < SNAP else 0.0)), (left, right)


def _sole_cue(soles, ankle, ahead) -> float:
    """+1 or -1: the side of `ahead` the toes are on, or 0 when the soles do not say."""
    reach, length = 0.0, 0.0
    for foot, points in soles.items():
        t = (points - ankle[foot]) @ ahead
        reach += t.max() + t.min()  # toe reach ahead minus heel reach behind
        length += t.max() - t.min()
    return float(np.sign(reach)) if length > 0 and abs(reach) >= SOLE_CUE * length else 0.0


def _knee_cue(model, data, feet, axes, lateral, ahead) -> float:
    """+1 or -1: the side of `ahead` opposite to where flexing the knees moves the feet,
    or 0 when the knees do not say (both legs must agree)."""
    votes = []
    for foot in feet:
        leg = leg_path(model, foot)
        hip, ankle = data.oMi[leg[0]].translation, data.oMi[foot].translation
        best, knee = 0.0, None
        for j in leg:
            axis = data.oMi[j].rotation @ axes[model.names[j]]
            p = data.oMi[j].translation
            middle = min(np.linalg.norm(p - hip), np.linalg.norm(p - ankle))
            if abs(axis @ lateral) >= _LATERAL and middle > best:
                best, knee = middle, (j, axis, p)
        if knee is None or best < 0.25 * np.linalg.norm(ankle - hip):
            return 0.0
        j, axis, p = knee
        idx = model.joints[j].idx_q
        lo, hi = float(model.lowerPositionLimit[idx]), float(model.upperPositionLimit[idx])
        small, large = sorted((abs(lo) if lo < 0 else 0.0, hi if hi > 0 else 0.0))
        if max(abs(lo), abs(hi)) >= KNEE_RANGE or large == 0 or small > KNEE_CUE * large:
            return 0.0
        flex = 1.0 if hi + lo > 0 else -1.0
        votes.append(-np.sign(flex * np.cross(axis, ankle - p) @ ahead))
    return float(votes[0]) if votes[0] == votes[1] else 0.0


def _snap(forward: np.ndarray) -> np.ndarray:
    """`forward` (unit, horizontal) snapped onto the URDF's +-x or +-y within SNAP."""
    for axis in np.eye(3)[:2]:
        for s in (1.0, -1.0):
            if np.abs(forward - s * axis).max() < SNAP:
                return s * axis
    return forward
