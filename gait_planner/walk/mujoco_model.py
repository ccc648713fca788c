"""The walker in MuJoCo: the recording's /robot_description with the planned feet, or a
drafted robot's own URDF with its own feet.

`build_model(rec, scene, settings, robot=None)` loads one of two descriptions:

* **The recording's** (robot None): /robot_description as `gait_planner.io.urdf` writes it
  (links on the directors, the root link's origin at its centre of mass) and, at every
  planned contact point, two spheres at +-foot_half_width along the foot's d2, their lowest
  points on the contact point when the foot is level: a point contact as the plan assumes,
  and a foot that can carry the full-contact roll moment (up to the normal force times
  foot_half_width) the plan allows. Every body gets the scene's principal moments after
  compiling (`set_inertia`): the URDF must carry a realisable tensor, the plan may use one
  that is not (the paper's torso), and the simulated walker is the planned one.
* **A drafted robot's own** (`robot`, a `walk.robot_urdf.RobotUrdf`): its URDF with the
  locked joints welded at the draft's angles, its own inertias (the draft's where the URDF
  has none: iCub's right leg), and the feet's own collision geometry as the contact
  geometry (`walk.robot_urdf.simulation_urdf`: nothing else collides, no visual geometry);
  the plan's frames are found on its links by `walk.director_frames`.

Either way the plan's frames are MuJoCo sites: ``plan_root`` at the root body's centre of
mass with its directors as axes (the plan's root state; `plan_qpos` places the root link so
that the site is there), ``plan_<contact>`` at each planned contact point. The root gets the
scene's freedom (free: a free joint; planar: slides along x and z and a hinge about y), and
the ground is the one the plan was made for (its metadata's ``slope``, ``step_height``,
``stair_riser``, ``stair_tread``, `gait_planner.model.ground`; absent: level): the plane
z = 0, a ramp's plane through the origin turned about y by the slope, or stairs as the boxes
of `gait_planner.io.urdf.ground_boxes` from `STAIRS_BEHIND` m behind the origin to
`STAIR_TREADS` treads ahead. The joint PD's damping -kd v is the joints' MuJoCo damping
(implicit: the feet's small inertias make an explicit kd unstable at any practical step);
the controller adds kd v_ref.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from gait_planner.io.mcap_reader import RecordedPlan
from gait_planner.io.urdf import ground_boxes
from gait_planner.model.angles import angle_names
from gait_planner.model.ground import Ground, GroundError
from gait_planner.model.scene import Scene
from gait_planner.walk.director_frames import SiteFrame, director_frames
from gait_planner.walk.robot_urdf import FootMesh, RobotUrdf, foot_meshes, simulation_urdf

__all__ = ["STAIRS_BEHIND", "STAIR_TREADS", "WalkModel", "build_model", "plan_qpos",
           "plan_root_qvel", "recorded_ground", "root_link_pose", "set_inertia"]

STAIRS_BEHIND = 2.0  # m of stairs behind x = 0
STAIR_TREADS = 24  # treads ahead of the first edge (the default walk takes 10 half cycles)


@dataclass(frozen=True)
class WalkModel:
    """A walker in MuJoCo: `model` (mujoco.MjModel); the qpos and dof address of each plan
    joint angle; the root body's name and whether it is planar; the MuJoCo sites of the
    plan's frames: `root_site` the root body's centre of mass with its directors as axes
    (the plan's root state), `contact_sites` each planned contact point (scene order); and
    `geom_contact` (ngeom,) the contact (scene index) each foot geometry belongs to (-1:
    none)."""

    model: object
    qpos: np.ndarray
    dof: np.ndarray
    root: str
    planar: bool
    root_site: int
    contact_sites: np.ndarray
    geom_contact: np.ndarray


def build_model(rec: RecordedPlan, scene: Scene, half_width: float, radius: float,
                time_step: float, time_constant: float, damping: float,
                robot: RobotUrdf | None = None, noslip_iterations: int = 0) -> WalkModel:
    """The walker of the module docstring: from /robot_description (robot None) or from the
    drafted robot's own URDF (`robot`); half_width and radius (m) place the added spheres
    (not used for a robot's own URDF), time_step s, time_constant s (the contacts' solref),
    damping N m s/rad on the plan's joints; noslip_iterations: passes of MuJoCo's no-slip
    solver after each step (0: none; the soft contacts' friction then lets a loaded foot
    creep). ValueError naming what does not fit."""
    import mujoco

    mu = float(rec.metadata.get("friction_coefficient", 0.8))
    foot = dict(friction=[mu, 0.005, 0.0001], solref=[time_constant, 1.0], condim=3,
                contype=1, conaffinity=0)
    if robot is None:
        spec = _load(rec.urdf, f"{rec.path}: /robot_description")
        _check_root(spec, scene, f"{rec.path}: /robot_description")
        _add_spheres(spec, scene, half_width, radius, foot, f"{rec.path}: /robot_description")
        root_site = SiteFrame(scene.root.body, np.zeros(3), np.eye(3))
        sites = {c.name: SiteFrame(c.name, np.zeros(3), np.eye(3)) for c in scene.contacts}
    else:
        feet = {c.body for c in scene.contacts}
        spec = _load(simulation_urdf(robot, angle_names(scene), feet, _drafted(scene)),
                     "the robot's URDF")
        _check_root(spec, scene, "the robot's URDF")
        _add_meshes(spec, foot_meshes(robot, feet))
        for geom in spec.geoms:  # the feet's own collision geometry, the only geometry left
            for key, value in foot.items():
                setattr(geom, key, value)
        root_site, sites = director_frames(spec.compile(), scene)
    _add_site(spec, "plan_root", root_site)
    for name, frame in sites.items():
        _add_site(spec, f"plan_{name}", frame)
    planar = scene.root.type.name.lower() == "planar"
    _add_root_joint(spec.body(scene.root.body), planar)
    spec.option.timestep = time_step
    spec.option.noslip_iterations = noslip_iterations
    _add_ground(spec, recorded_ground(rec), dict(friction=[mu, 0.005, 0.0001],
                                                 solref=[time_constant, 1.0], contype=0,
                                                 conaffinity=1))
    for name in rec.joint_names:  # the joint PD's damping, integrated implicitly by MuJoCo
        if spec.joint(name) is not None:
            spec.joint(name).damping = [damping, 0.0, 0.0]
    model = spec.compile()
    if robot is None:
        set_inertia(model, {b.name: tuple(b.inertia) for b in scene.bodies})
    names = {model.joint(j).name for j in range(model.njnt)}
    missing = [n for n in rec.joint_names if n not in names]
    if missing:
        raise ValueError(f"{rec.path}: the walker's URDF lacks the planned joints {missing}")
    qpos = np.array([model.joint(n).qposadr[0] for n in rec.joint_names])
    dof = np.array([model.joint(n).dofadr[0] for n in rec.joint_names])
    contact_sites = np.array([model.site(f"plan_{c.name}").id for c in scene.contacts])
    return WalkModel(model, qpos, dof, scene.root.body, planar, model.site("plan_root").id,
                     contact_sites, _geom_contacts(model, contact_sites))


def _load(urdf: str, what: str):
    import mujoco

    try:
        return mujoco.MjSpec.from_string(urdf)
    except Exception as error:  # MuJoCo's compiler error: name the source
        raise ValueError(f"{what}: MuJoCo cannot load it: {error}") from None


def _check_root(spec, scene: Scene, what: str) -> None:
    if spec.body(scene.root.body) is None:
        raise ValueError(f"{what} has no link {scene.root.body!r}, the root of scene "
                         f"{scene.name!r}")


def _add_spheres(spec, scene: Scene, half_width: float, radius: float, foot: dict,
                 what: str) -> None:
    """Two spheres at each contact point's link (module docstring)."""
    import mujoco

    for contact in scene.contacts:
        body = spec.body(contact.name)
        if body is None:
            raise ValueError(f"{what} has no link for contact {contact.name!r} of scene "
                             f"{scene.name!r}")
        for side in (1.0, -1.0):
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius, 0, 0],
                          pos=[0.0, side * half_width, radius], **foot)


def _drafted(scene: Scene) -> dict[str, tuple]:
    """link -> the draft's body (mass kg, COM (3,) m, inertia (3, 3) kg m^2) in the link's
    frame, for the links whose URDF lacks an inertia (`walk.robot_urdf`)."""
    out = {}
    for body in scene.bodies:
        if body.name in scene.robot.links:
            position, rotation = scene.robot.link_pose(body.name)  # link frame in the body's
            out[body.name] = (body.mass, -rotation.T @ position,
                              rotation.T @ np.diag(body.inertia) @ rotation)
    return out


def _add_meshes(spec, meshes: list[FootMesh]) -> None:
    """The feet's meshes MuJoCo does not read from a file, from their vertices (its
    collision takes their convex hull, as it does of any mesh)."""
    import mujoco

    for i, mesh in enumerate(meshes):
        spec.add_mesh(name=f"foot_mesh_{i}", uservert=mesh.vertices.ravel().tolist())
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, mesh.R.ravel())
        spec.body(mesh.link).add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"foot_mesh_{i}",
                                      pos=mesh.pos, quat=quat)


def _add_site(spec, name: str, frame: SiteFrame) -> None:
    import mujoco

    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(frame.R).reshape(-1))
    spec.body(frame.body).add_site(name=name, pos=list(frame.pos), quat=list(quat))


def _add_root_joint(root, planar: bool) -> None:
    """The scene's freedom for the root body (module docstring)."""
    import mujoco

    if planar:
        root.add_joint(name="root_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        root.add_joint(name="root_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
        root.add_joint(name="root_pitch", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])
    else:
        root.add_freejoint()


def _add_ground(spec, ground: Ground, surface: dict) -> None:
    """The ground the plan was made for (module docstring)."""
    import mujoco

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


def _geom_contacts(model, contact_sites: np.ndarray) -> np.ndarray:
    """(ngeom,) the index of the contact site nearest each foot geometry (contype 1) on the
    same rigid body, at the model's reference pose; -1 for other geometry."""
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    weld = model.body_weldid[model.site_bodyid[contact_sites]]
    out = np.full(model.ngeom, -1)
    for g in np.flatnonzero(model.geom_contype == 1):
        near = np.flatnonzero(weld == model.body_weldid[model.geom_bodyid[g]])
        if near.size:
            gaps = np.linalg.norm(data.site_xpos[contact_sites[near]] - data.geom_xpos[g], axis=1)
            out[g] = near[int(np.argmin(gaps))]
    return out


def recorded_ground(rec: RecordedPlan) -> Ground:
    """The ground a recording's metadata names (`Ground.from_metadata`); ValueError naming
    the recording if it names none."""
    try:
        return Ground.from_metadata(rec.metadata)
    except GroundError as error:
        raise ValueError(f"{rec.path}: the metadata names no ground to walk on: {error}") from None


def plan_qpos(wm: WalkModel, root: int, q_row: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """MuJoCo qpos (nq,) of one plan node: the root link placed so that its `root_site` is
    at the COM and directors D = [d1 d2 d3] of body index `root`'s block of q_row (12 nb,)
    (free: link origin and quaternion; planar: x, z, pitch), the hinges at the plan's joint
    angles (na,) rad."""
    import mujoco

    position, R = root_link_pose(wm, q_row[12 * root:12 * root + 3],
                                 q_row[12 * root + 3:12 * root + 12].reshape(3, 3).T)
    qpos = np.zeros(wm.model.nq)
    if wm.planar:
        qpos[:3] = position[0], position[2], math.atan2(R[0, 2], R[2, 2])
    else:
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R).reshape(-1))
        qpos[:7] = np.r_[position, quat]
    qpos[wm.qpos] = angles
    return qpos


def plan_root_qvel(wm: WalkModel, D: np.ndarray, velocity: np.ndarray,
                   rate: np.ndarray) -> np.ndarray:
    """The root joint's qvel (6,) (free) or (3,) (planar: x, z, pitch rates) of the root's
    COM velocity (3,) m/s and angular velocity `rate` (3,) rad/s (world) at directors D."""
    s = wm.model.site(wm.root_site)
    R = _site_rotation(wm)
    origin_rate = velocity - np.cross(rate, D @ R.T @ s.pos)  # the link origin's velocity
    if wm.planar:
        return np.array([origin_rate[0], origin_rate[2], rate[1]])
    return np.r_[origin_rate, R @ D.T @ rate]  # angular velocity in the link's frame


def root_link_pose(wm: WalkModel, com: np.ndarray, D: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(origin (3,) m, axes (3, 3)) of the root link whose `root_site` is at `com` (m) with
    directors D: axes D R_site^T, origin com - axes site_pos."""
    R = D @ _site_rotation(wm).T
    return com - R @ wm.model.site(wm.root_site).pos, R


def _site_rotation(wm: WalkModel) -> np.ndarray:
    import mujoco

    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, wm.model.site_quat[wm.root_site])
    return R.reshape(3, 3)


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
