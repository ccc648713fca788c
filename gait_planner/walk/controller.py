"""The reference stabilising controller of a walk.

Joint torques = scale x the plan's efforts (feed-forward) + joint PD against the plan's
angles and rates + three loops on what the joints do not control (the floating base):

* Torso attitude: the torque the torso needs to return to the plan's pitch and roll,
  -kp e - kd (w - w_ref) (e the rotation vector of D D_ref^T, w the angular velocity, world;
  its vertical part dropped), made by the hips of the legs that stand on the ground (the
  reaction of a hip torque acts on the torso; split evenly between them): the legs whose
  contact points the walk last found loaded (`loaded`, set by the walk; before that, those
  the plan holds). A leg the plan still swings but that has struck early carries the
  torso; one the plan holds but that is still in the air does not. Yaw is
  left to the joint PD: the plan's point contacts carry no moment about the vertical in
  single support, and a foot asked for one spins on its sole (over 12 gain settings,
  walker3d lost a hip's yaw by 45 deg in 8 with yaw in the loop, in none without).
* Torso position (`walk.stance`): the torso's centre of mass behind, ahead of, below or
  beside the plan's is pushed back by the legs on the ground, at the feet's contacts that
  MuJoCo finds: the joint torques that give it the acceleration kp e + kd e_dot while the
  touching points stay put (a small change of the motion and the ground forces, least
  squares). Without it nothing regained the speed a walker loses in a stance: on a 10 deg
  ramp up walker3d fell 4-9 cm further behind its plan every half cycle.
* Foot placement (`placement_shift`, `placement_offsets`): the centre of mass running ahead
  of or behind its support, or sideways, is caught where a walker catches it, by putting
  the swing foot down elsewhere. The shift is kp e + kd e_dot, e the centre of mass's
  horizontal offset from the held contacts minus the plan's (the capture point of the
  linear inverted pendulum for kp = 1, kd = sqrt(z / g)), and the swing leg's joint targets
  (the whole leg, hip to ankle: `hip_legs`) move, along the swing (`smoothstep`), towards
  angles that put the foot there without turning it (damped least squares on the foot's
  Jacobian). On a ramp the horizontal shift runs along the ground (a vertical part keeps
  the foot's height above it).
* Swing height: the swing foot is kept at the plan's height above the ground. Its contact
  points' mean height error along the ground's normal (a ramp's, e_z on level ground and
  stairs), times height_kp, is added to the shift. Without it the swing heel ran 5-8 mm
  low (the stance foot sinks into MuJoCo's soft ground and the legs sag) and struck 20-40 ms
  early; on a 10 deg ramp the early strike threw the walker back, 10 cm behind the plan
  after its first half cycle. The height aimed at is the plan's plus a margin that rises
  and falls over the swing (swing_margin x sin(pi s), s the swing's progress from release
  to strike): the plans keep a swing point only 1 cm above the ground, within the swing
  foot's tracking error. Without the margin walker3d's default walk struck its heel 15-16 ms
  early four times in ten half cycles and the run scuffed its forefoot after every toe-off;
  with 1 cm the default walk touches nowhere unplanned, and the run and the torque-squared
  plan walk 10 half cycles instead of 8 and 9 (benchmarks/HISTORY.md, 2026-11-30 evening).

`ReferenceController(model, wm, ref, gains, max_shift, scale, clock)(data)` evaluates all of
it on a MuJoCo state whose kinematics are current (after `mj_step1`), against the plan at
the plan's time clock(data.time) (`walk.clock`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np

from gait_planner.model.angles import angle_names
from gait_planner.model.scene import Scene
from gait_planner.walk.stance import position_torques

__all__ = ["Gains", "Leg", "ReferenceController", "hip_legs", "torso_torque", "rotation_error",
           "placement_shift", "placement_offsets", "smoothstep", "stance_jacobians"]


@dataclass(frozen=True)
class Gains:
    kp: float  # N m/rad, joints
    kd: float  # N m s/rad, joints
    torso_kp: float  # N m/rad
    torso_kd: float  # N m s/rad
    placement_kp: float = 0.0  # -, foot shift per m of centre-of-mass offset error
    placement_kd: float = 0.0  # s, foot shift per m/s of centre-of-mass velocity error
    height_kp: float = 0.0  # -, share of the swing foot's height error (ground normal) corrected
    position_kp: float = 0.0  # 1/s^2, torso centre of mass acceleration per m of its error
    position_kd: float = 0.0  # 1/s, ... per m/s of its velocity error
    swing_margin: float = 0.0  # m, height above the plan's aimed at mid-swing


class Leg(NamedTuple):
    """A joint on the root and what hangs from it; indices into the joint angle names."""

    hip: list[int]  # the joint's own angles
    contacts: set[str]  # the contact points below it
    chain: list[int]  # the angles of it and every joint below it


def hip_legs(scene: Scene, joint_names) -> list[Leg]:
    """A `Leg` per joint on the root, its indices into `joint_names`."""
    children: dict[str, list] = {}
    for j in scene.joints:
        children.setdefault(j.parent, []).append(j)
    names = list(joint_names)
    legs = []
    for joint in children.get(scene.root.body, []):
        below, chain, todo = set(), [], [joint]
        while todo:
            j = todo.pop()
            below.add(j.child)
            chain += [names.index(a) for a in j.angle_names]
            todo += children.get(j.child, [])
        contacts = {c.name for c in scene.contacts if c.body in below}
        legs.append(Leg([names.index(a) for a in joint.angle_names], contacts, sorted(chain)))
    return legs


def rotation_error(D: np.ndarray, D_ref: np.ndarray) -> np.ndarray:
    """Rotation vector (world) of D D_ref^T, small-angle form."""
    R = D @ D_ref.T
    return 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])


def torso_torque(gains: Gains, D, D_ref, w, w_ref, axes: np.ndarray) -> np.ndarray:
    """Hip torques (one per row of `axes`, the stance hips' joint axes in world) whose
    reaction on the torso is the attitude feedback about the horizontal axes."""
    tau = -gains.torso_kp * rotation_error(D, D_ref) - gains.torso_kd * (w - w_ref)
    tau[2] = 0.0
    return -(axes @ tau)


def placement_shift(gains: Gains, offset_error: np.ndarray, velocity_error: np.ndarray,
                    limit: float) -> np.ndarray:
    """Horizontal swing-foot shift (3,) m, world, z = 0: kp e + kd e_dot of the centre of
    mass's offset error e (m) from its support and its velocity error (m/s), each (3,),
    clipped to length `limit` m."""
    shift = gains.placement_kp * offset_error + gains.placement_kd * velocity_error
    shift[2] = 0.0
    size = float(np.linalg.norm(shift))
    return shift * (limit / size) if size > limit else shift


def placement_offsets(jacp: np.ndarray, jacr: np.ndarray, shift: np.ndarray,
                      damping: float = 0.01) -> np.ndarray:
    """Joint offsets (n,) rad that move a foot by `shift` (3,) m without turning it:
    damped least squares on [jacp; jacr] (6, n), the foot body's translational and
    rotational Jacobians over the leg's n joint dofs. The damping (m per rad) keeps a
    nearly straight knee from asking for large offsets (at 1e-3 the stretched-knee plan's
    feedback reached 15 times its torque); it costs 7 % of a shift."""
    J = np.vstack([jacp, jacr])
    target = np.r_[shift, np.zeros(3)]
    return J.T @ np.linalg.solve(J @ J.T + damping ** 2 * np.eye(6), target)


def smoothstep(s: float) -> float:
    """3 s^2 - 2 s^3 of s clipped to [0, 1]: 0 at lift-off, 1 at the strike, flat at both."""
    s = min(max(s, 0.0), 1.0)
    return s * s * (3.0 - 2.0 * s)


def stance_jacobians(model, data, wm) -> tuple[np.ndarray, np.ndarray]:
    """(J (3 k, nv), J_task (6, nv)) for `walk.stance.position_torques` on a MuJoCo state
    whose kinematics are current: the translation Jacobians of the k contacts MuJoCo found
    between a foot (`wm.geom_contact`) and the ground, each at its contact position, and the
    translation and rotation Jacobians of the torso's centre of mass (`wm.root_site`)."""
    import mujoco

    # each contact's two geometries (ncon, 2); the foot's is the one that belongs to a contact
    # point (geom_contact >= 0, the ground's -1; of two feet that touch, the later point's)
    geoms = data.contact.geom
    rank = wm.geom_contact[geoms]
    foot = np.where(rank[:, 1] > rank[:, 0], geoms[:, 1], geoms[:, 0])
    on_foot = wm.geom_contact[foot] >= 0
    points, bodies = data.contact.pos[on_foot], model.geom_bodyid[foot[on_foot]]
    J = np.zeros((3 * len(points), model.nv))
    for i, (point, body) in enumerate(zip(points, bodies)):
        mujoco.mj_jac(model, data, J[3 * i:3 * i + 3], None, point, body)
    J_task = np.zeros((6, model.nv))
    mujoco.mj_jacSite(model, data, J_task[:3], J_task[3:], wm.root_site)
    return J, J_task


class ReferenceController:
    """The controller of the module docstring for one walk.

    model, wm: the `walk.mujoco_model.WalkModel`'s MuJoCo model and layout; ref: the joined
    plan (`walk.reference.Reference`); gains; max_shift m, the largest foot shift; scale:
    the factor on the plan's efforts (1; the self-test's 0 and 0.5); clock: the plan's time
    at a simulated time (`walk.clock.PlanClock`; default: the simulated time itself)."""

    def __init__(self, model, wm, ref, gains: Gains, max_shift: float, scale: float = 1.0,
                 clock: Callable[[float], float] = float):
        self.model, self.wm, self.ref, self.gains = model, wm, ref, gains
        self.clock = clock
        self.loaded: set[str] | None = None  # contact points on the ground (module docstring)
        self.max_shift, self.scale = max_shift, scale
        scene = ref.scene
        self.legs = hip_legs(scene, angle_names(scene))
        self.swings = ref.swing_windows([leg.contacts for leg in self.legs])
        self.feet = [model.body(scene.contact(sorted(leg.contacts)[0]).body).id
                     for leg in self.legs]
        self.root = model.body(wm.root).id
        self.joint_ids = np.array([model.joint(n).id for n in angle_names(scene)])
        self.contact_site = dict(zip((c.name for c in scene.contacts), wm.contact_sites))
        self.points = {c.name: (scene.body_index(c.body),
                                np.asarray(scene.body(c.body).points[c.point]))
                       for c in scene.contacts}
        self._jacp, self._jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
        self._M = np.zeros((model.nv, model.nv))
        self.base_dofs = np.setdiff1d(np.arange(model.nv), wm.dof)
        self._vel = np.zeros(6)

    def __call__(self, data) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(feed-forward, feedback, the plan's efforts, the plan's angles), each (na,), N m and
        rad, at the plan's time clock(data.time); the feedback includes the joints' damping
        -kd v that MuJoCo applies (walk.mujoco_model), so the torque to apply is ff + fb +
        kd v."""
        import mujoco

        model, wm, ref, g, t = self.model, self.wm, self.ref, self.gains, self.clock(data.time)
        angles, rates, efforts, active = ref.at(t)
        target = angles.copy()
        swing = next((w for w in self.swings if w[0] <= t < w[1]), None)
        if swing is not None and active:
            t0, t1, leg = swing
            idx, q_ref = self.legs[leg].chain, ref.q_at(t)
            along = self._shift(data, t, q_ref, active)
            n = ref.normal
            along[2] = -(n @ along) / n[2]  # along the ground: its height above it kept
            s = (t - t0) / (t1 - t0)
            shift = (smoothstep(s) * along
                     + self._lift(data, q_ref, self.legs[leg].contacts, s))
            target[idx] += placement_offsets(*self._foot_jacobians(data, leg, wm.dof[idx]),
                                             shift)
        q, v = data.qpos[wm.qpos], data.qvel[wm.dof]
        fb = g.kp * (target - q) + g.kd * (rates - v)
        down = set(active) if self.loaded is None else self.loaded
        stance = [leg.hip for leg in self.legs if leg.contacts & down]
        if stance:
            h = model.opt.timestep
            _, D_ref = ref.root_at(t)
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, self.root,
                                     self._vel, 0)
            D, w_ref = data.site_xmat[wm.root_site].reshape(3, 3), ref.root_rate_at(t, h)
            for idx in stance:
                fb[idx] += torso_torque(g, D, D_ref, self._vel[:3], w_ref,
                                        data.xaxis[self.joint_ids[idx]]) / len(stance)
        if g.position_kp or g.position_kd:
            fb += self._carried(data, t)
        return self.scale * efforts, fb, efforts, angles

    def _carried(self, data, t: float) -> np.ndarray:
        """(na,) N m: `walk.stance.position_torques` for the torso centre of mass's
        acceleration kp (p_ref - p) + kd (v_ref - v), at the feet's contacts with the ground
        (MuJoCo's, of this state: each at its contact position)."""
        import mujoco

        model, wm, g, h = self.model, self.wm, self.gains, self.model.opt.timestep
        J, J_task = stance_jacobians(model, data, wm)
        ref_now = self.ref.root_at(t)[0]
        v_ref = self.ref.root_velocity_at(t, h)
        a_task = (g.position_kp * (ref_now - data.site_xpos[wm.root_site])
                  + g.position_kd * (v_ref - J_task[:3] @ data.qvel))
        mujoco.mj_fullM(model, data, self._M)
        return position_torques(self._M, J, J_task, np.r_[a_task, 0.0, 0.0, 0.0],
                                self.base_dofs, wm.dof)

    def planned_point(self, q_row: np.ndarray, contact: str) -> np.ndarray:
        """World position (3,) m of a contact point in the plan's configuration q_row."""
        i, p = self.points[contact]
        return q_row[12 * i:12 * i + 3] + q_row[12 * i + 3:12 * i + 12].reshape(3, 3).T @ p

    def _shift(self, data, t: float, q_ref: np.ndarray, active) -> np.ndarray:
        """`placement_shift` of the centre of mass against the held contacts `active`; q_ref
        the plan's configuration at t."""
        import mujoco

        ref, h = self.ref, self.model.opt.timestep
        mujoco.mj_subtreeVel(self.model, data)
        planned = np.mean([self.planned_point(q_ref, c) for c in active], axis=0)
        support = np.mean([data.site_xpos[self.contact_site[c]] for c in active], axis=0)
        com_rate = ref.com_velocity_at(t, h)
        return placement_shift(self.gains,
                               data.subtree_com[self.root] - support - (ref.com_at(t) - planned),
                               data.subtree_linvel[self.root] - com_rate, self.max_shift)

    def _lift(self, data, q_ref: np.ndarray, contacts, s: float) -> np.ndarray:
        """(3,) m: height_kp x the contact points' mean height error along the ground's
        normal (the plan's configuration q_ref, raised by `swing_margin` sin(pi s) at the
        swing's progress s in [0, 1) (inside its window), minus the walker's)."""
        n = self.ref.normal
        error = np.mean([n @ (self.planned_point(q_ref, c) - data.site_xpos[self.contact_site[c]])
                         for c in sorted(contacts)])
        margin = self.gains.swing_margin * math.sin(math.pi * s)
        return self.gains.height_kp * (error + margin) * n

    def _foot_jacobians(self, data, leg: int, dofs) -> tuple[np.ndarray, np.ndarray]:
        import mujoco

        mujoco.mj_jacBody(self.model, data, self._jacp, self._jacr, self.feet[leg])
        return self._jacp[:, dofs], self._jacr[:, dofs]
