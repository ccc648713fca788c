"""What holds a drafted robot's locked joints: the data of their holding efforts.

A draft (`gait_planner.model.urdf_import`) locks every joint outside the legs and merges
its links into a leg body or the base, so the planner never sees them move. A real robot
still has to hold them: the waist's actuator carries the torso and arms through every
step, and its torque is bounded by the URDF's ``<limit effort>`` like any leg joint's.
On Unitree G1 the locked waist roll needed 62 N m against its 35 (issue #61).

A locked joint j inside body B moves rigidly with B, so what holds it follows from B's
motion alone: one side of the joint (its *held part*) is acted on only by gravity and by
the joint, and the joint's effort is the moment that part needs about the joint's axis
(`gait_planner.ocp.held_efforts`). The held part is j's subtree when no leg hangs below
j (a waist, a shoulder, an elbow: `side` +1); otherwise, in the base only, the rest of
the base when the legs all hang below j (a waist between a torso base and the pelvis:
`side` -1, the effort being the reaction). A joint with legs on both sides, or with
legs below it in a leg body, cannot be held this way and gets no row (`skipped`).

Each hold is written to the scene (``robot.holds``) in its body's director frame (origin
at B's centre of mass, axes its directors), at the draft pose:

    waist_roll_joint: {body: pelvis, side: 1, effort: 35.0,   # N m, the URDF's limit
                       axis: [..], point: [..],               # unit; m
                       mass: 15.2, com: [..],                 # kg; m
                       inertia: [ixx, iyy, izz, ixy, ixz, iyz]}  # kg m^2 at the part's COM
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from gait_planner.model.urdf_errors import UrdfError
from gait_planner.model.urdf_read import revolute_axis

__all__ = ["locked_holds"]


def locked_holds(full, q_lock: np.ndarray, legs: Sequence[int], owner: dict[int, tuple],
                 ) -> tuple[dict[str, dict], list[str]]:
    """({locked joint: hold}, [skipped joint: reason]) of a URDF's Pinocchio `full` model
    (free-flyer base joint 1) at configuration `q_lock` (base at identity, legs at zero,
    locked joints at their angle).

    legs: the full model's planned joint ids; owner: the joint id of each drafted body in
    the full model (1: the base) -> (name, centre of mass (3,) and principal axes R (3, 3)
    in that joint's frame): the body's director frame. Joints with no positive finite
    effort limit, and prismatic ones, are left out (nothing to bound)."""
    import pinocchio as pin  # noqa: PLC0415 - the importer's dependency

    data = full.createData()
    pin.forwardKinematics(full, data, q_lock)
    leg_set = set(legs)
    holds, skipped = {}, []
    for j in range(2, full.njoints):
        if j in leg_set:
            continue
        name, joint = full.names[j], full.joints[j]
        limit = float(full.effortLimit[joint.idx_v]) if joint.nv == 1 else 0.0
        try:
            axis = revolute_axis(full, j)
        except UrdfError:  # prismatic, planar, ...: no torque to bound
            continue
        if not 0.0 < limit < 1e10:
            continue
        body = _owner(full, j, leg_set)
        below = set(full.subtrees[j])
        if not below & leg_set:
            side, part = 1.0, sorted(below)
        elif body == 1 and not _legs_above(full, leg_set, below):
            side, part = -1.0, [i for i in _merged(full, 1, leg_set) if i not in below]
        else:
            skipped.append(f"{name}: legs hang on both sides of it")
            continue
        body_name, com, R = owner[body]
        to_body = data.oMi[body].inverse()
        inertia = pin.Inertia.Zero()
        for i in part:
            inertia += (to_body * data.oMi[i]).act(full.inertias[i])
        if inertia.mass <= 0.0:
            continue
        placement = to_body * data.oMi[j]
        c = R.T @ (np.asarray(inertia.lever) - com)
        I = R.T @ np.asarray(inertia.inertia) @ R
        holds[name] = {
            "body": body_name, "side": int(side), "effort": limit,
            "axis": _round(R.T @ placement.rotation @ axis),
            "point": _round(R.T @ (placement.translation - com)),
            "mass": round(float(inertia.mass), 12), "com": _round(c),
            "inertia": _round([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])}
    return holds, skipped


def _owner(full, j: int, legs: set[int]) -> int:
    """The drafted body a locked joint is merged into: its nearest leg-joint ancestor,
    or the base (1)."""
    while j > 1 and j not in legs:
        j = int(full.parents[j])
    return j


def _merged(full, body: int, legs: set[int]) -> list[int]:
    """The full model's joints whose links are merged into drafted body `body`."""
    return [i for i in range(1, full.njoints)
            if (i == body or i not in legs) and _owner(full, i, legs) == body]


def _legs_above(full, legs: set[int], below: set[int]) -> bool:
    """Whether a leg hangs from a link outside `below` (a locked joint's subtree)."""
    return any(int(full.parents[i]) not in legs | below for i in legs)


def _round(v, digits: int = 12) -> list[float]:
    return [round(float(x), digits) + 0.0 for x in v]
