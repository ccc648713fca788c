"""Where a drafted plan's frames sit on the robot's own links (`gait_planner.walk.mujoco_model`).

A scene drafted from a URDF (`gait_planner.model.urdf_import`) describes each body by its
centre of mass and its principal axes (directors), not by the URDF link's frame. The walk
needs, on the MuJoCo bodies of the original URDF, the root body's centre of mass and
directors (the plan's root state) and every contact point. `director_frames(model, scene)`
finds them by matching the two kinematic trees at the zero pose (all joint angles zero in
both, the scene's root at the origin with D = I, MuJoCo's root link at the origin with its
axes): the scene's joint points P and MuJoCo's joint anchors Q are the same points seen from
two frames, Q = R P + t (Kabsch: the proper rotation minimising the squared distances), so
the root's directors are R and its centre of mass is t in the root link's frame; every
scene frame then maps into its own link's frame through the anchors' common frame. Nothing
of the draft's conventions (eigenvector ordering, mirror symmetrisation) is re-derived: the
scene itself is matched. ValueError if the anchors do not fit to `FIT_TOLERANCE` (the URDF
is not the scene's robot, or a locked joint is not at the draft's angle) or lie on a line.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gait_planner.model.angles import configuration
from gait_planner.model.scene import Scene

__all__ = ["FIT_TOLERANCE", "SiteFrame", "director_frames", "kabsch"]

FIT_TOLERANCE = 1e-4  # m, largest distance of a joint anchor from the scene's joint point (the
#                       draft writes mirror images within 1e-3 relative: iCub's joints 6.5 um)


@dataclass(frozen=True)
class SiteFrame:
    """A frame on a MuJoCo body: `pos` (3,) m and `R` (3, 3) (columns: the frame's axes)
    in the body's frame."""

    body: str
    pos: np.ndarray
    R: np.ndarray


def kabsch(P: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(R, t, residual m): the proper rotation and shift minimising sum |R p + t - q|^2 over
    the rows of P and Q (n, 3), and the largest remaining distance; ValueError if the
    points lie on a line (the rotation about it is undetermined)."""
    p0, q0 = P.mean(axis=0), Q.mean(axis=0)
    A, B = P - p0, Q - q0
    if np.linalg.matrix_rank(A, tol=1e-6 * max(np.abs(A).max(), 1e-12)) < 2:
        raise ValueError("the joint points lie on a line: the frames cannot be matched")
    U, _, Vt = np.linalg.svd(B.T @ A)
    R = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    t = q0 - R @ p0
    return R, t, float(np.linalg.norm(P @ R.T + t - Q, axis=1).max())


def director_frames(model, scene: Scene) -> tuple[SiteFrame, dict[str, SiteFrame]]:
    """(the root body's centre of mass and directors, each contact point (axes those of its
    link)) on the bodies of a compiled MuJoCo `model` of the robot (module docstring): its
    root link welded at the origin (no root joint yet), a hinge or slide for every scene
    joint, named like it."""
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    pose = replace(scene.initial_pose, root_position=(0.0, 0.0, 0.0),
                   root_angles=(0.0, 0.0, 0.0), joint_angles={})
    frames = {b.name: (row[:3], row[3:].reshape(3, 3).T)
              for b, row in zip(scene.bodies, configuration(scene, pose).reshape(-1, 12))}
    P, Q = [], []
    for joint in scene.joints:
        phi, D = frames[joint.parent]
        P.append(phi + D @ np.asarray(scene.body(joint.parent).points[joint.parent_point]))
        Q.append(data.xanchor[model.joint(joint.name).id])
    R, t, residual = kabsch(np.array(P), np.array(Q))
    if residual > FIT_TOLERANCE:
        raise ValueError(f"the URDF's joints are not scene {scene.name!r}'s: at the zero pose "
                         f"a joint anchor lies {residual:.3g} m from the scene's joint point "
                         f"(more than {FIT_TOLERANCE:g} m)")

    def on_link(body: str, point: np.ndarray, axes: np.ndarray | None = None) -> SiteFrame:
        """A scene point and axes (root director frame) on `body`'s link; axes None: the
        link's own."""
        b = model.body(body).id
        X = data.xmat[b].reshape(3, 3)
        return SiteFrame(body, X.T @ (R @ point + t - data.xpos[b]),
                         np.eye(3) if axes is None else X.T @ R @ axes)

    phi, D = frames[scene.root.body]
    contacts = {}
    for c in scene.contacts:
        phi_c, D_c = frames[c.body]
        contacts[c.name] = on_link(c.body, phi_c + D_c @ np.asarray(
            scene.body(c.body).points[c.point]))
    return on_link(scene.root.body, phi, D), contacts
