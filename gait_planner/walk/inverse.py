"""MuJoCo's inverse dynamics along a recorded plan: is the simulated walker the planned one?

`plan_inverse(rec)` builds the walk's MuJoCo model (`walk.mujoco_model`, without joint
damping and with contacts off), puts it on the plan's configuration at every inner node
n = 1..N-1 and reads the joint torques MuJoCo needs for the plan's motion under the plan's
ground forces (`mujoco.mj_inverse`):

* velocities and accelerations are the differences the integrator's node equation sees, as
  in the Pinocchio certificate (`gait_planner.verify.continuous`): xi+ = (q_{n+1} - q_n)/h_n,
  xi- = (q_n - q_{n-1})/h_{n-1} (both at q_n, `mj_differentiatePos`), a = (xi+ - xi-)/w_n,
  w_n = (h_{n-1} + h_n)/2; the velocity terms are the average of those of xi- and xi+,
  weighted h_{n-1} : h_n (a velocity jump at an impact then leaves no spurious Coriolis term);
* the recorded ground wrench on each foot (`verify.continuous.foot_wrenches_of_recording`)
  acts on the foot's body (`mj_applyFT`) and its generalised force is taken off
  qfrc_inverse;
* each plan joint angle is a MuJoCo hinge (the URDF splits a spherical joint into pitch,
  roll and yaw hinges), so its generalised force is the torque conjugate to the angle, the
  published effort's convention; the root's dofs give the base residual, the force (N,
  world) and moment (N m, world, about the root's centre of mass) nothing in the plan
  supplies (planar root: x and z force, y moment).

`inertia` replaces bodies' principal moments (name -> (J1, J2, J3) about d1, d2, d3) after
compiling, e.g. the scene's non-realisable torso that the URDF cannot carry
(`gait_planner.io.urdf.realisable_inertia`): MuJoCo's dynamics only need the tensor.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from gait_planner.io.mcap_reader import RecordedPlan
from gait_planner.verify.continuous import foot_wrenches_of_recording
from gait_planner.verify.mechanics import parse_scene
from gait_planner.verify.physical import near_switch, switch_nodes

__all__ = ["PlanInverse", "plan_inverse"]


@dataclass(frozen=True)
class PlanInverse:
    """At the inner nodes (n_in = N - 1): nodes, times (s); torque and effort (n_in, na) N m,
    MuJoCo's joint torques and the plan's efforts, columns `joint_names`; base (n_in, 6)
    residual force N and moment N m (world; planar: (n_in, 3) = f_x, f_z, m_y); near_switch
    (n_in,) a node whose held contacts change, or a neighbour; peak (N m) max |effort| (1 if 0);
    weight (N) m g."""

    joint_names: tuple[str, ...]
    nodes: np.ndarray
    times: np.ndarray
    torque: np.ndarray
    effort: np.ndarray
    base: np.ndarray
    near_switch: np.ndarray
    peak: float
    weight: float

    def error(self, switches: bool = False) -> np.ndarray:
        """(na,) max |torque - effort| / peak per joint, over the nodes away from contact
        switches (or at them, `switches`)."""
        rows = np.abs(self.torque - self.effort)[self.near_switch == switches]
        return rows.max(axis=0, initial=0.0) / self.peak


def plan_inverse(rec: RecordedPlan, inertia: Mapping[str, tuple[float, float, float]] | None = None
                 ) -> PlanInverse:
    """MuJoCo's joint torques along the recorded plan (module docstring)."""
    import mujoco

    from gait_planner.walk.mujoco_model import build_model, plan_qpos, set_inertia
    from gait_planner.walk.reference import scene_of

    scene = scene_of(rec)
    # no joint damping; contacts off, so the feet's spheres and the time step do not enter
    wm = build_model(rec, scene, half_width=0.05, radius=0.005, time_step=1e-3,
                     time_constant=0.005, damping=0.0)
    model = wm.model
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    set_inertia(model, inertia or {})
    data = mujoco.MjData(model)
    data_scene = parse_scene(rec.scene_text)
    wrenches, _ = foot_wrenches_of_recording(rec, data_scene)
    i_root = scene.body_index(scene.root.body)
    qpos = [plan_qpos(wm, i_root, row, a) for row, a in zip(rec.q, rec.positions)]
    h = np.diff(rec.times)
    n_nodes, root = len(rec.times), model.body(wm.root).id
    torque, base = [], []
    for n in range(1, n_nodes - 1):
        xi_p, xi_m = np.zeros(model.nv), np.zeros(model.nv)
        mujoco.mj_differentiatePos(model, xi_p, h[n], qpos[n], qpos[n + 1])
        mujoco.mj_differentiatePos(model, xi_m, h[n - 1], qpos[n], qpos[n - 1])
        xi_m = -xi_m
        tau = np.zeros(model.nv)
        for v, weight in ((xi_m, h[n - 1]), (xi_p, h[n])):
            data.qpos[:], data.qvel[:] = qpos[n], v
            data.qacc[:] = (xi_p - xi_m) / (0.5 * (h[n - 1] + h[n]))
            mujoco.mj_inverse(model, data)
            tau += weight / (h[n - 1] + h[n]) * data.qfrc_inverse
        ground = np.zeros(model.nv)
        for body, w in wrenches.items():  # wrench about the world origin
            mujoco.mj_applyFT(model, data, w[n, :3].copy(), w[n, 3:].copy(), np.zeros(3),
                              model.body(body).id, ground)
        tau -= ground
        torque.append(tau[wm.dof])
        if wm.planar:
            base.append(tau[:3])
        else:  # free joint: world force, moment in the root's frame
            base.append(np.r_[tau[:3], data.xmat[root].reshape(3, 3) @ tau[3:6]])
    effort = np.asarray(rec.effort, dtype=float)
    mass = float(np.sum(model.body_mass))
    return PlanInverse(
        tuple(rec.joint_names), np.arange(1, n_nodes - 1), rec.times[1:-1], np.array(torque),
        effort[1:-1], np.array(base),
        near_switch(n_nodes, switch_nodes(tuple(map(tuple, rec.active_contacts))))[1:-1],
        float(np.abs(effort).max()) or 1.0, mass * float(-model.opt.gravity[2]))
