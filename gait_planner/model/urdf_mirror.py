"""Left and right in a drafted URDF scene (`gait_planner.model.urdf_import`): the half
cycle's mirror periodicity needs a left-right symmetric robot, so the draft pairs left and
right links and joints by their names and writes the right ones as the left ones' mirror
images about the xz-plane, S = diag(1, -1, 1).

Two steps, both refusing (`UrdfError`, naming the link or joint) what is not symmetric:

* `mirrored_inertias`, on the URDF's data in the joint frames: a right link's mass, centre
  of mass and inertia become its left partner's mirror image (m, S c, S I S), a link
  without a partner (the base) is made symmetric about its own xz-plane ((I + S I S)/2,
  c_y = 0), when the URDF's differ by less than MIRROR_TOLERANCE (mass, inertia; relative,
  5 %, or the user's `--mirror-tolerance`) and MIRROR_COM_TOLERANCE (centre of mass, 1 cm).
  G1's right knee, whose Ixz has the wrong sign (9e-5 kg m^2), is written symmetric;
  Talos's leg_2 inertias (5.35 % apart) only with `--mirror-tolerance 0.06`, its COMs being
  0.4 mm apart and its base with the locked torso and arms 2.05 mm off the mid-plane.
* `mirror_geometry`, on the drafted points, axes and references (director components,
  the right links' principal axes being the left ones' mirrored): points (X1, X2, X3) ->
  (X1, -X2, X3), axes n -> +-(-S n), references R0 -> S R0 S, after checking that the
  URDF's own placements agree to round-off (_SNAP_TOLERANCE).
"""

from __future__ import annotations

import math
import re

import numpy as np

from gait_planner.model.urdf_errors import UrdfError

MIRROR_TOLERANCE = 5e-2  # relative: a mass or inertia differing less is written symmetric
MIRROR_COM_TOLERANCE = 1e-2  # m: a centre of mass differing less is written symmetric
_SNAP_TOLERANCE = 1e-9  # relative: mirrored geometry (placements are exact) after symmetry
S = np.diag([1.0, -1.0, 1.0])  # the mirror y -> -y
_SIDES = (("left_", "right_"), ("l_", "r_"), ("_left", "_right"), ("_l", "_r"),
          ("L_", "R_"), ("_L", "_R"), ("FL_", "FR_"), ("HL_", "HR_"), ("left", "right"))


def mirror_name(name: str) -> tuple[str, str] | tuple[None, None]:
    """(the name with its side swapped, "left" or "right": the side of `name`), or
    (None, None) for a name without a side token (`_SIDES`)."""
    for left, right in _SIDES:
        for a, b, side in ((left, right, "left"), (right, left, "right")):
            for pattern in (rf"^{a}", rf"{a}$", rf"(?<=[_\W]){a}"):
                if re.search(pattern, name):
                    return re.sub(pattern, b, name, count=1), side
    return None, None


def mirrored_inertias(model, links: dict[int, str], changes: list[str], *,
                      tolerance: float = MIRROR_TOLERANCE
                      ) -> tuple[dict[int, tuple], dict[int, int]]:
    """(joint -> (mass, COM (3,), inertia at the COM (3, 3)) in the joint frames, left
    links before their right partners; right joint -> its left partner) of a Pinocchio
    model's links (module docstring); `changes` collects what moved. `tolerance`: the
    relative difference of mass and inertia written symmetric (MIRROR_TOLERANCE unless the
    user asks, `--mirror-tolerance`); a larger one is refused naming the worst link and the
    tolerance that would accept every link."""
    raw = {j: (float(model.inertias[j].mass), np.array(model.inertias[j].lever),
               np.array(model.inertias[j].inertia)) for j in links}
    by_name = {name: j for j, name in links.items()}
    out, left_of, beyond = {}, {}, []
    for joint, name in links.items():
        image_name, side = mirror_name(name)
        other = by_name.get(image_name or "", joint)
        if side != "right" and other != joint:  # a left link: kept as the URDF has it
            out[joint] = raw[joint]
            continue
        mass, com, inertia = raw[joint]
        if other == joint:  # the base, made symmetric about its own xz-plane
            image = (mass, np.array([com[0], 0.0, com[2]]), 0.5 * (inertia + S @ inertia @ S))
            partner, moved = "its own mirror image", "symmetric"
            written = "writing it symmetric about its own xz-plane"
        else:
            m2, c2, i2 = raw[other]
            image = (m2, S @ c2, S @ i2 @ S)
            partner = moved = f"{links[other]}'s mirror image"
            written = "writing the left's data for both"
            left_of[joint] = other
        scale = max(np.abs(np.linalg.eigvalsh(m)).max() for m in (inertia, image[2]))
        for what, a, b, unit in (("mass", mass, image[0], max(mass, image[0])),
                                 ("centre of mass", com, image[1], None),
                                 ("inertia", inertia, image[2], scale)):
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
        out[joint] = image
    if beyond:
        relative, what, written = max(beyond)
        others = " and every other link" if len(beyond) > 1 else ""
        asked = (f"; --mirror-tolerance {_above(relative):g} accepts it{others}, {written}"
                 if _above(relative) < 1 else "")
        raise UrdfError(f"{what} (more than {100 * tolerance:g} %){asked}: the half cycle's "
                        f"mirror periodicity needs a left-right symmetric robot")
    return {j: out[j] for j in sorted(out, key=lambda j: j in left_of)}, left_of


def _above(fraction: float) -> float:
    """The one-significant-digit fraction just above `fraction` (0.0536 -> 0.06)."""
    exponent = math.floor(math.log10(fraction))
    digit = math.floor(fraction / 10.0 ** exponent) + 1
    return round(digit * 10.0 ** exponent, -exponent)


def mirror_geometry(names: dict[int, str], left_of: dict[int, int], local, joints) -> None:
    """Write the right links' points (`local`: joint -> point -> director components) and
    the right joints' axes and references (`joints`: name -> {"parent", "child", "axis",
    "reference"}) as the left ones' mirror images, and the base's points as their own
    (a point named for a side as its partner's image, any other one on the mirror plane);
    `names`: joint -> link name, `left_of` from `mirrored_inertias` (module docstring).
    Spherical joints (no "axis") are exact in their parents' directors
    (`gait_planner.model.urdf_fuse`), so mirror images once their bodies are."""
    pairs = [(left, right) for right, left in left_of.items()]
    pairs += [(j, j) for j in names if j not in left_of and j not in left_of.values()]
    for left, right in pairs:
        for point, X in list(local[left].items()):
            image = mirror_name(point)[0]
            if image is None or image not in local[right]:
                image = point  # a contact (heel, forefoot) or a point on the mirror plane
            if image not in local[right]:
                raise UrdfError(f"link {names[right]!r} has no point {image!r} to mirror "
                                f"{names[left]!r}'s {point!r}")
            _close(f"link {names[right]!r}: point {image!r}", S @ X, local[right][image],
                   max(np.linalg.norm(X), 0.01))
            if left != right or image != point or abs(X[1]) > 0:
                local[right][image] = S @ X
    rights = {names[j] for j in left_of}
    for name, joint in joints.items():
        other = mirror_name(name)[0]
        if "axis" not in joint or other not in joints or joint["parent"] not in rights and joint["child"] not in rights:
            continue
        left, right = joints[other], joint
        image = -S @ left["axis"]
        sign = 1.0 if image @ right["axis"] >= 0 else -1.0
        _close(f"joint {name!r}: axis", sign * image, right["axis"], 1.0)
        _close(f"joint {name!r}: zero-angle reference", S @ left["reference"] @ S,
               right["reference"], 1.0)
        right["axis"], right["reference"] = sign * image, S @ left["reference"] @ S


def _close(what: str, a, b, scale: float) -> None:
    gap = float(np.max(np.abs(np.asarray(a, float) - np.asarray(b, float))))
    if gap > _SNAP_TOLERANCE * max(float(scale), 1e-300):
        raise UrdfError(f"{what} are not mirror images ({gap:.3g} apart, more than "
                        f"{_SNAP_TOLERANCE:g} relative): the half cycle's mirror "
                        f"periodicity needs a left-right symmetric robot (its joint "
                        f"placements, axes and collision geometry mirrored)")
