"""Joint couples of a recording: from the recorded body couples (leaves first along the
tree), from the published efforts (conjugate to the joint angles), and their mirror images
at the periodic end. Part of the independent verifier: numpy only, no planner code."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from gait_planner.verify.mechanics import MIRROR, Mechanics, SceneData


def _norm(v) -> float:
    return float(np.linalg.norm(v))


def joint_couples(scene: SceneData, couples: np.ndarray) -> np.ndarray:
    """Joint couples (nodes, nj, 3) from body couples (nodes, nb, 3) on the tree: a joint
    acts +m_j on its child and -m_j on its parent, so, leaves first,
    m_j = m_child + sum of the couples of the joints whose parent is the child."""
    index = {j.name: i for i, j in enumerate(scene.joints)}
    out = np.zeros((couples.shape[0], len(scene.joints), 3))
    for j in reversed(scene.joints):  # tree order reversed: children before parents
        m = couples[:, scene.body_index(j.child)].copy()
        for k in scene.joints:
            if k.parent == j.child:
                m += out[:, index[k.name]]
        out[:, index[j.name]] = m
    return out


def effort_couples(scene: SceneData, mech: Mechanics, q: np.ndarray, effort: np.ndarray,
                    slots: dict) -> np.ndarray:
    """World couples (N+1, nj, 3) of the recorded efforts, node n expressed with q_n.

    The recording's efforts are conjugate to the joint angles (gait_planner.io.messages):
    revolute, the torque about the axis D_p n; spherical, the couple's projections on the
    pitch axis d2 of the parent, the roll axis and the yaw axis d3 of the child. For
    R_rel = Ry(pitch) Rx(roll) Rz(yaw) the roll axis Ry(pitch) e1 (parent components) is
    normal to the other two: in world components it is (d2_p x d3_c) / cos(roll). The
    couple follows from the 3x3 system A^T m = effort, A = [d2_p, roll axis, d3_c]."""
    out = np.zeros((q.shape[0], len(scene.joints), 3))
    for n in range(q.shape[0]):
        for ji, j in enumerate(scene.joints):
            Dp = mech.directors(q[n], j.parent)
            e = effort[n, slots[j.name]]
            if j.axis is not None:
                out[n, ji] = float(e[0]) * (Dp @ j.axis)
                continue
            pitch_axis, yaw_axis = Dp[:, 1], mech.directors(q[n], j.child)[:, 2]
            roll_axis = np.cross(pitch_axis, yaw_axis)
            roll_axis = roll_axis / max(_norm(roll_axis), 1e-300)
            A = np.column_stack([pitch_axis, roll_axis, yaw_axis])
            out[n, ji] = np.linalg.lstsq(A.T, e, rcond=None)[0]
    return out


def effort_slots(scene: SceneData, names: Sequence[str]) -> dict[str, list[int]] | str:
    """joint -> indices of its effort components in the JointTrajectory, or a failure."""
    slots = {}
    for j in scene.joints:
        wanted = list(j.angles)
        missing = [w for w in wanted if w not in names]
        if missing:
            return f"the JointTrajectory names no effort slots {missing} of joint {j.name}"
        slots[j.name] = [list(names).index(w) for w in wanted]
    return slots


def periodic_torque_error(scene: SceneData, couples: np.ndarray, N: int) -> float:
    """Largest relative difference between the joint couples of nodes N-1, N (world, at
    q_{N-1}, q_N) and the mirror images of those of nodes 0, 1: a couple m mirrors to
    -S m on the partner joint, or to +S m when the mirror swaps the joint's parent and child
    (the couple then acts on the other body)."""
    by_bodies = {(j.parent, j.child): i for i, j in enumerate(scene.joints)}
    scale = max(float(np.abs(couples[[0, 1, N - 1, N]]).max()), 1e-300)
    error = 0.0
    for i, j in enumerate(scene.joints):
        p, c = scene.mirror[j.parent], scene.mirror[j.child]
        if (p, c) in by_bodies:
            sign, partner = -1.0, by_bodies[(p, c)]
        elif (c, p) in by_bodies:
            sign, partner = 1.0, by_bodies[(c, p)]
        else:
            return math.inf
        for src, dst in ((0, N - 1), (1, N)):
            image = sign * MIRROR * couples[src, i]
            error = max(error, _norm(couples[dst, partner] - image) / scale)
    return error
