"""A start state from joint states and the root's pose and twist (`ocp.joint_state`): a
plan's node converted to what a robot publishes and back is that node, its momentum the
recording's to first order in the time step, and bad states are refused naming what is
wrong."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gait_planner.io.messages import frame_tree, quaternion_msg
from gait_planner.model.angles import angle_names, configuration, joint_angles
from gait_planner.model.loader import load_scene, scene_from_text
from gait_planner.model.multibody import Multibody
from gait_planner.model.urdf_import import draft_scene
from gait_planner.ocp.joint_state import start_of_joint_state
from gait_planner.ocp.transition import StartError
from gait_planner.transitions import start_of_recording
from synthetic_result import _pose
from urdf_bipeds import biped

ROUND_OFF = 1e-12


def _published(scene, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position and quaternion (x, y, z, w) of the frame /tf publishes for the root at q."""
    i = scene.body_index(scene.root.body)
    phi, D = q[12 * i:12 * i + 3], q[12 * i + 3:12 * i + 12].reshape(3, 3).T
    offset = frame_tree(scene).root_pose
    if offset is not None:
        phi, D = phi + D @ offset[0], D @ offset[1]
    quaternion = quaternion_msg(D)
    return phi, np.array([quaternion[k] for k in "xyzw"])


def _twist(scene, q: np.ndarray, q_dot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The published root frame's linear and angular velocity (world) of (q, q_dot)."""
    i = scene.body_index(scene.root.body)
    D, D_dot = (v[12 * i + 3:12 * i + 12].reshape(3, 3).T for v in (q, q_dot))
    W = D_dot @ D.T  # omega^
    omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
    linear = q_dot[12 * i:12 * i + 3]
    offset = frame_tree(scene).root_pose
    if offset is not None:
        linear = linear + np.cross(omega, D @ offset[0])
    return linear, omega


def _state_of(scene, q, angles, rates, q_dot):
    position, xyzw = _published(scene, q)
    linear, angular = _twist(scene, q, q_dot)
    return dict(names=list(angle_names(scene)), positions=list(angles),
                velocities=list(rates), root_position=position, root_orientation_xyzw=xyzw,
                root_linear_velocity=linear, root_angular_velocity=angular, origin="test")


def _drafted_biped():
    """A drafted robot whose base link is not its root body's frame, with its URDF (for the
    /tf frames, `frame_tree`)."""
    urdf = biped()
    scene = scene_from_text(draft_scene(urdf).yaml, "biped.yaml")
    return dataclasses.replace(scene, robot=dataclasses.replace(scene.robot, urdf=urdf))


@pytest.mark.parametrize("scene", [load_scene("walker2d"), load_scene("walker3d"),
                                   _drafted_biped()], ids=["walker2d", "walker3d", "urdf"])
def test_a_configurations_published_state_gives_it_back(scene):
    """Poses along a motion (all joints and the root moving; planar scenes in their plane)
    converted to joint states and root pose + twist and back: q to round-off, and the
    momentum M q_dot of q_dot by the central difference of those poses."""
    mb = Multibody(scene)
    h = 1e-6
    for s in (0.1, 0.45, 0.8):
        q = configuration(scene, _pose(scene, s))
        q_dot = (configuration(scene, _pose(scene, s + h))
                 - configuration(scene, _pose(scene, s - h))) / (2 * h)
        angles = joint_angles(scene, q)
        rates = (joint_angles(scene, configuration(scene, _pose(scene, s + h)))
                 - joint_angles(scene, configuration(scene, _pose(scene, s - h)))) / (2 * h)
        start = start_of_joint_state(scene, **_state_of(scene, q, angles, rates, q_dot))
        assert np.abs(start.q - q).max() < ROUND_OFF
        assert np.abs(start.momentum - mb.mass_diagonal * q_dot).max() < 1e-6 * max(
            1.0, np.abs(mb.mass_diagonal * q_dot).max())


def test_a_drafted_robots_locked_joints_may_be_given():
    scene = _drafted_biped()
    locked = dict(scene.robot.locked)
    assert locked, "the biped's waist is locked by the draft"
    q = configuration(scene, _pose(scene, 0.3))
    state = _state_of(scene, q, joint_angles(scene, q), np.zeros(len(angle_names(scene))),
                      np.zeros_like(q))
    state["names"] += list(locked)
    state["positions"] += list(locked.values())
    state["velocities"] += [0.0] * len(locked)
    assert np.abs(start_of_joint_state(scene, **state).q - q).max() < ROUND_OFF


def test_a_plans_node_gives_the_recordings_momentum_to_first_order(solved):
    """walker2d's plan at every node inside a phase: the state a robot would publish there
    (the plan's joint angles and rates, the root's pose and its central-difference twist)
    gives the node's q to round-off and, as M q_dot, the discrete momentum of the recording
    (`start_of_recording`) to first order in h: in the free directions (P^T, where the
    joints' constraint forces vanish) within h times the walker's weight (measured: h / 2
    times it, 2.1-3.8 N s at h = 15 ms against momenta of 55-64 N s; the nodes at a phase
    change, a heel strike's velocity jump among them, are left out)."""
    plan = solved("walker2d")
    scene, result = plan.scene, plan.result
    mb = Multibody(scene)
    weight = 9.81 * sum(b.mass for b in scene.bodies)
    t, phases = result.times, result.phases
    inner = [n for n in range(1, result.n_nodes - 1)
             if phases[n - 1] == phases[n] == phases[n + 1]]
    assert len(inner) > result.n_nodes // 2
    for n in inner:
        q_dot = (result.q[n + 1] - result.q[n - 1]) / (t[n + 1] - t[n - 1])
        state = _state_of(scene, result.q[n], result.joint_angles[n],
                          result.joint_velocities[n], q_dot)
        start = start_of_joint_state(scene, **state)
        assert np.abs(start.q - result.q[n]).max() < 1e-9
        recorded = start_of_recording(scene, str(plan.path), float(t[n] - t[0]))
        P = np.array(mb.null_space(result.q[n]))
        error = np.abs(P.T @ (start.momentum - recorded.momentum)).max()
        h = float(max(t[n + 1] - t[n], t[n] - t[n - 1]))
        assert error < h * weight, (n, phases[n], error, h * weight)


def _good(scene):
    q = configuration(scene)
    return _state_of(scene, q, joint_angles(scene, q), np.zeros(len(angle_names(scene))),
                     np.zeros_like(q))


def test_bad_joint_states_are_refused_naming_what_is_wrong():
    scene = load_scene("walker3d")
    names = angle_names(scene)
    state = _good(scene)
    with pytest.raises(StartError, match="does not have: elbow_l"):
        start_of_joint_state(scene, **{**state, "names": names[:-1] + ("elbow_l",)})
    with pytest.raises(StartError, match=f"lacks the joints {names[-1]}"):
        start_of_joint_state(scene, **{**state, "names": names[:-1],
                                       "positions": state["positions"][:-1],
                                       "velocities": []})
    with pytest.raises(StartError, match=f"NaN or infinite values for {names[2]}"):
        start_of_joint_state(scene, **{**state, "positions": [
            np.nan if i == 2 else p for i, p in enumerate(state["positions"])]})
    with pytest.raises(StartError, match="names and 3 velocities"):
        start_of_joint_state(scene, **{**state, "velocities": [0.0] * 3})
    with pytest.raises(StartError, match="not a rotation"):
        start_of_joint_state(scene, **{**state, "root_orientation_xyzw": [0, 0, 0, 0]})
    with pytest.raises(StartError, match="root angular velocity must be 3 finite"):
        start_of_joint_state(scene, **{**state, "root_angular_velocity": [0, np.inf, 0]})
    planar = load_scene("walker2d")
    with pytest.raises(StartError, match="x-z plane, but the root's y position"):
        start_of_joint_state(planar, **{**_good(planar), "root_position": [0.0, 0.1, 1.0]})
    assert start_of_joint_state(scene, **{**state, "velocities": []}).q.shape == (
        Multibody(scene).k,)
