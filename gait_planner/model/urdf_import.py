"""A scene drafted from a robot's URDF: its legs as bodies and joints, every other joint
locked, contact points from the feet's collision geometry (docs/user-guide.md, "Your robot").

`draft_scene(urdf_text)` reads the description with Pinocchio (`buildModelFromXML`, the
collision geometry with `buildGeomFromUrdfString`), so the URDF is parsed, its fixed joints
merged and meshes read as the rest of the field does. The draft is the URDF's model, not an
approximation of it:

* **The walker's frame.** The scene's world (x forward, y left, z up) is found from the
  robot at its draft pose, whatever axes the URDF uses (`gait_planner.model.urdf_frame`:
  the mirror plane from the feet, forward from the soles, else the knees, else the URDF's
  x); the draft is written in it (iCub, whose base x points backwards, walks along -x of
  its base).
* **Legs.** The two chains from the floating base to the feet (`feet` LEFT, RIGHT, or the
  two lowest leaves of the tree, left told by the walker's frame). Every other joint is
  locked at `locked` (default: the URDF's zero) and its links, massless or not, merged
  into their parent with `pinocchio.buildReducedModel`: one rigid body with the combined
  mass and inertia.
* **Bodies.** Each remaining joint's body; its directors are its principal axes of inertia
  (the inertia at the centre of mass diagonalised; of the 24 right-handed orderings of the
  eigenvectors the one nearest the walker's axes, so that the URDF's link frames do not
  matter), joint points and contact points in them, from the centre of mass.
* **Joints.** Every leg joint is revolute: its axis in the parent's directors and its
  zero-angle reference R0 (the child's directors in the parent's at the URDF's zero pose,
  as `reference_rpy`), so the scene's joint angle is the URDF's (zero at the URDF's zero,
  positive about its axis) and its name is the URDF joint's. Three revolute joints chained
  by two massless links (a URDF's ball joint, as `gait-planner urdf` writes spherical
  joints) whose axes meet in one point as pitch, roll, yaw: one spherical joint whose
  angles are the three URDF joints' (`gait_planner.model.urdf_fuse`; exact; links with
  mass are never fused).
* **Contacts.** Heel and forefoot, or a point foot, from each foot's collision geometry
  (else its visual geometry) at the draft pose (`gait_planner.model.urdf_contacts`).
* **Mirror.** Left and right bodies and joints paired from the kinematic tree (the legs'
  joints in chain order), not from their names, and compared in the walker's world at
  the draft pose, not link frame by link frame (`gait_planner.model.urdf_mirror`). The
  half-cycle's mirror periodicity needs a symmetric robot: right and left data that differ
  by more than its tolerances are refused, naming the link; below them the draft writes
  the left link's data mirrored for the right one and lists what moved (G1's right knee
  inertia, Bolt's 1.5e-6 kg, iCub's right leg links, whose URDF has no inertia).
  `mirror_tolerance` (a fraction, default 5 %: `--mirror-tolerance`) is the mass and
  inertia difference the user accepts; the refusal names the value that would accept the
  robot.
* **Legs apart.** The lower legs' bodies (knee, shank, ankle, foot) carry spheres that
  contain their collision geometry (``collision:``, `gait_planner.model.urdf_collision`),
  and the gait keeps them ``leg_clearance`` (`leg_clearance`, default 1 cm) apart
  (`gait_planner.ocp.legs`).
* **Limits.** The URDF's ranges (`joint_limits`, within +-89.5 deg of its zero: the range
  rows take ranges narrower than 180 deg) and efforts (`effort_limits`, hard bounds on the
  torques) per joint; its velocity limits per joint (`joint_speed_limits`, a left-right
  pair's the smaller, a ball's the smallest of its three; `joint_speed_max`, the slowest,
  where no joint is slower than 600 deg/s, faster than a walk turns any joint). The locked joints' efforts are bounded too
  (`robot.holds`, `gait_planner.model.urdf_holds`).
* **Walking envelope.** An upright walk (`gait_planner.model.urdf_envelope`): the base
  within 10 deg of upright, hip yaw within +-15 deg, the stance knee within +-45 deg in
  single support.
* **Gait.** walker3d's five phases for feet with heel and forefoot, the compass's two for
  point feet; walker3d's swing clearance and strike speed, the step length and the time
  step scaled from walker3d by the leg length L
  (hip to sole): step = 0.7066 L (walker3d: 0.6338 m at L = 0.897 m), base time step
  0.01 s sqrt(L / 0.897 m) (equal Froude number, so sigma's bounds keep their meaning);
  sigma's upper bound walker3d's 1.5, or longer where the slowest hip or ankle pitch joint
  cannot sweep the step that fast (`gait_planner.model.urdf_pace`: Romeo's 3.0).

Refused before anything is built, with the joint or link named (`UrdfError`): an
unreadable or closed-chain description, a leg joint that is not revolute (prismatic,
planar, floating, spherical), a moving leg body without mass (other than a ball joint's)
or with a non-physical inertia, fewer than two feet, feet not side by side or not below
the hips along z, a foot without collision or visual geometry or contact frames, a mesh
that cannot be read.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import yaml

from gait_planner.model.rotations import matrix_rpy
from gait_planner.model.urdf_collision import LEG_CLEARANCE, leg_spheres
from gait_planner.model.urdf_contacts import foot_contacts, sole_points
from gait_planner.model.urdf_envelope import (HIP_YAW_DEG, STANCE_KNEE_DEG, UPRIGHT_DEG,
                                              leg_roles, walking_envelope)
from gait_planner.model.urdf_errors import UrdfError
from gait_planner.model.urdf_frame import walking_frame
from gait_planner.model.urdf_fuse import ball_points, find_balls
from gait_planner.model.urdf_holds import locked_holds
from gait_planner.model.urdf_mirror import (MIRROR_TOLERANCE, S, mirror_geometry,
                                            mirror_pairs, mirrored_inertias)
from gait_planner.model.urdf_pace import scaling_upper
from gait_planner.model.urdf_read import (find_feet, leg_path, read_urdf, revolute_axis,
                                          visual_geometry)

__all__ = ["UrdfDraft", "UrdfError", "draft_scene"]

_RANGE_MAX = 89.5  # deg from the zero pose: the joint-range rows take ranges under 180 deg
_MIN_MASS = 1e-6  # kg: a moving body lighter than this is massless
_INERTIA_TOLERANCE = 1e-9  # relative: eigenvalues and triangle inequality
WALKER3D_LEG = 0.897  # m, walker3d's hip height standing (config/scenes/walker3d.yaml)
WALKER3D_STEP_RATIO = 0.6338 / WALKER3D_LEG
WALK_JOINT_SPEED = 600.0  # deg/s: no walk's joint turns faster (the verifier's JOINT_SPEED_MAX)


@dataclass(frozen=True)
class UrdfDraft:
    """A drafted scene: `yaml` its text (load it with `scene_from_text`), `name` the
    scene's name, the URDF joints planned (`joints`, leg joints in scene order) and locked
    (`locked`: name -> angle rad)."""

    yaml: str
    name: str
    joints: tuple[str, ...]
    locked: Mapping[str, float] = field(default_factory=dict)


def _pin():
    import pinocchio as pin  # noqa: PLC0415 - only the importer needs it at import time

    return pin


# ----------------------------------------------------------------------------- bodies


def _principal(name: str, mass: float, inertia: np.ndarray, world: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """(moments (3,), R (3, 3)): principal moments and axes (columns, joint frame) of the
    inertia (3, 3) at the COM in the joint frame, ordered and signed nearest the walker's
    axes (`world`: the joint frame's axes in the walker's world, so that the URDF's link
    frames do not matter); UrdfError for a body without mass or a non-physical inertia."""
    if not mass > _MIN_MASS:
        raise UrdfError(f"link {name!r} moves with the leg but has no mass ({mass:g} kg): "
                        f"give it an <inertial>, or merge it by making its joint fixed")
    scale = max(float(np.trace(inertia)), 1e-300)
    if np.abs(inertia - inertia.T).max() > _INERTIA_TOLERANCE * scale:
        raise UrdfError(f"link {name!r}: its inertia is not symmetric")
    if np.abs(inertia - np.diag(np.diag(inertia))).max() <= 1e-12 * scale:
        values, vectors = np.diag(inertia).copy(), np.eye(3)  # already principal
    else:
        values, vectors = np.linalg.eigh(0.5 * (inertia + inertia.T))
    best = None
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            R = vectors[:, perm] * signs
            nearness = np.trace(world @ R)
            if np.linalg.det(R) > 0 and (best is None or nearness > best[0] + 1e-12):
                best = (nearness, R, values[list(perm)])
    _, R, moments = best
    if moments.min() <= _INERTIA_TOLERANCE * scale or \
            2 * moments.max() > moments.sum() * (1 + _INERTIA_TOLERANCE):
        raise UrdfError(f"link {name!r} has a non-physical inertia (principal moments "
                        f"{moments.round(9).tolist()} kg m^2: each must be positive and at "
                        f"most the sum of the other two)")
    return moments, R


# ----------------------------------------------------------------------------- the draft


@dataclass
class _Body:
    name: str  # the URDF link carried by the joint (the scene's body name)
    joint: int
    mass: float
    moments: np.ndarray
    com: np.ndarray  # in the joint frame
    R: np.ndarray  # principal axes (columns) in the joint frame
    points: dict[str, np.ndarray] = field(default_factory=dict)  # in the joint frame

    def local(self, p: np.ndarray) -> np.ndarray:
        """A joint-frame point in director components from the centre of mass."""
        return self.R.T @ (np.asarray(p) - self.com)


def _link_name(model, joint: int) -> str:
    """The URDF link a joint carries (its first BODY frame)."""
    pin = _pin()
    for frame in model.frames:
        if frame.parentJoint == joint and frame.type == pin.FrameType.BODY:
            return frame.name
    return model.names[joint]


def draft_scene(urdf_text: str, *, feet: Sequence[str] | None = None,
                locked: Mapping[str, float] | None = None, name: str | None = None,
                package_dirs: Sequence[str | Path] = (), urdf_file: str = "robot.urdf",
                robot_dirs: Sequence[str] = (),
                mirror_tolerance: float = MIRROR_TOLERANCE,
                leg_clearance: float = LEG_CLEARANCE) -> UrdfDraft:
    """The scene of a URDF's legs (module docstring); UrdfError naming what is refused.

    `package_dirs` resolve the URDF's meshes here; the draft's ``robot:`` section names the
    URDF as `urdf_file` and its mesh folders as `robot_dirs` (both as the scene file will
    read them: relative to its folder, or absolute). `mirror_tolerance`: the relative
    difference of a right link's mass and inertia from its left partner's mirror image
    written symmetric (a fraction in [0, 1); `gait_planner.model.urdf_mirror`).
    `leg_clearance` m >= 0: the gait's distance between the legs' collision spheres."""
    if not (isinstance(leg_clearance, (int, float)) and 0.0 <= leg_clearance < math.inf):
        raise UrdfError(f"--leg-clearance takes a distance >= 0 m (0.01 for 1 cm), got "
                        f"{leg_clearance!r}")
    if not 0.0 <= mirror_tolerance < 1.0:
        raise UrdfError(f"--mirror-tolerance takes a fraction in [0, 1) (0.06 for 6 %), got "
                        f"{mirror_tolerance:g}")
    pin = _pin()
    dirs = [str(p) for p in package_dirs]
    full, geometry = read_urdf(urdf_text, dirs)
    foot_a, foot_b = find_feet(full, feet)
    legs = leg_path(full, foot_a) + leg_path(full, foot_b)
    axes = {full.names[j]: revolute_axis(full, j) for j in legs}  # joint frame: kept by
    # the reduction, which changes placements only
    locked = dict(locked or {})
    q_lock = pin.neutral(full)
    for joint_name, angle in locked.items():
        if not full.existJointName(joint_name):
            raise UrdfError(f"--lock names no joint of the URDF: {joint_name!r}")
        jid = full.getJointId(joint_name)
        if jid in legs:
            raise UrdfError(f"joint {joint_name!r} is a leg joint: it is planned, not locked")
        q_lock[full.joints[jid].idx_q] = float(angle)
    others = [j for j in range(2, full.njoints) if j not in legs]
    lock_angles = {full.names[j]: float(q_lock[full.joints[j].idx_q]) for j in others}
    shapes = [geometry]
    if any(all(o.parentJoint != f for o in geometry.geometryObjects) for f in (foot_a, foot_b)):
        shapes += [g for g in [visual_geometry(full, urdf_text, dirs)] if g is not None]
    model, shapes = pin.buildReducedModel(full, shapes, others, q_lock)
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    reduced = {j: model.getJointId(full.names[j]) for j in (foot_a, foot_b)}
    links = {j: _link_name(model, j) for j in range(1, model.njoints)}
    soles = {f: sole_points(model, shapes, data, f, links[f]) for f in reduced.values()}
    frame, foot_ids = walking_frame(model, data, tuple(reduced.values()),
                                    {f: world for f, (_, world) in soles.items()}, axes,
                                    given=bool(feet))
    left_leg, right_leg = (leg_path(model, f) for f in foot_ids)
    ids = {str(model.names[j]): j for j in left_leg + right_leg}

    balls = find_balls(model, list(ids.values()), links)
    left_of, twins = mirror_pairs(model, left_leg, right_leg, balls)
    inner = {j for ball in balls for j in ball.joints[:2]}  # carry the massless links
    body_links = {j: links[j] for j in [1] + list(ids.values()) if j not in inner}
    left_of = {r: l for r, l in left_of.items() if r in body_links}
    changes: list[str] = []
    inertias, source_of = mirrored_inertias(model, data, frame, body_links, left_of, changes,
                                            tolerance=mirror_tolerance)
    world = {j: frame.rotation(data.oMi[j].rotation) for j in body_links}
    bodies: dict[int, _Body] = {}
    for joint, (mass, com, inertia) in inertias.items():
        if joint in source_of:  # a twin's image: its principal axes mirrored in the world
            twin = bodies[source_of[joint]]
            moments = twin.moments.copy()
            R = world[joint].T @ S @ world[twin.joint] @ twin.R @ S
        else:
            moments, R = _principal(links[joint], mass, inertia, world[joint])
        bodies[joint] = _Body(links[joint], joint, mass, moments, com, R)
    contacts, half_widths = foot_contacts(soles, frame)
    spheres = leg_spheres(model, shapes[0], data, bodies, left_of, foot_ids, frame)
    owner = {full.getJointId(model.names[j]) if j > 1 else 1: (b.name, b.com, b.R)
             for j, b in bodies.items()}
    holds, unheld = locked_holds(full, q_lock, legs, owner)
    roles = {side: leg_roles(model, data, leg, axes, frame)
             for side, leg in (("l", left_leg), ("r", right_leg))}
    if max(frame.snapped) > 1e-9:
        changes.append(f"walking frame: turned by {frame.snapped[0]:.3g} rad and moved by "
                       f"{frame.snapped[1] * 1e3:.3g} mm onto the URDF's axes")
    source = {"urdf": urdf_file, **({"package_dirs": list(robot_dirs)} if robot_dirs else {}),
              "locked": lock_angles, **({"holds": holds} if holds else {})}
    return _write(model, data, full, bodies, ids, axes, balls, foot_ids, contacts, half_widths,
                  left_of, twins, frame, spheres, leg_clearance,
                  name or re.sub(r"[^A-Za-z0-9_-]", "_", full.name or "robot"),
                  changes, source, mirror_tolerance, unheld, roles)


def _write(model, data, full, bodies, ids, axes, balls, foot_ids, contacts, half_widths,
           left_of, twins, frame, spheres, leg_clearance, name, changes, source,
           mirror_tolerance, unheld, roles) -> UrdfDraft:
    order = [1] + [j for j in ids.values() if j in bodies]
    for foot, points in contacts.items():
        bodies[foot].points.update(points)
    ball_of = {ball.joints[2]: ball for ball in balls}
    joints, limits, efforts, speeds = {}, {}, {}, {}
    for jname, jid in ids.items():
        if jid in ball_of:  # the ball's last joint: the ball is one spherical joint
            ball = ball_of[jid]
            bp, bc = bodies[int(model.parents[ball.joints[0]])], bodies[jid]
            bp.points[ball.name], bc.points[ball.name] = ball_points(
                model, ball, axes, bp.R, bc.R, bp.name, bc.name)
            joints[ball.name] = {"parent": bp.name, "child": bc.name,
                                 "entry": ball.entry(bp.name, bc.name)}
        elif jid in bodies:
            parent = int(model.parents[jid])
            placement = model.jointPlacements[jid]
            bp, bc = bodies[parent], bodies[jid]
            bp.points[jname] = placement.translation
            bc.points[jname] = np.zeros(3)
            joints[jname] = {"parent": bp.name, "child": bc.name,
                             "axis": bp.R.T @ placement.rotation @ axes[jname],
                             "reference": bp.R.T @ placement.rotation @ bc.R}
        jm = model.joints[jid]
        lo, hi = float(model.lowerPositionLimit[jm.idx_q]), float(model.upperPositionLimit[jm.idx_q])
        if jm.nq == 1 and abs(lo) < 1e10 and abs(hi) < 1e10:
            limits[jname] = [round(max(math.degrees(lo), -_RANGE_MAX), 6),
                             round(min(math.degrees(hi), _RANGE_MAX), 6)]
        if 0 < model.effortLimit[jm.idx_v] < 1e10:
            efforts[jname] = float(model.effortLimit[jm.idx_v])
        if 0 < model.velocityLimit[jm.idx_v] < 1e10:
            speeds[jname] = round(math.degrees(model.velocityLimit[jm.idx_v]), 6)
    speed_limits = _speed_limits(model, order[1:], ball_of, left_of, speeds)
    local = {j: {p: bodies[j].local(v) for p, v in bodies[j].points.items()} for j in order}
    mirror_geometry({j: bodies[j].name for j in order}, left_of, twins, local, joints,
                    changes)
    # each body's link frame in its own: origin at the joint point (the root: -R^T com), R^T
    links = {bodies[j].name: _round(np.r_[local[j][ball_of[j].name if j in ball_of else
                                                   model.names[j]] if j != 1 else
                                          bodies[1].local(np.zeros(3)),
                                          matrix_rpy(bodies[j].R.T)]) for j in order}
    lock_angles = source["locked"]
    mirror = {bodies[left_of[j]].name: bodies[j].name for j in order if j in left_of}
    z_sole = min(float(data.oMi[f].act(p)[2]) for f in foot_ids for p in contacts[f].values())
    hip = [data.oMi[leg_path(model, f)[0]].translation[2] for f in foot_ids]
    leg = float(np.mean(hip)) - z_sole
    root = bodies[1]
    com_world = frame.point(root.com) - np.array([0.0, 0.0, z_sole])  # sole at z = 0
    point_feet = all("foot" in contacts[f] for f in foot_ids)  # else heel, forefoot
    side = {foot_ids[0]: "l", foot_ids[1]: "r"}
    contact_yaml, contact_names = [], {}
    for foot in (foot_ids[1], foot_ids[0]):
        for point in contacts[foot]:
            cname = f"foot_{side[foot]}" if point_feet else f"foot_{side[foot]}_{point}"
            contact_names[(side[foot], point)] = cname
            contact_yaml.append({"name": cname, "body": bodies[foot].name, "point": point})
    step = round(WALKER3D_STEP_RATIO * leg, 4)
    phases = _phases(contact_names, point_feet)
    sides = {name: side for (side, _), name in contact_names.items()}
    stance = {}
    for phase in phases:
        held = {sides[c] for c in phase["contacts"]}
        if len(held) == 1:
            stance.setdefault(held.pop(), []).append(phase["name"])
    envelope = walking_envelope(roles, limits, stance)
    time_step = round(0.01 * math.sqrt(leg / WALKER3D_LEG), 5)
    pace = scaling_upper(step, leg, time_step, phases, sides,
                         {j: speeds[j] for role in roles.values() for j in role["sweep"]
                          if j in speeds})
    fused = f" ({3 * len(balls)} as {len(balls)} spherical)" if balls else ""
    scene = {
        "name": name,
        "description": f"Legs of the URDF robot {full.name!r}: {len(ids)} revolute joints "
                       f"planned{fused}, {len(lock_angles)} locked (gait-planner scene "
                       f"from-urdf).",
        "gravity": 9.81,
        "root": {"body": root.name, "type": "free"},
        "bodies": [{"name": bodies[j].name, "mass": round(bodies[j].mass, 12),
                    "inertia": _round(bodies[j].moments),
                    "points": {p: _round(v) for p, v in local[j].items()},
                    **({"collision": [_round(np.r_[s[:3], s[3] + 1e-6], 6) for s in spheres[j]]}
                       if j in spheres
                       else {})} for j in order],
        "joints": [j.get("entry") or {
            "name": jname, "type": "revolute", "axis": _round(j["axis"]),
            "reference_rpy": _round(matrix_rpy(j["reference"])), "parent": j["parent"],
            "parent_point": jname, "child": j["child"], "child_point": jname}
            for jname, j in joints.items()],
        "contacts": contact_yaml,
        "initial_pose": {"root_position": _round(com_world),
                         "root_angles": _round(matrix_rpy(frame.rotation(root.R))[::-1])},
        "gait": {
            "step_length": step, "base_time_step": time_step,
            "scaling_bounds": [0.5, pace.upper], "friction_coefficient": 0.8,
            "cost": "kinetic_energy", "mirror": mirror,
            "phases": phases,
            "options": {**_swing_options(leg, half_widths), **envelope,
                        **({"leg_clearance": float(leg_clearance)} if spheres else {}),
                        "joint_limits": limits, "effort_limits": efforts,
                        **_speed_options(speed_limits, joints),
                        "step_length_bounds": [round(0.6 * step, 4), round(1.4 * step, 4)]},
        },
        "robot": {**source, "links": links},
    }
    header = (f"# Drafted by `gait-planner scene from-urdf` from the URDF robot {full.name!r}\n"
              f"# (gait_planner.model.urdf_import). Bodies: the leg links, directors their "
              f"principal axes;\n# joints: the URDF's, zero and sign as the URDF's. Leg length "
              f"(hip to sole) L = {leg:.4f} m:\n# step_length = 0.7066 L, base_time_step = "
              f"0.01 s sqrt(L / 0.897 m) (walker3d scaled).\n# Joint ranges: the URDF's within "
              f"+-{_RANGE_MAX} deg of its zero pose (the planner's range rows);\n# collision: "
              f"spheres containing the lower legs' collision geometry (leg_clearance between "
              f"legs);\n# joint_speed_limits: each joint's own velocity limit (a left-right pair's "
              f"and a ball's: the smaller;\n# joint_speed_max, the slowest, where none is under "
              f"{WALK_JOINT_SPEED:g} deg/s).\n# Walking envelope (gait_planner.model.urdf_envelope): the base "
              f"link within {UPRIGHT_DEG:g} deg of upright,\n# hip yaw within "
              f"+-{HIP_YAW_DEG:g} deg, the stance knee within +-{STANCE_KNEE_DEG:g} deg in "
              f"single support.\n") + pace.comment()
    if np.any(frame.W != np.eye(3)) or np.any(frame.origin != 0):
        header += (f"# Walking direction (the scene's x): the URDF's "
                   f"{_round(frame.W[:, 0], 6)}, told by {frame.cue}; left: "
                   f"{_round(frame.W[:, 1], 6)}; mid-plane through {_round(frame.origin, 6)} m "
                   f"(gait_planner.model.urdf_frame).\n")
    if lock_angles:
        header += "# Locked joints (merged into their parent): " + ", ".join(
            f"{k} = {v:g} rad" for k, v in lock_angles.items()) + "\n"
    if source.get("holds"):
        header += ("# robot.holds: the locked joints whose holding effort the plan keeps "
                   "within the URDF's\n# effort limit (gait_planner.model.urdf_holds)"
                   + "".join(f"; not bounded: {reason}" for reason in unheld) + "\n")
    if changes:
        asked = (f"; --mirror-tolerance {mirror_tolerance:g}"
                 if mirror_tolerance != MIRROR_TOLERANCE else "")
        header += f"# Made mirror-symmetric (the URDF's own data differ{asked}):\n" + "".join(
            f"#   {change}\n" for change in changes)
    text = header + yaml.safe_dump(scene, sort_keys=False, width=100, default_flow_style=None)
    return UrdfDraft(text, name, tuple(ids), lock_angles)


def _speed_options(limits: dict[str, float], joints) -> dict:
    """The gait's speed option: ``joint_speed_max`` the slowest limit where every planned
    joint has one and none is slower than a walk's joints turn (`WALK_JOINT_SPEED`: G1's
    1146 deg/s, iCub's, Bolt's; one row function for all, as the shipped scenes), else
    ``joint_speed_limits``, each joint its own (Romeo's hip yaw 18.3 deg/s, Talos's)."""
    if not limits:
        return {}
    if set(limits) == set(joints) and min(limits.values()) >= WALK_JOINT_SPEED:
        return {"joint_speed_max": min(limits.values())}
    return {"joint_speed_limits": limits}


def _speed_limits(model, joints, ball_of, left_of, speeds) -> dict[str, float]:
    """{scene joint: deg/s}: each planned joint's URDF velocity limit (`speeds`, by URDF
    joint), a ball's the smallest of its three joints' (its rows bound the whole relative
    rotation), a joint and its mirror twin's the smaller of theirs (the half cycle's mirror
    image walks each leg with the other's rows); joints without a limit left out."""
    def own(j):
        names = ([str(model.names[i]) for i in ball_of[j].joints] if j in ball_of
                 else [str(model.names[j])])
        values = [speeds[n] for n in names if n in speeds]
        return min(values) if values else None

    twin = {**left_of, **{l: r for r, l in left_of.items()}}
    out = {}
    for j in joints:
        values = [v for v in (own(j), own(twin[j]) if j in twin else None) if v is not None]
        if values:
            out[ball_of[j].name if j in ball_of else str(model.names[j])] = min(values)
    return out


def _swing_options(leg: float, half_widths: dict[int, float]) -> dict[str, float]:
    """walker3d's swing options (config/scenes/walker3d.yaml: 1 cm clearance reached over
    0.03 s, strikes slower than 1 m/s) scaled by the leg length L (lengths by L / 0.897 m,
    times by sqrt(L / 0.897 m)); for flat feet the roll moment's bound from the sole's
    half width (the contact geometry's lateral spread)."""
    scale = leg / WALKER3D_LEG
    out = {"swing_clearance": round(0.01 * scale, 5),
           "swing_clearance_ramp": round(0.03 * math.sqrt(scale), 5),
           "strike_speed_max": round(1.0 * math.sqrt(scale), 4)}
    if half_widths:
        out["foot_half_width"] = round(min(half_widths.values()), 5)
    return out


def _phases(names: dict[tuple[str, str], str], point_feet: bool) -> list[dict]:
    if point_feet:
        return [{"name": "stance_r", "contacts": [names[("r", "foot")]], "scaling": 0,
                 "intervals": 20},
                {"name": "stance_l", "contacts": [names[("l", "foot")]], "scaling": 0,
                 "intervals": 1}]
    rh, rf = names[("r", "heel")], names[("r", "forefoot")]
    lh, lf = names[("l", "heel")], names[("l", "forefoot")]
    return [{"name": "right_full", "contacts": [rh, rf], "scaling": 0, "intervals": 8},
            {"name": "right_forefoot", "contacts": [rf], "scaling": 1, "intervals": 8},
            {"name": "double_heel", "contacts": [rf, lh], "scaling": 2, "intervals": 8},
            {"name": "double_full", "contacts": [rf, lh, lf], "scaling": 3, "intervals": 8},
            {"name": "left_full", "contacts": [lh, lf], "scaling": 0, "intervals": 8}]


def _round(v, digits: int = 12) -> list[float]:
    return [round(float(x), digits) + 0.0 for x in v]
