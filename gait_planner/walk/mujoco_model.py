"""The walker in MuJoCo: the recording's own /robot_description with the planned feet.

`build_model(rec, scene, settings)` loads the URDF (`gait_planner.io.urdf`: links on the
directors, the root link's origin at its centre of mass), gives the root the scene's
freedom (free: a free joint; planar: slides along x and z and a hinge about y), adds the
ground plane z = 0 and, at every planned contact point, two spheres at +-foot_half_width
along the foot's d2, their lowest points on the contact point when the foot is level: a
point contact as the plan assumes, and a foot that can carry the full-contact roll moment
(up to the normal force times foot_half_width) the plan allows. The joint PD's damping
-kd v is the joints' MuJoCo damping (implicit: the feet's small inertias make an explicit
kd unstable at any practical step); the controller adds kd v_ref.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gait_planner.io.mcap_reader import RecordedPlan
from gait_planner.model.scene import Scene

__all__ = ["WalkModel", "build_model"]


@dataclass(frozen=True)
class WalkModel:
    model: object  # mujoco.MjModel
    qpos: np.ndarray  # qpos address of each plan joint angle
    dof: np.ndarray  # dof address of each plan joint angle
    root: str
    planar: bool


def build_model(rec: RecordedPlan, scene: Scene, half_width: float, radius: float,
                time_step: float, time_constant: float, damping: float) -> WalkModel:
    import mujoco

    try:
        spec = mujoco.MjSpec.from_string(rec.urdf)
    except Exception as error:  # MuJoCo's compiler error: name the file
        raise ValueError(f"{rec.path}: MuJoCo cannot load /robot_description: {error}") from None
    root = spec.body(scene.root.body)
    if root is None:
        raise ValueError(f"{rec.path}: /robot_description has no link {scene.root.body!r}, "
                         f"the root of scene {scene.name!r}")
    planar = scene.root.type.name.lower() == "planar"
    if planar:
        root.add_joint(name="root_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        root.add_joint(name="root_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
        root.add_joint(name="root_pitch", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])
    else:
        root.add_freejoint()
    spec.option.timestep = time_step
    mu = float(rec.metadata.get("friction_coefficient", 0.8))
    spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1],
                            friction=[mu, 0.005, 0.0001], solref=[time_constant, 1.0], contype=0, conaffinity=1)
    for contact in scene.contacts:
        body = spec.body(contact.name)
        if body is None:
            raise ValueError(f"{rec.path}: /robot_description has no link for contact "
                             f"{contact.name!r} of scene {scene.name!r}")
        for side in (1.0, -1.0):
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius, 0, 0],
                          pos=[0.0, side * half_width, radius], friction=[mu, 0.005, 0.0001],
                          solref=[time_constant, 1.0], condim=3,
                          contype=1, conaffinity=0)
    for name in rec.joint_names:  # the joint PD's damping, integrated implicitly by MuJoCo
        if spec.joint(name) is not None:
            spec.joint(name).damping = [damping, 0.0, 0.0]
    model = spec.compile()
    names = {model.joint(j).name for j in range(model.njnt)}
    missing = [n for n in rec.joint_names if n not in names]
    if missing:
        raise ValueError(f"{rec.path}: /robot_description lacks the planned joints {missing}")
    qpos = np.array([model.joint(n).qposadr[0] for n in rec.joint_names])
    dof = np.array([model.joint(n).dofadr[0] for n in rec.joint_names])
    return WalkModel(model, qpos, dof, scene.root.body, planar)
