"""The state a late command will meet: a Smith predictor for a walk under a torque delay.

A joint that receives its command `delay` s late (`walk.model_error.DelayedTorque`) acts at
t on what the controller saw at t - delay. `DelayPredictor` lets the controller act on the
state the command will meet instead: it copies the measured state at t into its own copy
of the walker as the plan models it (the nominal MuJoCo model: no mass, friction or
contact change, which the controller cannot know) and steps it through the delay with the
commands already sent and not yet arrived, each joint's own PD (kp q, and MuJoCo's joint
damping) acting on the predicted state as the real joint's does. The controller then
computes the command for t + delay from that state (a late command read ahead in time,
the standard cure of a known dead time: O. J. M. Smith, "Closer control of loops with dead
time", Chem. Eng. Prog. 53, 1957).

The commands in flight are `DelayedTorque`'s own queue (in its form: the joint torque plus
kp q, so that each joint's own position term is taken out), read, not copied.
"""

from __future__ import annotations

import numpy as np

from gait_planner.walk.model_error import DelayedTorque

__all__ = ["DelayPredictor"]


class DelayPredictor:
    """`__call__(data)`: the nominal walker's MjData as many simulation steps after the
    measured state `data` as `delayed` delays (its kinematics current, `mj_step1`; its time
    advanced), the commands in flight of `delayed` applied (before the first command is
    sent: `data`'s state, not advanced). kp: N m/rad, the joints' own position gain; dofs
    and qpos: the MuJoCo addresses of the plan's joint angles."""

    def __init__(self, model, delayed: DelayedTorque, kp: float, dofs: np.ndarray,
                 qpos: np.ndarray):
        import mujoco

        self.model, self.data, self.delayed = model, mujoco.MjData(model), delayed
        self.kp, self.dofs, self.qpos = kp, dofs, qpos

    def __call__(self, data):
        import mujoco

        model, d = self.model, self.data
        d.time = data.time
        d.qpos[:], d.qvel[:] = data.qpos, data.qvel
        d.qacc_warmstart[:] = data.qacc_warmstart
        # the queue holds the commands of the last steps + 1 steps; the oldest was applied
        for command in list(self.delayed.queue)[1:]:
            d.qfrc_applied[:] = 0.0
            d.qfrc_applied[self.dofs] = command - self.kp * d.qpos[self.qpos]
            mujoco.mj_step(model, d)
        mujoco.mj_step1(model, d)
        return d
