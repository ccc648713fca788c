"""The torso's position carried by the legs on the ground.

A walker that falls behind its plan cannot catch up by its joints' PD: they track angles,
and the torso's place over the feet is the floating base's, which no joint drives. In a
phase on a flat foot, or on two feet, the legs can push it, by changing the forces the
ground puts on the feet. `position_torques` finds the joint torques that give the torso's
centre of mass an extra acceleration (m/s^2), and its attitude none, while every foot point
on the ground stays where it is, a small change to the motion and the forces:

    minimise  |J_task a - a_task|^2 + (W_JOINT |a_joints|)^2 + (W_FORCE |df|)^2
    subject to (weighted rows)  M_b a = J_b^T df   (the floating base's rows of M a + h =
                                                    S^T tau + J^T f, for the changes)
                                J a = 0              (the points on the ground stay put)

and returns dtau = (M a - J^T df)_joints, the joints' rows of the same equation. M (nv, nv)
is the walker's mass matrix at its state, J (3 k, nv) the k touching points' translation
Jacobians, J_task (6, nv) the torso centre of mass's translation and rotation Jacobians,
a_task (6,) the extra acceleration asked of them (the walk asks none of the rotation: the
torso's attitude has its own loop, and a lean is the cheapest way to move a centre of
mass that the legs would otherwise be asked to carry). The velocity-product terms (J_dot v)
are left out: the correction is a change of acceleration at the walker's state. Where the
legs cannot give a_task (on one point: the torso is a pendulum about it), the least-squares
solution gives what they can; in the air, nothing; on a state that is not finite (a
simulation that diverged, which the walk then stops on), nothing.

The walk asks for a_task = kp (p_ref - p) + kd (v_ref - v) of the torso's centre of mass
(config/walk.yaml `torso.position_kp`, `position_kd`; `walk.controller`). Measured on
walker3d's 10 deg ramp up (2026-11-30, benchmarks/HISTORY.md): without it the walker fell
4-9 cm behind its plan every half cycle, its stance foot creeping back on MuJoCo's soft
friction; with MuJoCo's no-slip solver and this loop it walks 10 of 10.
"""

from __future__ import annotations

import numpy as np

__all__ = ["position_torques", "W_DYNAMICS", "W_CONTACT", "W_JOINT", "W_FORCE"]

W_DYNAMICS = 100.0  # the floating base's rows: nearly exact (units: N, N m)
W_CONTACT = 30.0  # touching points stay put (m/s^2)
W_JOINT = 0.1  # joint accelerations kept small (rad/s^2): the torso moves, not the legs
W_FORCE = 1e-3  # force changes kept small (N): resolves the indeterminate share of two feet


def position_torques(M: np.ndarray, J: np.ndarray, J_task: np.ndarray, a_task: np.ndarray,
                     base: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """Joint torque changes (len(joints),) N m of the module docstring.

    M (nv, nv) kg, kg m, kg m^2; J (3 k, nv) the touching points' Jacobians (k may be 0);
    J_task (6, nv) the torso's translation and rotation Jacobians; a_task (6,) m/s^2 and
    rad/s^2; base and joints:
    the dof indices of the floating base and of the joints (together every dof)."""
    nv, nf = M.shape[0], J.shape[0]
    if nf == 0 or not all(np.isfinite(x).all() for x in (M, J, J_task, a_task)):
        return np.zeros(len(joints))  # in the air; or a diverged state, which the walk stops on
    rows = [np.hstack([W_DYNAMICS * M[base], -W_DYNAMICS * J.T[base]]),
            np.hstack([W_CONTACT * J, np.zeros((nf, nf))]),
            np.hstack([J_task, np.zeros((len(J_task), nf))]),
            np.hstack([W_JOINT * np.eye(nv)[joints], np.zeros((len(joints), nf))]),
            np.hstack([np.zeros((nf, nv)), W_FORCE * np.eye(nf)])]
    rhs = np.concatenate([np.zeros(len(base) + nf), a_task, np.zeros(len(joints) + nf)])
    try:
        x = np.linalg.lstsq(np.vstack(rows), rhs, rcond=None)[0]
    except np.linalg.LinAlgError:  # a state far off any walk (huge values): no correction
        return np.zeros(len(joints))
    a, df = x[:nv], x[nv:]
    return (M @ a - J.T @ df)[joints]
