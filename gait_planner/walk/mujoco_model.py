"""The walker in MuJoCo: the recording's own /robot_description with the planned feet.

`build_model(rec, scene, settings)` loads the URDF (`gait_planner.io.urdf`: links on the
directors, the root link's origin at its centre of mass), gives the root the scene's
freedom (free: a free joint; planar: slides along x and z and a hinge about y), adds the
ground the plan was made for (its metadata's ``slope``, ``step_height``, ``stair_riser``,
``stair_tread``, `gait_planner.model.ground`; absent: level): the plane z = 0, a ramp's
plane through the origin turned about y by the slope, or stairs as the boxes of
`gait_planner.io.urdf.ground_boxes` from `STAIRS_BEHIND` m behind the origin to
`STAIR_TREADS` treads ahead, and, at every planned contact point, two spheres at
+-foot_half_width along the foot's d2, their lowest points on the contact point when the
foot is level: a point contact as the plan assumes, and a foot that can carry the
full-contact roll moment (up to the normal force times foot_half_width) the plan allows.
The joint PD's damping -kd v is the joints' MuJoCo damping (implicit: the feet's small
inertias make an explicit kd unstable at any practical step); the controller adds kd v_ref.
Every body gets the scene's principal moments after compiling (`set_inertia`): the URDF
must carry a realisable tensor, the plan may use one that is not (the paper's torso), and
the simulated walker is the planned one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from gait_planner.io.mcap_reader import RecordedPlan
from gait_planner.io.urdf import ground_boxes
from gait_planner.model.ground import Ground, GroundError
from gait_planner.model.scene import Scene

__all__ = ["STAIRS_BEHIND", "STAIR_TREADS", "WalkModel", "build_model", "plan_qpos",
           "recorded_ground", "set_inertia"]

STAIRS_BEHIND = 2.0  # m of stairs behind x = 0
STAIR_TREADS = 24  # treads ahead of the first edge (the default walk takes 10 half cycles)


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
    ground = recorded_ground(rec)
    surface = dict(friction=[mu, 0.005, 0.0001], solref=[time_constant, 1.0], contype=0,
                   conaffinity=1)
    if ground.stairs:
        x_end = ground.riser + STAIR_TREADS * ground.tread
        for i, box in enumerate(ground_boxes(ground, -STAIRS_BEHIND, x_end)):
            spec.worldbody.add_geom(name=f"tread_{i}", type=mujoco.mjtGeom.mjGEOM_BOX,
                                    size=[0.5 * v for v in box.size], pos=list(box.centre),
                                    **surface)
    else:  # the plane through the origin with normal (-sin a, 0, cos a): e_z turned about y
        a = math.radians(ground.slope)
        turn = {"quat": [math.cos(a / 2), 0.0, -math.sin(a / 2), 0.0]} if a else {}
        spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1],
                                **turn, **surface)
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
    set_inertia(model, {b.name: tuple(b.inertia) for b in scene.bodies})
    names = {model.joint(j).name for j in range(model.njnt)}
    missing = [n for n in rec.joint_names if n not in names]
    if missing:
        raise ValueError(f"{rec.path}: /robot_description lacks the planned joints {missing}")
    qpos = np.array([model.joint(n).qposadr[0] for n in rec.joint_names])
    dof = np.array([model.joint(n).dofadr[0] for n in rec.joint_names])
    return WalkModel(model, qpos, dof, scene.root.body, planar)


def recorded_ground(rec: RecordedPlan) -> Ground:
    """The ground a recording's metadata names (`Ground.from_metadata`); ValueError naming
    the recording if it names none."""
    try:
        return Ground.from_metadata(rec.metadata)
    except GroundError as error:
        raise ValueError(f"{rec.path}: the metadata names no ground to walk on: {error}") from None


def plan_qpos(wm, root: int, q_row: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """MuJoCo qpos (nq,) of one plan node: the root (body index `root` in the plan's q) from
    its block of q_row (12 nb,) (free: COM and quaternion of D = [d1 d2 d3]; planar: x, z,
    pitch), the hinges from the plan's joint angles (na,) rad."""
    import mujoco

    phi, D = q_row[12 * root:12 * root + 3], q_row[12 * root + 3:12 * root + 12].reshape(3, 3).T
    qpos = np.zeros(wm.model.nq)
    if wm.planar:
        qpos[:3] = phi[0], phi[2], math.atan2(D[0, 2], D[2, 2])
    else:
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(D).reshape(-1))
        qpos[:7] = np.r_[phi, quat]
    qpos[wm.qpos] = angles
    return qpos


def set_inertia(model, inertia: Mapping[str, tuple[float, float, float]]) -> None:
    """Give bodies (name -> principal moments (J1, J2, J3) kg m^2 about d1, d2, d3) these
    moments in the compiled model: MuJoCo's dynamics need only the tensor, so a
    non-realisable one (the paper's torso, `gait_planner.io.urdf.realisable_inertia`)
    is simulated as it is planned."""
    import mujoco

    for name, moments in inertia.items():
        b = model.body(name).id
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, model.body_iquat[b])  # MuJoCo's principal frame in the body's
        R = R.reshape(3, 3)
        model.body_inertia[b] = np.diag(R.T @ np.diag(moments) @ R)
