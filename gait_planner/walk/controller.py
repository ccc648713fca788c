"""The reference stabilising controller of a walk.

Joint torques = scale x the plan's efforts (feed-forward) + joint PD against the plan's
angles and rates + the torso attitude feedback: the torque the torso needs to return to the
plan's attitude, -kp e - kd (w - w_ref) (e the rotation vector of D D_ref^T, world), made by
the hips of the legs in contact in the plan (the reaction of a hip torque acts on the torso;
split evenly between the stance legs). A joint PD alone cannot correct the floating base.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gait_planner.model.scene import Scene

__all__ = ["Gains", "hip_legs", "torso_torque", "rotation_error"]


@dataclass(frozen=True)
class Gains:
    kp: float  # N m/rad, joints
    kd: float  # N m s/rad, joints
    torso_kp: float  # N m/rad
    torso_kd: float  # N m s/rad


def hip_legs(scene: Scene, joint_names) -> list[tuple[list[int], set[str]]]:
    """Per joint on the root: (indices of its angles in `joint_names`, the contacts below it)."""
    children: dict[str, list[str]] = {}
    for j in scene.joints:
        children.setdefault(j.parent, []).append(j.child)
    legs = []
    for joint in scene.joints:
        if joint.parent != scene.root.body:
            continue
        below, todo = set(), [joint.child]
        while todo:
            body = todo.pop()
            below.add(body)
            todo += children.get(body, [])
        contacts = {c.name for c in scene.contacts if c.body in below}
        legs.append(([list(joint_names).index(a) for a in joint.angle_names], contacts))
    return legs


def rotation_error(D: np.ndarray, D_ref: np.ndarray) -> np.ndarray:
    """Rotation vector (world) of D D_ref^T, small-angle form."""
    R = D @ D_ref.T
    return 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])


def torso_torque(gains: Gains, D, D_ref, w, w_ref, axes: np.ndarray) -> np.ndarray:
    """Hip torques (one per row of `axes`, the stance hips' joint axes in world) whose
    reaction on the torso is the attitude feedback."""
    tau = -gains.torso_kp * rotation_error(D, D_ref) - gains.torso_kd * (w - w_ref)
    return -(axes @ tau)
