"""Left and right in a drafted URDF scene (`gait_planner.model.urdf_import`): the half
cycle's mirror periodicity needs a left-right symmetric robot, so the draft pairs left and
right links and joints and writes the right ones as the left ones' mirror images about the
walker's mid-plane, S = diag(1, -1, 1) in the walker's frame
(`gait_planner.model.urdf_frame`).

* `mirror_pairs` pairs them from the kinematic tree: the two legs' joints from the base to
  the feet, in chain order (a ball joint with its partner). The names are not read: iCub's
  l_/r_, Alexander's LEFT_/RIGHT_ and G1's left_/right_ pair alike, and legs of different
  lengths are refused.
* `mirrored_inertias` compares the robot in the walker's world at the draft pose, not link
  frame by link frame (the URDF's left and right link frames may differ, as iCub's and
  Alexander's do): a right link's mass, centre of mass and inertia become its left
  partner's mirror image (m, S c, S I S in the world), a link without a partner (the base)
  is made symmetric about the mid-plane ((I + S I S)/2, c_y = 0), when the URDF's differ
  by less than MIRROR_TOLERANCE (mass, inertia; relative, 5 %, or the user's
  `--mirror-tolerance`) and MIRROR_COM_TOLERANCE (centre of mass, 1 cm). G1's right
  knee, whose Ixz has the wrong sign (9e-5 kg m^2), is written symmetric; Talos's leg_2
  inertias (5.35 % apart) only with `--mirror-tolerance 0.06`, its COMs being 0.4 mm apart
  and its base with the locked torso and arms 2.05 mm off the mid-plane.
* `mirror_geometry`, on the drafted points, axes and references (director components,
  the right links' principal axes being the left ones' mirrored in the world): points
  (X1, X2, X3) -> (X1, -X2, X3), axes n -> +-(-S n), references R0 -> S R0 S, after
  checking that the URDF's own placements agree within GEOMETRY_TOLERANCE (1e-3
  relative: iCub's rpy of 1.5708 leave its right joints a few micrometres and 1e-4 rad
  from its left ones' images); what moved beyond 1e-6 relative is listed in the header.
* A link with mass whose URDF inertia is zero (`MISSING_INERTIA`: all of iCub's right leg
  links but its foot in example-robot-data) takes its twin's mirrored inertia, its mass
  and centre of mass still checked; the header says so.
"""

from __future__ import annotations

import math

import numpy as np

from gait_planner.model.urdf_errors import UrdfError

MIRROR_TOLERANCE = 5e-2  # relative: a mass or inertia differing less is written symmetric
MIRROR_COM_TOLERANCE = 1e-2  # m: a centre of mass differing less is written symmetric
MISSING_INERTIA = 1e-12  # kg m^2: a link with mass whose inertia is this small has none in
#                          the URDF (iCub's right leg links): its twin's image is written
GEOMETRY_TOLERANCE = 1e-3  # relative (rad for axes): joint placements and contact points
#                            differing less are written as mirror images (iCub's rpy of
#                            1.5708 leave its joints 2e-4 apart, a few micrometres)
_LISTED = 1e-6  # relative: a geometry change above this is listed in the draft's header
S = np.diag([1.0, -1.0, 1.0])  # the mirror y -> -y


def mirror_pairs(model, left_leg: list[int], right_leg: list[int], balls
                 ) -> tuple[dict[int, int], dict[str, str]]:
    """(right joint -> its left partner, left joint or ball name -> right one) of the legs
    `left_leg`, `right_leg` (Pinocchio joint ids from the base to the foot) in chain order;
    `balls`: `gait_planner.model.urdf_fuse.Ball`s. UrdfError when the legs differ in
    length or in joint type."""
    if len(left_leg) != len(right_leg):
        raise UrdfError(f"the legs are not mirror images: the left one has {len(left_leg)} "
                        f"joints ({', '.join(model.names[j] for j in left_leg)}), the right "
                        f"one {len(right_leg)} ({', '.join(model.names[j] for j in right_leg)})"
                        f": the half cycle's mirror periodicity needs a left-right symmetric "
                        f"robot")
    left_of = dict(zip(right_leg, left_leg))
    ball_of = {ball.joints[2]: ball.name for ball in balls}
    names = {str(model.names[l]): str(model.names[r]) for l, r in zip(left_leg, right_leg)}
    for left, right in zip(left_leg, right_leg):
        if (left in ball_of) != (right in ball_of):
            raise UrdfError(f"joint {model.names[right]!r} is not {model.names[left]!r}'s "
                            f"mirror image: one ends a ball joint, the other does not")
        if left in ball_of:
            names[ball_of[left]] = ball_of[right]
    return left_of, names


def mirrored_inertias(model, data, frame, links: dict[int, str], left_of: dict[int, int],
                      changes: list[str], *, tolerance: float = MIRROR_TOLERANCE
                      ) -> tuple[dict[int, tuple], dict[int, int]]:
    """(joint -> (mass kg, COM (3,) m, inertia at the COM (3, 3) kg m^2) in the joint
    frames, each link after the twin it is the image of; image joint -> its source) of a
    Pinocchio model's links (`links`: joint -> link name; `left_of`: right joint -> left
    twin, `mirror_pairs`), compared in the walker's world (`frame`, a
    `gait_planner.model.urdf_frame.WalkFrame`, at the pose of `data`) as the module
    docstring says: the right link is its left twin's image, unless the right one alone
    has an inertia (`MISSING_INERTIA`). `changes` collects what moved. `tolerance`: the
    relative difference of mass and inertia written symmetric (MIRROR_TOLERANCE unless the
    user asks, `--mirror-tolerance`); a larger one is refused naming the worst link and the
    tolerance that would accept every link."""
    place = {j: (frame.rotation(data.oMi[j].rotation), frame.point(data.oMi[j].translation))
             for j in links}
    raw = {}
    for j in links:  # in the walker's world
        R, p = place[j]
        inertia = model.inertias[j]
        raw[j] = (float(inertia.mass), R @ np.array(inertia.lever) + p,
                  R @ np.array(inertia.inertia) @ R.T)
    missing = {j for j in links if np.abs(raw[j][2]).max() <= MISSING_INERTIA}
    source_of = {}
    for right, left in left_of.items():
        image, source = (left, right) if left in missing and right not in missing else \
            (right, left)
        source_of[image] = source
    out, beyond = {}, []
    for joint, name in links.items():
        if joint not in source_of:
            if any(s == joint for s in source_of.values()):  # a source: as the URDF has it
                inertia = model.inertias[joint]
                out[joint] = (raw[joint][0], np.array(inertia.lever), np.array(inertia.inertia))
                continue
        mass, com, inertia = raw[joint]
        other = source_of.get(joint)
        if other is None:  # the base, made symmetric about the mid-plane
            image = (mass, np.array([com[0], 0.0, com[2]]), 0.5 * (inertia + S @ inertia @ S))
            partner, moved = "its own mirror image", "symmetric"
            written = "writing it symmetric about the mid-plane"
        else:
            m2, c2, i2 = raw[other]
            image = (m2, S @ c2, S @ i2 @ S)
            partner = moved = f"{links[other]}'s mirror image"
            written = "writing the left's data for both"
        checks = [("mass", mass, image[0], max(mass, image[0])),
                  ("centre of mass", com, image[1], None)]
        if joint in missing and other is not None:
            changes.append(f"{name}: inertia missing (zero) in the URDF, written as {moved}")
        else:
            scale = max(np.abs(np.linalg.eigvalsh(m)).max() for m in (inertia, image[2]))
            checks.append(("inertia", inertia, image[2], scale))
        for what, a, b, unit in checks:
            gap = float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
            if unit is None:  # the centre of mass: an absolute tolerance
                if gap > 1e-6 * MIRROR_COM_TOLERANCE:
                    changes.append(f"{name}: {what} moved by {gap * 1e3:.3g} mm to be {moved}")
                if gap > MIRROR_COM_TOLERANCE:
                    raise UrdfError(f"{name}'s {what} is {gap * 1e3:.3g} mm from {partner} "
                                    f"(more than {MIRROR_COM_TOLERANCE * 1e3:g} mm): the half "
                                    f"cycle's mirror periodicity needs a left-right "
                                    f"symmetric robot")
                continue
            relative = gap / unit if gap > 0 else 0.0  # relative to the larger of the two
            if relative > 1e-6 * MIRROR_TOLERANCE:
                changes.append(f"{name}: {what} moved by {gap:.3g} ({100 * relative:.3g} %) "
                               f"to be {moved}")
            if relative > tolerance:
                beyond.append((relative, f"{name}'s {what} is {100 * relative:.3g} % from "
                                         f"{partner}", written))
        R, p = place[joint]  # the image back in the joint frame
        out[joint] = (image[0], R.T @ (image[1] - p), R.T @ image[2] @ R)
    if beyond:
        relative, what, written = max(beyond)
        others = " and every other link" if len(beyond) > 1 else ""
        asked = (f"; --mirror-tolerance {_above(relative):g} accepts it{others}, {written}"
                 if _above(relative) < 1 else "")
        raise UrdfError(f"{what} (more than {100 * tolerance:g} %){asked}: the half cycle's "
                        f"mirror periodicity needs a left-right symmetric robot")
    return {j: out[j] for j in sorted(out, key=lambda j: j in source_of)}, source_of


def _above(fraction: float) -> float:
    """The one-significant-digit fraction just above `fraction` (0.0536 -> 0.06)."""
    exponent = math.floor(math.log10(fraction))
    digit = math.floor(fraction / 10.0 ** exponent) + 1
    return round(digit * 10.0 ** exponent, -exponent)


def mirror_geometry(names: dict[int, str], left_of: dict[int, int], twins: dict[str, str],
                    local, joints, changes: list[str]) -> None:
    """Write the right links' points (`local`: joint -> point -> director components) and
    the right joints' axes and references (`joints`: name -> {"parent", "child", "axis",
    "reference"}) as the left ones' mirror images, and the base's points as their own
    (a leg joint's point as its twin's image, any other one on the mirror plane); `names`:
    joint -> link name, `left_of` and `twins` (left joint or ball name -> right one) from
    `mirror_pairs` (module docstring); `changes` collects what moved beyond round-off
    (module docstring). Spherical joints (no "axis") are exact in their
    parents' directors (`gait_planner.model.urdf_fuse`), so mirror images once their
    bodies are."""
    twin = {**twins, **{right: left for left, right in twins.items()}}
    pairs = [(left, right) for right, left in left_of.items()]
    pairs += [(j, j) for j in names if j not in left_of and j not in left_of.values()]
    for left, right in pairs:
        for point, X in list(local[left].items()):
            image = twin.get(point, point)  # a contact (heel, forefoot) keeps its name
            if image not in local[right]:
                raise UrdfError(f"link {names[right]!r} has no point {image!r} to mirror "
                                f"{names[left]!r}'s {point!r}")
            _close(f"{names[right]}: point {image}", S @ X, local[right][image],
                   max(np.linalg.norm(X), 0.01), changes)
            if left != right or image != point or abs(X[1]) > 0:
                local[right][image] = S @ X
    for name, right in joints.items():
        if "axis" not in right or name not in twins.values():
            continue
        left = joints[twin[name]]
        image = -S @ left["axis"]
        sign = 1.0 if image @ right["axis"] >= 0 else -1.0
        _close(f"{name}: axis", sign * image, right["axis"], 1.0, changes)
        _close(f"{name}: zero-angle reference", S @ left["reference"] @ S,
               right["reference"], 1.0, changes)
        right["axis"], right["reference"] = sign * image, S @ left["reference"] @ S


def _close(what: str, a, b, scale: float, changes: list[str]) -> None:
    """Refuse `a` and `b` further apart than GEOMETRY_TOLERANCE * scale, list them in
    `changes` when further than _LISTED * scale."""
    gap = float(np.max(np.abs(np.asarray(a, float) - np.asarray(b, float))))
    if gap > _LISTED * scale:
        changes.append(f"{what} moved by {gap:.3g} to be its twin's mirror image")
    if gap > GEOMETRY_TOLERANCE * max(float(scale), 1e-300):
        raise UrdfError(f"{what} is not its twin's mirror image ({gap:.3g} apart, more than "
                        f"{GEOMETRY_TOLERANCE:g} relative): the half cycle's mirror "
                        f"periodicity needs a left-right symmetric robot (its joint "
                        f"placements, axes and collision geometry mirrored)")
