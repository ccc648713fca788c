"""A `PlanResult` as ROS message layouts: plain nested dicts and lists, no ROS import.

The one place that converts a plan into messages, and a request's start fields (a state
given or measured: `requested_start`) into a transition's `StartState`. The MCAP writer
serialises these dicts (`gait_planner.io.mcap_writer.CdrEncoder`, which refuses a dict
whose keys differ from the type's fields), and the ROS node copies them into rclpy
messages with `fill_message`.
Field names are exactly those of the .msg/.srv definitions (docs/design.md section 7);
builtin_interfaces/Time and Duration are ``{"sec": int, "nanosec": int}``; arrays are
lists of Python floats/ints/strs.

Conventions:

* Time: node n has ``time = t_n - t_0`` and ``header.stamp = start + (t_n - t_0)`` (ns,
  rounded); the ``frame_id`` of world-frame data is ``"world"``.
* Joint angles and their names: `gait_planner.model.angles` (spherical joints: pitch, roll,
  yaw with R_rel = Ry(pitch) Rx(roll) Rz(yaw); revolute: right-handed about the axis).
* Effort (JointTrajectory points and JointState): N m, in the order of the joint angle
  names, the torque conjugate to each joint angle (effort . angle rate = joint power), so a
  controller can use it with the positions as given. Node n carries the planner's node
  torque tau[n] (torques are linear in time between nodes), the torque node n's discrete
  equation applies, expressed with the angles at node n. A revolute
  joint's effort is its torque about the axis; a spherical joint's three efforts are the
  projections of its couple on the pitch axis (the parent's d2), the once-pitched roll axis
  and the child's yaw axis d3 (`gait_planner.model.angles.conjugate_torques`). The
  planner's raw torques (couple components along the parent's directors) are in
  `PlanResult.tau`.
* Contact forces (ContactForces): only the contacts active at the node, in the order of
  ``active_contacts``; points are the contact points' world positions phi + X_i d_i from q;
  forces are ``result.contact_forces[name][n]``, the force of the ground on the foot (N,
  world), published as the planner split them. For full contact (heel and forefoot of one
  foot both active) the two forces sum to the net ground force on that foot; how that net
  force is divided between the two points is the planner's convention (documented with the
  contact multipliers in gait_planner.ocp.contacts: each point's force lies in its own
  friction cone). The couple of the ground about the heel-toe line, which two point forces
  on that line cannot carry, is in the per-foot wrenches (`foot_wrenches`): force and
  moment about the mean of the foot's active points, and the centre of pressure.
* /tf: per node one TFMessage: ``world -> <root>`` (the root's COM and directors) and one
  transform per moving URDF joint (origin translation, rotation about the axis by the joint
  angle); /tf_static: the contact frames. Frames are those of `gait_planner.io.urdf`; for a
  scene drafted from a URDF (`Scene.robot`) those of that URDF (`frame_tree`,
  `gait_planner.io.robot_tree`), whose text is then /robot_description, and the
  JointTrajectory and /joint_states add its locked joints (`published_joints`).
"""

from __future__ import annotations

import importlib
import math
import re
from typing import Any, Mapping, Sequence

import numpy as np

from gait_planner.io.urdf import (WORLD_FRAME, KinematicJoint, KinematicTree, kinematic_tree,
                                 scene_to_urdf)
from gait_planner.model.angles import angle_names, conjugate_torques
from gait_planner.model.rotations import cross, rot_axis, rpy_matrix
from gait_planner.result import PlanResult

__all__ = ["check_result", "contact_forces", "contact_points", "fill_message", "foot_wrenches",
           "frame_tree", "joint_states", "published_joints",
           "joint_trajectory", "multibody_states", "node_efforts", "plan_response_fields",
           "quaternion_msg", "requested_start", "robot_description", "node_stamps_ns",
           "tf_messages", "tf_static", "time_msg", "time_ns", "walk_response_fields", "WORLD_FRAME"]

NS_PER_S = 1_000_000_000


# ---------------------------------------------------------------------------- helpers


def time_msg(ns: int) -> dict[str, int]:
    """builtin_interfaces/Time (or Duration) of a non-negative time in ns."""
    ns = int(ns)
    if ns < 0:
        raise ValueError(f"times before 1970 (or negative durations) are not used here: {ns} ns")
    return {"sec": ns // NS_PER_S, "nanosec": ns % NS_PER_S}


def node_stamps_ns(result: PlanResult, start_ns: int) -> list[int]:
    """Stamps (ns) of the nodes: start + (t_n - t_0), rounded to the nanosecond."""
    t = np.asarray(result.times, dtype=float)
    return [int(start_ns) + int(round((tn - t[0]) * NS_PER_S)) for tn in t]


def header(ns: int, frame_id: str) -> dict[str, Any]:
    return {"stamp": time_msg(ns), "frame_id": frame_id}


def _floats(values) -> list[float]:
    return [float(v) for v in np.asarray(values, dtype=float).ravel()]


def _frames(q_row: np.ndarray, nb: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """(phi, D) per body of one configuration row, D = [d1 d2 d3] (columns)."""
    return [(q_row[12 * i:12 * i + 3], q_row[12 * i + 3:12 * i + 12].reshape(3, 3).T)
            for i in range(nb)]


def quaternion_msg(R: np.ndarray) -> dict[str, float]:
    """geometry_msgs/Quaternion (unit, w >= 0) of a rotation matrix (Shepperd's method)."""
    m = np.asarray(R, dtype=float)
    trace = np.trace(m)
    diagonal = np.diag(m)
    k = int(np.argmax(np.r_[trace, diagonal]))
    if k == 0:
        w = 0.5 * math.sqrt(max(1.0 + trace, 0.0))
        s = 0.25 / w
        x, y, z = (m[2, 1] - m[1, 2]) * s, (m[0, 2] - m[2, 0]) * s, (m[1, 0] - m[0, 1]) * s
    else:
        i = k - 1
        j, l = (i + 1) % 3, (i + 2) % 3
        v = np.zeros(3)
        v[i] = 0.5 * math.sqrt(max(1.0 + m[i, i] - m[j, j] - m[l, l], 0.0))
        s = 0.25 / v[i]
        v[j] = (m[j, i] + m[i, j]) * s
        v[l] = (m[l, i] + m[i, l]) * s
        w = (m[l, j] - m[j, l]) * s
        x, y, z = v
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    sign = -1.0 if w < 0 else 1.0
    return {"x": sign * x / norm, "y": sign * y / norm, "z": sign * z / norm, "w": sign * w / norm}


def _joint_quaternion(joint: KinematicJoint, angle: float) -> dict[str, float]:
    """The rotation Rot(rpy) Rot(axis, angle) of a moving URDF joint (`KinematicJoint`)."""
    a = np.asarray(joint.axis, dtype=float)
    a = a / np.linalg.norm(a)
    s = math.sin(0.5 * angle)
    turn = {"x": float(a[0] * s), "y": float(a[1] * s), "z": float(a[2] * s),
            "w": float(math.cos(0.5 * angle))}
    if not any(joint.rpy):
        return turn
    return quaternion_msg(rpy_matrix(joint.rpy) @ rot_axis(a, angle))


def vector3(v) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def node_efforts(result: PlanResult) -> np.ndarray:
    """(N+1, na) efforts per node: the torques conjugate to the joint angles
    (`gait_planner.model.angles.conjugate_torques`) of the node torques tau[n]."""
    tau = np.asarray(result.tau, dtype=float)
    if tau.shape[0] == 0:
        return np.zeros((result.n_nodes, len(result.joint_angle_names)))
    return conjugate_torques(result.scene, result.joint_angles, tau)


# ---------------------------------------------------------------------------- validation


def check_result(result: PlanResult, *, finite: bool = True) -> None:
    """Raise ValueError (one sentence) unless `result`'s arrays have consistent shapes,
    strictly increasing times and, with `finite`, no NaN or infinity."""
    scene = result.scene
    n, nb = result.n_nodes, len(scene.bodies)
    names = tuple(result.joint_angle_names)
    na = len(names)

    def fail(what: str) -> None:
        raise ValueError(f"plan result (scene {scene.name!r}) cannot be converted: {what}")

    if n < 1:
        fail("it has no time nodes")
    if names != angle_names(scene):
        fail(f"joint_angle_names {names} differ from the scene's {angle_names(scene)}")
    shapes = {"times": (n,), "q": (n, 12 * nb), "tau": (n, na), "joint_angles": (n, na),
              "joint_velocities": (n, na), "joint_accelerations": (n, na),
              "generalized_force": (n, 12 * nb),
              "kinetic_energy": (n,), "potential_energy": (n,)}
    for field, shape in shapes.items():
        value = np.asarray(getattr(result, field), dtype=float)
        if value.shape != shape:
            fail(f"{field} has shape {value.shape}, expected {shape}")
        if finite and not np.all(np.isfinite(value)):
            fail(f"{field} contains NaN or infinite values")
    if n > 1 and not np.all(np.diff(result.times) > 0):
        fail("times are not strictly increasing")
    if len(result.phases) != n or len(result.active_contacts) != n:
        fail(f"phases ({len(result.phases)}) and active_contacts "
             f"({len(result.active_contacts)}) must have one entry per node ({n})")
    known = {c.name for c in scene.contacts}
    for node, active in enumerate(result.active_contacts):
        for name in active:
            if name not in known:
                fail(f"node {node} lists unknown contact {name!r}")
            if name not in result.contact_forces:
                fail(f"contact {name!r} is active at node {node} but has no contact_forces")
    for name, forces in result.contact_forces.items():
        forces = np.asarray(forces, dtype=float)
        if forces.shape != (n, 3):
            fail(f"contact_forces[{name!r}] has shape {forces.shape}, expected {(n, 3)}")
        if finite and not np.all(np.isfinite(forces)):
            fail(f"contact_forces[{name!r}] contains NaN or infinite values")


# ---------------------------------------------------------------------------- messages


def published_joints(result: PlanResult) -> tuple[list[str], np.ndarray, np.ndarray,
                                                  np.ndarray, np.ndarray]:
    """(names, positions, velocities, accelerations, efforts), each (N+1, n), of the joints
    the JointTrajectory and /joint_states carry: the planned joint angles, then for a scene
    drafted from a URDF its locked joints, held at their angle with the efforts that hold
    them (`PlanResult.held_efforts`); ValueError if those were not computed."""
    names = list(result.joint_angle_names)
    rows = [np.asarray(a, dtype=float) for a in (result.joint_angles, result.joint_velocities,
                                                  result.joint_accelerations)]
    effort = node_efforts(result)
    locked = dict(result.scene.robot.locked) if result.scene.robot is not None else {}
    if locked:
        missing = [name for name in locked if name not in result.held_efforts]
        if missing:
            raise ValueError(f"plan result (scene {result.scene.name!r}): no held efforts for "
                             f"the locked joints {missing} (set by the URDF certificate)")
        n, ones = result.n_nodes, np.ones((result.n_nodes, len(locked)))
        rows = [np.hstack([rows[0], ones * np.array(list(locked.values()))]),
                np.hstack([rows[1], 0 * ones]), np.hstack([rows[2], 0 * ones])]
        effort = np.hstack([effort, np.column_stack(
            [np.asarray(result.held_efforts[name], dtype=float).reshape(n) for name in locked])])
        names += list(locked)
    return names, rows[0], rows[1], rows[2], effort


def joint_trajectory(result: PlanResult, stamp_ns: int = 0) -> dict[str, Any]:
    """trajectory_msgs/JointTrajectory: one point per node (module docstring for effort);
    header.stamp = `stamp_ns` is the reference time of every time_from_start."""
    t = np.asarray(result.times, dtype=float)
    names, position, velocity, acceleration, effort = published_joints(result)
    points = [
        {
            "positions": _floats(position[n]),
            "velocities": _floats(velocity[n]),
            "accelerations": _floats(acceleration[n]),
            "effort": _floats(effort[n]),
            "time_from_start": time_msg(int(round((t[n] - t[0]) * NS_PER_S))),
        }
        for n in range(result.n_nodes)
    ]
    return {"header": header(stamp_ns, ""), "joint_names": names, "points": points}


def multibody_states(result: PlanResult, start_ns: int) -> list[dict[str, Any]]:
    """gait_planner_msgs/MultibodyState per node."""
    stamps = node_stamps_ns(result, start_ns)
    t = np.asarray(result.times, dtype=float)
    bodies = list(result.body_names)
    held = list(result.held_impulses)
    impulses = np.column_stack([np.asarray(result.held_impulses[name], dtype=float)
                                for name in held]) if held else np.zeros((result.n_nodes, 0))
    return [
        {
            "header": header(stamps[n], WORLD_FRAME),
            "node": n,
            "time": float(t[n] - t[0]),
            "phase": str(result.phases[n]),
            "active_contacts": list(result.active_contacts[n]),
            "body_names": bodies,
            "q": _floats(result.q[n]),
            "generalized_force": _floats(result.generalized_force[n]),
            "kinetic_energy": float(result.kinetic_energy[n]),
            "potential_energy": float(result.potential_energy[n]),
            "held_joint_names": held,
            "held_joint_impulses": _floats(impulses[n]),
        }
        for n in range(result.n_nodes)
    ]


def contact_points(result: PlanResult, node: int, names: Sequence[str]) -> list[np.ndarray]:
    """World positions phi + X_i d_i of the named contact points at `node`."""
    scene = result.scene
    frames = _frames(np.asarray(result.q[node], dtype=float), len(scene.bodies))
    out = []
    for name in names:
        contact = scene.contact(name)
        phi, D = frames[scene.body_index(contact.body)]
        out.append(phi + D @ np.asarray(scene.body(contact.body).points[contact.point]))
    return out


def foot_wrenches(result: PlanResult, node: int) -> list[tuple[str, np.ndarray, np.ndarray,
                                                               np.ndarray, np.ndarray]]:
    """Per body with an active contact at `node`, in scene body order: (body, reference
    point r, force F, moment M about r, centre of pressure), world frame, m, N, N m.
    r is the mean of the body's active points; F and M sum the point forces and their
    moments about r plus the full contact's roll moment M_roll (d2 x n, n the ground's
    normal: e_z on level ground, `gait_planner.ocp.contacts`); the centre of pressure is
    r + (n x M) / (n . F) (on level ground r + (-M_y, M_x, 0) / F_z; r itself where
    n . F <= 0)."""
    scene = result.scene
    normal = result.ground.normal
    names = list(result.active_contacts[node])
    points = dict(zip(names, contact_points(result, node, names)))
    frames = _frames(np.asarray(result.q[node], dtype=float), len(scene.bodies))
    out = []
    for body in (b.name for b in scene.bodies):
        mine = [c for c in names if scene.contact(c).body == body]
        if not mine:
            continue
        r = np.mean([points[c] for c in mine], axis=0)
        forces = [np.asarray(result.contact_forces[c], dtype=float)[node] for c in mine]
        F = np.sum(forces, axis=0)
        M = np.sum([cross(points[c] - r, f) for c, f in zip(mine, forces)], axis=0)
        roll = result.roll_moments.get(body)
        if roll is not None:
            d2 = frames[scene.body_index(body)][1][:, 1]
            M = M + float(roll[node]) * cross(d2, normal)
        pressing = float(normal @ F)
        cop = r + (cross(normal, M) / pressing if pressing > 0 else 0.0)
        out.append((body, r, F, M, cop))
    return out


def contact_forces(result: PlanResult, start_ns: int) -> list[dict[str, Any]]:
    """gait_planner_msgs/ContactForces per node, active contacts only (module docstring)."""
    stamps = node_stamps_ns(result, start_ns)
    t = np.asarray(result.times, dtype=float)
    messages = []
    for n in range(result.n_nodes):
        names = list(result.active_contacts[n])
        wrenches = foot_wrenches(result, n)
        messages.append({
            "header": header(stamps[n], WORLD_FRAME),
            "node": n,
            "time": float(t[n] - t[0]),
            "contact_names": names,
            "points": [vector3(p) for p in contact_points(result, n, names)],
            "forces": [vector3(np.asarray(result.contact_forces[c], dtype=float)[n])
                       for c in names],
            "wrench_bodies": [w[0] for w in wrenches],
            "wrench_points": [vector3(w[1]) for w in wrenches],
            "wrenches": [{"force": vector3(w[2]), "torque": vector3(w[3])} for w in wrenches],
            "centers_of_pressure": [vector3(w[4]) for w in wrenches],
        })
    return messages


def joint_states(result: PlanResult, start_ns: int) -> list[dict[str, Any]]:
    """sensor_msgs/JointState per node: angles, rates and efforts (module docstring)."""
    stamps = node_stamps_ns(result, start_ns)
    names, position, velocity, _, effort = published_joints(result)
    return [
        {
            "header": header(stamps[n], ""),
            "name": names,
            "position": _floats(position[n]),
            "velocity": _floats(velocity[n]),
            "effort": _floats(effort[n]),
        }
        for n in range(result.n_nodes)
    ]


def _transform(ns: int, parent: str, child: str, translation, rotation: dict) -> dict[str, Any]:
    return {"header": header(ns, parent), "child_frame_id": child,
            "transform": {"translation": vector3(translation), "rotation": rotation}}


def tf_messages(result: PlanResult, start_ns: int,
                tree: KinematicTree | None = None) -> list[dict[str, Any]]:
    """tf2_msgs/TFMessage per node: world -> root and every moving URDF joint."""
    scene = result.scene
    tree = tree or frame_tree(scene)
    stamps = node_stamps_ns(result, start_ns)
    root = scene.body_index(tree.root)
    messages = []
    for n in range(result.n_nodes):
        q = np.asarray(result.q[n], dtype=float)
        phi, D = q[12 * root:12 * root + 3], q[12 * root + 3:12 * root + 12].reshape(3, 3).T
        if tree.root_pose is not None:  # the robot's base link in the root body's frame
            phi, D = phi + D @ tree.root_pose[0], D @ tree.root_pose[1]
        transforms = [_transform(stamps[n], WORLD_FRAME, tree.root, phi, quaternion_msg(D))]
        for joint in tree.moving_joints:
            angle = float(result.joint_angles[n][joint.angle_index])
            transforms.append(_transform(stamps[n], joint.parent, joint.child, joint.origin,
                                         _joint_quaternion(joint, angle)))
        messages.append({"transforms": transforms})
    return messages


def tf_static(result: PlanResult, stamp_ns: int = 0,
              tree: KinematicTree | None = None) -> dict[str, Any]:
    """tf2_msgs/TFMessage of the fixed URDF joints (contact frames), stamped `stamp_ns`."""
    tree = tree or frame_tree(result.scene)
    return {"transforms": [_transform(stamp_ns, j.parent, j.child, j.origin,
                                      quaternion_msg(rpy_matrix(j.rpy)))
                           for j in tree.fixed_joints]}


def robot_description(result: PlanResult) -> dict[str, str]:
    """std_msgs/String holding the URDF of the plan's scene: the robot's own for a scene
    drafted from one (`Scene.robot`), else `gait_planner.io.urdf.scene_to_urdf`'s."""
    robot = result.scene.robot
    if robot is not None:
        if not robot.urdf:
            raise ValueError(f"scene {result.scene.name!r}: its URDF {robot.urdf_file!r} "
                             f"was not read")
        return {"data": robot.urdf}
    return {"data": scene_to_urdf(result.scene)}


def frame_tree(scene) -> KinematicTree:
    """The frames /tf and /tf_static publish: the robot's own URDF's for a scene drafted
    from one (`gait_planner.io.robot_tree`), else those of `gait_planner.io.urdf`."""
    if scene.robot is not None:
        from gait_planner.io.robot_tree import robot_tree

        return robot_tree(scene)
    return kinematic_tree(scene)


def plan_response_fields(result: PlanResult, mcap_path: str | None,
                         stamp_ns: int = 0) -> dict[str, Any]:
    """The fields of gait_planner_msgs/srv/PlanGait's response for `result`."""
    stats = result.stats
    return {
        "success": bool(result.success),
        "message": str(result.message),
        "solver_status": str(stats.status),
        "cost": float(result.cost_value),
        "step_length": float(result.step_length),
        "duration": float(result.duration),
        "phase_scaling": _floats(result.phase_scaling),
        "solve_time": float(stats.solve_time),
        "iterations": int(stats.iterations),
        "max_constraint_violation": float(stats.max_constraint_violation),
        "max_dynamics_residual": float(stats.max_dynamics_residual),
        "max_friction_violation": float(stats.max_friction_violation),
        "trajectory": joint_trajectory(result, stamp_ns),
        "mcap_path": str(mcap_path or ""),
        "continuous_torque_error": _setting(result, "continuous_torque_error"),
        "continuous_torque_error_at_switches": _setting(
            result, "continuous_torque_error_at_switches"),
        "continuous_base_force": _setting(result, "continuous_base_force"),
        "continuous_dynamics": str(result.settings.get("continuous_dynamics", "")),
    }


def walk_response_fields(steps: int, walked: Mapping[str, Any] | None,
                         error: str = "") -> dict[str, Any]:
    """The walk fields of PlanGait's response for a walk of `steps` half cycles: `walked` is
    the summary of `gait_planner.walk.walk_plan.walk`, None when the walk could not run
    (`error` says why: walk_stopped "not walked: ERROR", feedback share NaN)."""
    if walked is None:
        return {"walk_steps": int(steps), "walk_half_cycles": 0,
                "walk_feedback_share": math.nan, "walk_stopped": f"not walked: {error}",
                "walk_touches": 0, "walk_first_touch": ""}
    touches = walked["unplanned_touches"]
    return {"walk_steps": int(steps), "walk_half_cycles": int(walked["half_cycles_walked"]),
            "walk_feedback_share": float(walked["feedback_share"]),
            "walk_stopped": str(walked["stopped"]), "walk_touches": len(touches),
            "walk_first_touch": touches[0]["words"] if touches else ""}


def _setting(result: PlanResult, key: str) -> float:
    """A numeric entry of result.settings, NaN where the plan has none."""
    return float(result.settings.get(key, "nan"))


# ---------------------------------------------------------------------------- a request's start

# PlanGait's `start`: "" the periodic gait, "standing" the scene's standing pose at rest,
# "state" the request's state, "robot" the node's latest /joint_states and /tf
START_KINDS = ("", "standing", "state", "robot")


def time_ns(stamp: Any) -> int:
    """ns of a builtin_interfaces/Time (attributes sec, nanosec)."""
    return int(stamp.sec) * NS_PER_S + int(stamp.nanosec)


def _xyz(v: Any) -> list[float]:
    return [float(v.x), float(v.y), float(v.z)]


def requested_start(scene, request: Any, joint_state: Any = None,
                    transforms: Mapping[str, Any] | None = None):
    """(StartState or None, stamp ns or None) of a PlanGait request's or goal's start fields
    (srv/PlanGait.srv): start "" is the periodic gait (None, None); "standing" the scene's
    standing pose at rest (`ocp.transition.standing_start`, stamp None); "state" the request's
    `state` (sensor_msgs/JointState), `root_pose` and `root_twist`; "robot" the node's latest
    /joint_states `joint_state` and, from `transforms` (child frame -> the latest
    geometry_msgs/TransformStamped from ``world``; None: the node has no /tf subscription),
    the root frame the node's recordings publish (`frame_tree`), with `root_twist`. The stamp is the JointState's (0: none).
    RequestError for another start;
    `ocp.transition.StartError` for a state that cannot be used or a robot state not yet
    received, naming what (`ocp.joint_state.start_of_joint_state`)."""
    from gait_planner.ocp.joint_state import start_of_joint_state
    from gait_planner.ocp.transition import StartError, standing_start
    from gait_planner.request import RequestError

    kind = str(getattr(request, "start", "") or "")
    if kind not in START_KINDS:
        raise RequestError(f"start must be \"\" (the periodic gait), \"standing\", \"state\" "
                           f"or \"robot\", got {kind!r}")
    if not kind:
        return None, None
    if kind == "standing":
        return standing_start(scene), None
    twist = request.root_twist
    if kind == "state":
        state, pose = request.state, request.root_pose
        position, rotation = _xyz(pose.position), pose.orientation
        origin = "the request's state"
    else:
        root = frame_tree(scene).root
        if joint_state is None:
            raise StartError("start \"robot\": no /joint_states received yet")
        if transforms is None:
            raise StartError("start \"robot\": the node does not subscribe to /tf (tf2_msgs "
                             "is not installed; `make setup` builds it)")
        held = dict(transforms)
        if root not in held:
            raise StartError(f"start \"robot\": no transform {WORLD_FRAME} -> {root} received "
                             f"on /tf yet (from {WORLD_FRAME}: "
                             f"{', '.join(sorted(held)) or 'none'})")
        state, transform = joint_state, held[root].transform
        position, rotation = _xyz(transform.translation), transform.rotation
        origin = f"the robot's /joint_states and /tf {WORLD_FRAME} -> {root}"
    start = start_of_joint_state(
        scene, list(state.name), list(state.position), list(state.velocity), position,
        [float(rotation.x), float(rotation.y), float(rotation.z), float(rotation.w)],
        _xyz(twist.linear), _xyz(twist.angular), origin)
    return start, time_ns(state.header.stamp)


# ---------------------------------------------------------------------------- rclpy messages

_SEQUENCE = re.compile(r"^sequence<([\w]+)/([\w]+)(?:, ?\d+)?>$|^([\w]+)/([\w]+)\[\d*\]$")


def _element_class(msg: Any, field: str) -> type:
    """The message class of the elements of the message-array field `field` of `msg`."""
    spec = msg.get_fields_and_field_types()[field]
    match = _SEQUENCE.match(spec)
    if not match:
        raise TypeError(f"{type(msg).__name__}.{field} ({spec}) is not an array of messages")
    package, name = (match.group(1), match.group(2)) if match.group(1) else match.group(3, 4)
    return getattr(importlib.import_module(f"{package}.msg"), name)


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def fill_message(msg: Any, data: Mapping[str, Any]) -> Any:
    """Copy the nested dict `data` (the layouts of this module) into the rclpy message `msg`
    and return `msg`. Nested messages are filled in place, arrays of messages are built
    from their element class (imported lazily); unknown field names raise AttributeError."""
    fields = msg.get_fields_and_field_types()
    for key, value in data.items():
        if key not in fields:
            raise AttributeError(f"{type(msg).__name__} has no field {key!r} "
                                 f"(fields: {', '.join(fields)})")
        value = _plain(value)
        if isinstance(value, Mapping):
            fill_message(getattr(msg, key), value)
        elif isinstance(value, (list, tuple)) and value and isinstance(value[0], Mapping):
            cls = _element_class(msg, key)
            setattr(msg, key, [fill_message(cls(), item) for item in value])
        else:
            setattr(msg, key, value)
    return msg
