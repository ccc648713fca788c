"""A transition's start from a measured robot state: joint states and the root's pose and
twist, as a controller or a simulator publishes them (sensor_msgs/JointState and the
world -> root transform of /tf), converted to a `StartState` (issue #62).

* Joint angles are named as the plan's JointTrajectory names them
  (`gait_planner.model.angles.angle_names`: for a scene drafted from a URDF the URDF's
  joint names); a drafted robot's locked joints (`RobotSource.locked`) may be given too and
  are ignored (the plan holds them at their locked angle).
* The root pose is that of the frame /tf publishes as the child of ``world``: the root
  body's centre of mass and directors, or for a drafted robot its base link
  (`RobotSource.link_pose` of the root body), from which the root body's pose follows.
* The twist is the root frame's, in world components: the linear velocity of its origin
  (m/s) and the angular velocity (rad/s).

q is `configuration` of the pose (so it meets the joint constraints to round-off) and
q_dot its central difference along the measured rates (second order: the q of the
perturbed poses are exact configurations, so q_dot is exact to O(`STEP`^2) plus round-off
over `STEP`); the momentum is M q_dot (`start_of_velocity`). Pure numerics: no ROS.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from gait_planner.model.angles import angle_names, configuration, root_angles
from gait_planner.model.rotations import rot_axis
from gait_planner.model.scene import InitialPose, Scene
from gait_planner.ocp.transition import StartError, StartState, start_of_velocity

STEP = 1e-5  # s, the central difference of the configuration along the measured rates
# How far (m, rad, m/s, rad/s) a planar scene's root may leave its plane (x-z, turning
# about y) before the state is refused.
PLANAR_TOLERANCE = 1e-6


def _quaternion_matrix(xyzw: Sequence[float]) -> np.ndarray:
    """The rotation of a quaternion (x, y, z, w), normalised; StartError if it is zero."""
    x, y, z, w = (float(v) for v in xyzw)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not norm > 1e-9:
        raise StartError(f"the root orientation ({x:g}, {y:g}, {z:g}, {w:g}) is not a rotation "
                         "(a zero quaternion)")
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _joint_values(scene: Scene, names: Sequence[str], positions: Sequence[float],
                  velocities: Sequence[float]) -> tuple[dict[str, float], dict[str, float]]:
    """angle name -> position, angle name -> rate of the planned joints; StartError for an
    unknown or missing joint, mismatched lengths or a non-finite value, naming them."""
    planned = angle_names(scene)
    locked = set(scene.robot.locked) if scene.robot is not None else set()
    names = [str(n) for n in names]
    if len(positions) != len(names):
        raise StartError(f"the joint state has {len(names)} names and {len(positions)} "
                         "positions")
    if len(velocities) not in (0, len(names)):
        raise StartError(f"the joint state has {len(names)} names and {len(velocities)} "
                         "velocities (give one per name, or none for zero)")
    unknown = [n for n in names if n not in planned and n not in locked]
    if unknown:
        raise StartError(f"the joint state names joints {scene.name} does not have: "
                         f"{', '.join(unknown)} (its joints: {', '.join(planned)})")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise StartError(f"the joint state names {', '.join(repeated)} more than once")
    missing = [n for n in planned if n not in names]
    if missing:
        raise StartError(f"the joint state lacks the joints {', '.join(missing)} of "
                         f"{scene.name}")
    rates = velocities if len(velocities) else [0.0] * len(names)
    bad = [n for n, p, v in zip(names, positions, rates)
           if n in planned and not (math.isfinite(float(p)) and math.isfinite(float(v)))]
    if bad:
        raise StartError(f"the joint state has NaN or infinite values for {', '.join(bad)}")
    position = {n: float(p) for n, p in zip(names, positions)}
    rate = {n: float(v) for n, v in zip(names, rates)}
    return position, rate


def _root_body(scene: Scene, position: np.ndarray, rotation: np.ndarray, linear: np.ndarray,
               angular: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(phi, D, phi_dot) of the root body from the pose and twist of its published frame
    (a drafted robot's base link: `RobotSource.link_pose`)."""
    if scene.robot is None:
        return position, rotation, linear
    offset, turn = scene.robot.link_pose(scene.root.body)
    D = rotation @ turn.T
    phi = position - D @ offset
    return phi, D, linear + np.cross(angular, phi - position)


def _check_planar(scene: Scene, phi: np.ndarray, D: np.ndarray, phi_dot: np.ndarray,
                  angular: np.ndarray) -> None:
    yaw, _, roll = root_angles(D)
    off = {"y position (m)": phi[1], "yaw (rad)": yaw, "roll (rad)": roll,
           "y velocity (m/s)": phi_dot[1], "x angular velocity (rad/s)": angular[0],
           "z angular velocity (rad/s)": angular[2]}
    out = {k: float(v) for k, v in off.items() if abs(v) > PLANAR_TOLERANCE}
    if out:
        raise StartError(f"{scene.name} moves in the x-z plane, but the root's "
                         + ", ".join(f"{k} is {v:.3g}" for k, v in out.items()))


def start_of_joint_state(scene: Scene, names: Sequence[str], positions: Sequence[float],
                         velocities: Sequence[float], root_position: Sequence[float],
                         root_orientation_xyzw: Sequence[float],
                         root_linear_velocity: Sequence[float],
                         root_angular_velocity: Sequence[float], origin: str) -> StartState:
    """The `StartState` of a measured state (module docstring): joint `names`, `positions`
    (rad) and `velocities` (rad/s; empty: zero), the root frame's position (m) and
    orientation (quaternion x, y, z, w) in the world, its linear (m/s) and angular (rad/s)
    velocity in world components. StartError for an unknown or missing joint, a NaN, a
    zero quaternion, or a planar scene's root out of its plane, naming what is wrong."""
    position, rate = _joint_values(scene, names, positions, velocities)
    root = [np.asarray(v, dtype=float).ravel() for v in
            (root_position, root_orientation_xyzw, root_linear_velocity, root_angular_velocity)]
    for label, value, size in zip(("position", "orientation", "linear velocity",
                                   "angular velocity"), root, (3, 4, 3, 3)):
        if value.shape != (size,) or not np.all(np.isfinite(value)):
            raise StartError(f"the root {label} must be {size} finite numbers, got "
                             f"{value.tolist()}")
    phi, D, phi_dot = _root_body(scene, root[0], _quaternion_matrix(root[1]), root[2], root[3])
    omega = root[3]
    if scene.planar:
        _check_planar(scene, phi, D, phi_dot, omega)
    speed = float(np.linalg.norm(omega))

    def at(s: float) -> np.ndarray:
        turn = rot_axis(omega / speed, s * speed) if speed > 0 else np.eye(3)
        angles = {}
        for joint in scene.joints:
            angles[joint.name] = tuple(position[a] + s * rate[a] for a in joint.angle_names)
        return configuration(scene, InitialPose(tuple(phi + s * phi_dot),
                                                root_angles(turn @ D), angles))

    q = at(0.0)
    q_dot = (at(STEP) - at(-STEP)) / (2 * STEP)
    return start_of_velocity(scene, q, q_dot, origin)
