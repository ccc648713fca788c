"""The simulated walker and one step of its control, shared by the walk of one plan
(`walk.walk_plan.walk`) and the walk that re-plans (`walk.replan`).

`Simulation.build(rec, scene, cfg, robot, model_error)` makes the MuJoCo walker of a
recording (`walk_model`) with the controller's gains, the model error applied and
its torque delay (with config delay.predict, the prediction through the nominal walker,
`walk.predictor`). `step(control, clock, ref, touches, slides)` advances it by one time step
under `control` (`walk.controller.ReferenceController`) at the plan's time `clock(t)`: the
kinematics of the current state, the control on it, then the step (mj_step1/2), so that
what a step reports is all of one state; the ground forces of that state feed the touches
and slides and the loaded points go back to the controller (the caller paces the plan's
clock, `walk.clock`, by the walker's progress).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from gait_planner.walk.controller import Gains
from gait_planner.walk.model_error import DelayedTorque, ModelError
from gait_planner.walk.predictor import DelayPredictor
from gait_planner.walk.robot_urdf import RobotUrdf

__all__ = ["Simulation", "Step", "foot_half_width", "ground_forces", "walk_model"]


def foot_half_width(rec) -> float:
    """m: the half width of the feet the recording's plan assumes (its metadata; the
    planner's default for a recording without it)."""
    return float(rec.metadata.get("foot_half_width", 0.04575))


def walk_model(rec, scene, cfg: dict[str, Any], robot: RobotUrdf | None = None):
    """The MuJoCo walker (`walk.mujoco_model.WalkModel`) of the recording `rec` of `scene`
    with the simulation and joint damping of the controller's parameters `cfg`
    (`load_config`), on the robot's own URDF if given."""
    from gait_planner.walk.mujoco_model import build_model

    sim = cfg["simulation"]
    return build_model(rec, scene, foot_half_width(rec), sim["foot_sphere_radius"],
                       sim["time_step"], sim["contact_time_constant"], cfg["joints"]["kd"],
                       robot, int(sim["noslip_iterations"]))


def ground_forces(model, data, wm) -> np.ndarray:
    """(n_contacts, 3) N, world: the ground's force on each planned contact point's foot
    geometry (`WalkModel.geom_contact`), summed, from the contacts MuJoCo solved in the last
    step."""
    import mujoco

    force = np.zeros(6)
    per_point = np.zeros((len(wm.contact_sites), 3))
    for c in range(data.ncon):
        geoms = (data.contact[c].geom1, data.contact[c].geom2)
        ground_first = wm.geom_contact[geoms[0]] < 0  # geom1: the plane or a tread
        foot = geoms[1] if ground_first else geoms[0]
        mujoco.mj_contactForce(model, data, c, force)
        # the contact frame's rows are its axes, the first the normal, from geom1 to geom2
        f = data.contact[c].frame.reshape(3, 3).T @ force[:3]
        per_point[wm.geom_contact[foot]] += f if ground_first else -f
    return per_point


@dataclass(frozen=True)
class Step:
    """What one step saw: the command's parts (na,) N m (feed-forward, feedback, the plan's
    efforts), the plan's angles (na,) rad and the tracking error (na,) rad; the torso's
    centre of mass (3,) m, the plan's root position (3,) m and directors (3, 3) and the
    torso's tilt from them (deg), the simulated time (s) and the plan's time tau (s) of the
    state, the ground forces (n_contacts, 3) N solved in the step."""

    ff: np.ndarray
    fb: np.ndarray
    plan_effort: np.ndarray
    plan_angles: np.ndarray
    error: np.ndarray
    com: np.ndarray
    phi_ref: np.ndarray
    D_ref: np.ndarray
    tilt: float
    time: float
    tau: float
    forces: np.ndarray


@dataclass
class Simulation:
    """A MuJoCo walker under the reference controller (module docstring)."""

    wm: Any  # walk.mujoco_model.WalkModel
    data: Any  # mujoco.MjData
    gains: Gains
    delayed: DelayedTorque | None
    predictor: DelayPredictor | None
    factors: dict  # the model error's mass factors as drawn
    model_error: ModelError | None  # how the walker differs from the plan's model

    @property
    def model(self):
        return self.wm.model

    @classmethod
    def build(cls, rec, scene, cfg: dict[str, Any], robot: RobotUrdf | None = None,
              model_error: ModelError | None = None) -> "Simulation":
        import mujoco

        wm = walk_model(rec, scene, cfg, robot)
        factors = model_error.apply(wm.model) if model_error is not None else {}
        delay_steps = (round(model_error.torque_delay / wm.model.opt.timestep)
                       if model_error is not None else 0)
        delayed = DelayedTorque(delay_steps) if delay_steps else None
        predictor = None
        if delayed is not None and cfg["delay"]["predict"]:  # the nominal walker: no error
            predictor = DelayPredictor(walk_model(rec, scene, cfg, robot).model, delayed,
                                       cfg["joints"]["kp"], wm.dof, wm.qpos)
        place, torso = cfg["placement"], cfg["torso"]
        gains = Gains(cfg["joints"]["kp"], cfg["joints"]["kd"], torso["kp"], torso["kd"],
                      place["kp"], place["kd"], place["height_kp"], torso["position_kp"],
                      torso["position_kd"], place["swing_margin"])
        return cls(wm, mujoco.MjData(wm.model), gains, delayed, predictor, factors,
                   model_error)

    def model_error_summary(self) -> dict:
        """A walk summary's entry: {"model_error": {"differences": in words,
        "mass_factors": as drawn, by body}} for a walker built with a model error, else
        {}."""
        if self.model_error is None:
            return {}
        return {"model_error": {"differences": self.model_error.describe(),
                                "mass_factors": self.factors}}

    def weight(self) -> float:
        """N: the walker's weight."""
        return float(np.sum(self.model.body_mass)) * float(-self.model.opt.gravity[2])

    def place(self, ref) -> None:
        """Set the walker at the plan's node 0, with the root's rates there
        (`Reference.root_rate0`) and the joints at the node's rates."""
        from gait_planner.walk.mujoco_model import plan_qpos, plan_root_qvel

        scene, data = ref.scene, self.data
        i_root = scene.body_index(scene.root.body)
        data.qpos[:] = plan_qpos(self.wm, i_root, ref.q[0], ref.angles[0])
        root_qvel = plan_root_qvel(self.wm, ref.root_at(float(ref.times[0]))[1],
                                   *ref.root_rate0)
        data.qvel[:len(root_qvel)] = root_qvel
        data.qvel[self.wm.dof] = ref.rates[0]

    def step(self, control, clock, ref, touches, slides,
             before: Callable[[Any, float], None] | None = None) -> Step:
        """One time step (module docstring); before(data, tau) is called with the state the
        step starts from, its kinematics computed, before it is advanced."""
        import mujoco

        model, data, wm, gains = self.model, self.data, self.wm, self.gains
        mujoco.mj_step1(model, data)
        t_sim, t = data.time, clock(data.time)
        # under a delay with prediction: the command for the state it will meet
        state = self.predictor(data) if self.predictor is not None else data
        ff, fb, plan_effort, plan_angles = control(state)
        if self.predictor is not None:  # tracking is judged against the plan now
            plan_angles = ref.at(t)[0]
        data.qfrc_applied[:] = 0.0
        # -kd v is MuJoCo's (implicit) joint damping (walk.mujoco_model)
        torque = ff + fb + gains.kd * state.qvel[wm.dof]
        if self.delayed is not None:  # the command late, the joint's own kp q now
            torque = self.delayed(torque + gains.kp * state.qpos[wm.qpos],
                                  gains.kp * data.qpos[wm.qpos])
        data.qfrc_applied[wm.dof] = torque
        error = plan_angles - data.qpos[wm.qpos]
        com = data.site_xpos[wm.root_site].copy()
        phi_ref, D_ref = ref.root_at(t)
        tilt = math.degrees(math.acos(np.clip(
            data.site_xmat[wm.root_site].reshape(3, 3)[:, 2] @ D_ref[:, 2], -1, 1)))
        if before is not None:
            before(data, t)
        mujoco.mj_step2(model, data)
        forces = ground_forces(model, data, wm)  # of that state, solved in mj_step2
        normal = forces @ ref.normal  # the normal force on each point
        touches.update(t, normal)
        slides.update(t_sim, forces, normal,
                      data.site_xpos[wm.contact_sites])
        control.loaded = {name for name, f in zip(touches.names, normal)
                          if f > touches.threshold}
        return Step(ff, fb, plan_effort, plan_angles, error, com, phi_ref, D_ref, tilt, t_sim,
                    t, forces)
