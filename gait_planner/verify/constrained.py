"""Continuous constrained dynamics of a scene with ground contacts, in Pinocchio: the model
that `gait_planner.verify.drift` integrates. Nothing here comes from
gait_planner.model, .dynamics or .ocp (the scene is `verify.mechanics.parse_scene`'s data,
the tree `verify.continuous.build_model`'s).

* State: Pinocchio's (q, v), q (nq,) with the root's position and quaternion and one
  quaternion per spherical joint, v (nv,) the root's twist in its body frame and the joint
  rates (spherical: angular velocity in the child frame).
* Held contacts are holonomic constraints p_c(q) = p_c0 anchored where the point is when
  the constraint starts: a body holding a single point is held at that point (3 rows); a
  body holding two or more points (full contact) is fixed entirely (6 rows, the frame of its
  first held point: docs/design.md section 2, two points would leave the roll about the heel-toe
  line free). Planar scenes (free-flyer root, every joint about the lateral axis y) keep the
  in-plane rows only (point: x, z; full contact: x, z, rotation about y) and add the
  planar-root rows (root COM y = the scene's y, no rotation about x or z): with them the
  constraint rows are independent in every phase of the scenes.
* Forward dynamics with the constraint forces lambda (ground on body, world frame; rows as
  above, full contact: force, then moment about the point):
      [M  J^T] [ a ]   [tau - b(q, v)                               ]
      [J   0 ] [-lam] = [-Jdot v - 2 omega J v - omega^2 e(q)          ]
  with J the frame Jacobians (LOCAL_WORLD_ALIGNED), Jdot v the frames' classical
  accelerations at a = 0, e the position error against the anchors. Baumgarte
  stabilisation, critically damped at `BAUMGARTE` rad/s: the index-reduced equations let
  the position error grow from the integration error alone; the feedback keeps it at
  tolerance level, and its rate (50 1/s) is far below what the step sizes of DOP853
  resolve (steps ~1 ms: omega h ~ 0.05), so it adds no stiffness and, acting only on an
  error of the size of the tolerance, no measurable force.
* Plastic impact: v+ = v- - M^-1 J^T (J M^-1 J^T)^-1 J v-, the M-orthogonal projection on
  J v = 0, solved as [M J^T; J 0] [v+; Lambda] = [M v-; 0].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np
import pinocchio as pin

from gait_planner.verify.continuous import build_model
from gait_planner.verify.mechanics import SceneData

BAUMGARTE = 50.0  # rad/s, critically damped constraint stabilisation
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class Block:
    """Constraint rows on one frame: `rows` of its 6D twist (LOCAL_WORLD_ALIGNED: linear,
    then angular); body = the contact body ("" for the planar root); anchor (p0 (3,),
    R0 (3, 3)) of the frame when the constraint started."""

    frame: int
    rows: tuple[int, ...]
    body: str
    anchor: tuple[np.ndarray, np.ndarray]


class ConstrainedModel:
    """The Pinocchio model of `scene` with contact frames (module docstring)."""

    def __init__(self, scene: SceneData):
        self.scene = scene
        self.model, self.joint_of = build_model(scene)
        model = self.model
        self.origin = {scene.root: np.zeros(3)}  # joint origin from the body's COM
        self.origin.update({j.child: np.asarray(j.child_point, float) for j in scene.joints})
        bodies = {b.name: b for b in scene.bodies}
        self.contact_frame = {}
        for name, (body, point) in scene.contacts.items():
            placement = pin.SE3(np.eye(3), bodies[body].points[point] - self.origin[body])
            self.contact_frame[name] = model.addFrame(pin.Frame(
                name, self.joint_of[body], placement, pin.FrameType.OP_FRAME))
        self.root_frame = model.addFrame(pin.Frame(
            "planar_root", self.joint_of[scene.root], pin.SE3.Identity(), pin.FrameType.OP_FRAME))
        self.data = model.createData()
        self.nq, self.nv = model.nq, model.nv
        self.joint_slots = [(j.axis is None, model.getJointId(j.name)) for j in scene.joints]
        self.weight = sum(b.mass for b in scene.bodies) * scene.gravity  # N

    # ------------------------------------------------------------------ kinematics

    def _frames_at(self, q: np.ndarray, v: np.ndarray | None = None) -> None:
        """Joint Jacobians, frame placements and (with v) velocities and a = 0 accelerations."""
        pin.computeJointJacobians(self.model, self.data, q)
        if v is not None:
            pin.forwardKinematics(self.model, self.data, q, v, np.zeros(self.nv))
        pin.updateFramePlacements(self.model, self.data)

    def blocks(self, q: np.ndarray, contacts: Iterable[str]) -> tuple[Block, ...]:
        """The constraint blocks of the held `contacts`, anchored at configuration q."""
        self._frames_at(q)
        held: dict[str, list[str]] = {}
        for name in sorted(contacts, key=list(self.scene.contacts).index):
            held.setdefault(self.scene.contacts[name][0], []).append(name)
        planar = self.scene.planar
        out = []
        for body, names in held.items():
            full = len(names) > 1
            rows = ((0, 2, 4) if full else (0, 2)) if planar else tuple(range(6 if full else 3))
            out.append(self._block(self.contact_frame[names[0]], rows, body))
        if planar:
            out.append(self._block(self.root_frame, (1, 3, 5), ""))
        return tuple(out)

    def _block(self, frame: int, rows: tuple[int, ...], body: str) -> Block:
        M = self.data.oMf[frame]
        return Block(frame, rows, body, (M.translation.copy(), M.rotation.copy()))

    def _error(self, block: Block) -> np.ndarray:
        """Position error (len(rows),) of a block against its anchor (m, rad), after
        `_frames_at`. The planar root: (y - y0, d2_z, -d2_x), the out-of-plane tilt angles
        to first order (its rotation about y is free)."""
        M = self.data.oMf[block.frame]
        p0, R0 = block.anchor
        if not block.body:
            d2 = M.rotation[:, 1]
            return np.array([M.translation[1] - self.scene.root_y, d2[2], -d2[0]])
        e = np.concatenate([M.translation - p0, pin.log3(M.rotation @ R0.T)])
        return e[list(block.rows)]

    def jacobian(self, q: np.ndarray, blocks: tuple[Block, ...]) -> np.ndarray:
        """J (m, nv) of the blocks at configuration q (LOCAL_WORLD_ALIGNED rows)."""
        self._frames_at(q)
        return self._jacobian(blocks)

    def _jacobian(self, blocks: tuple[Block, ...]) -> np.ndarray:
        """J (m, nv) of the blocks, after `_frames_at`."""
        rows = [pin.getFrameJacobian(self.model, self.data, b.frame, _LWA)[list(b.rows)]
                for b in blocks]
        return np.vstack(rows) if rows else np.zeros((0, self.nv))

    def constraint_error(self, q: np.ndarray, blocks: tuple[Block, ...]) -> np.ndarray:
        """Position errors (m,) of the blocks at configuration q (m, rad)."""
        self._frames_at(q)
        return np.concatenate([self._error(b) for b in blocks] + [np.zeros(0)])

    # ------------------------------------------------------------------ dynamics

    def efforts(self, q: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Generalised forces (nv,) of joint torques tau (na,) in scene joint order (the
        plan's convention, `PlanResult.tau`: spherical, the couple's components along the
        parent's directors; revolute, about the axis), after `_frames_at(q)`: Pinocchio's
        spherical effort is the couple in the child frame, R_rel^T t. Root unactuated."""
        out, i = np.zeros(self.nv), 0
        for spherical, jid in self.joint_slots:
            s = self.model.joints[jid].idx_v
            if spherical:
                out[s:s + 3] = self.data.liMi[jid].rotation.T @ tau[i:i + 3]
                i += 3
            else:
                out[s] = tau[i]
                i += 1
        return out

    def forward(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray,
                blocks: tuple[Block, ...]) -> tuple[np.ndarray, np.ndarray]:
        """(a (nv,), lam (m,)): constrained forward dynamics (module docstring); tau (na,)
        joint torques as in `efforts`. Raises LinAlgError on a singular KKT matrix."""
        self._frames_at(q, v)
        J = self._jacobian(blocks)
        drift = np.concatenate([pin.getFrameClassicalAcceleration(
            self.model, self.data, b.frame, _LWA).vector[list(b.rows)] for b in blocks]
            + [np.zeros(0)])
        error = np.concatenate([self._error(b) for b in blocks] + [np.zeros(0)])
        generalised = self.efforts(q, tau)
        M = pin.crba(self.model, self.data, q)
        b = pin.nonLinearEffects(self.model, self.data, q, v)
        m = J.shape[0]
        K = np.block([[M, J.T], [J, np.zeros((m, m))]])
        rhs = np.concatenate([generalised - b,
                              -drift - 2 * BAUMGARTE * (J @ v) - BAUMGARTE ** 2 * error])
        solution = np.linalg.solve(K, rhs)
        return solution[:self.nv], -solution[self.nv:]

    def impact(self, q: np.ndarray, v: np.ndarray, blocks: tuple[Block, ...]) -> np.ndarray:
        """v+ (nv,) after a perfectly plastic impact on the blocks (module docstring)."""
        J = self.jacobian(q, blocks)
        M = pin.crba(self.model, self.data, q)
        m = J.shape[0]
        K = np.block([[M, J.T], [J, np.zeros((m, m))]])
        return np.linalg.solve(K, np.concatenate([M @ v, np.zeros(m)]))[:self.nv]

    def foot_forces(self, lam: np.ndarray, blocks: tuple[Block, ...]) -> dict[str, np.ndarray]:
        """body -> ground force (3,) N, world, from the multipliers of `forward`."""
        out, r = {}, 0
        for b in blocks:
            if b.body:
                F = np.zeros(3)
                linear = [k for k in b.rows if k < 3]
                F[linear] = lam[r:r + len(linear)]
                out[b.body] = F
            r += len(b.rows)
        return out

    # ------------------------------------------------------------------ state maps

    def configuration_rate(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """dq/dt (nq,) of (q, v): root position R v_linear; quaternions (x, y, z, w)
        1/2 q (x) (omega, 0) with omega in the moving frame; revolute angles v."""
        out = np.empty(self.nq)
        for joint in self.model.joints[1:]:
            iq, iv = joint.idx_q, joint.idx_v
            if joint.nq == 7:  # free flyer
                quat = q[iq + 3:iq + 7]
                out[iq:iq + 3] = pin.Quaternion(quat).matrix() @ v[iv:iv + 3]
                out[iq + 3:iq + 7] = _quaternion_rate(quat, v[iv + 3:iv + 6])
            elif joint.nq == 4:  # spherical
                out[iq:iq + 4] = _quaternion_rate(q[iq:iq + 4], v[iv:iv + 3])
            else:
                out[iq] = v[iv]
        return out

    def director_configuration(self, q: np.ndarray) -> np.ndarray:
        """Director coordinates (12 nb,) of Pinocchio's q: phi = joint origin - R origin,
        (d1, d2, d3) = the columns of the joint frame's rotation R."""
        pin.forwardKinematics(self.model, self.data, q)
        out = np.zeros(12 * len(self.scene.bodies))
        for i, body in enumerate(self.scene.bodies):
            M = self.data.oMi[self.joint_of[body.name]]
            out[12 * i:12 * i + 3] = M.translation - M.rotation @ self.origin[body.name]
            out[12 * i + 3:12 * i + 12] = M.rotation.T.reshape(-1)
        return out


def _quaternion_rate(quat: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """d/dt of a unit quaternion (x, y, z, w) turning at omega (3,) in its own frame."""
    u, w = quat[:3], quat[3]
    return 0.5 * np.concatenate([w * omega + np.cross(u, omega), [-u @ omega]])
