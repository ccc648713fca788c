"""A small synthetic but kinematically consistent PlanResult of walker3d for the io and viz tests
(their fixtures `result`, `make_result` and `start_ns` are in test/conftest.py).

`make_result()` moves the walker through a few poses: q from
`gait_planner.model.angles.configuration` (every joint constraint exact), joint angles
from `joint_angles`, velocities by finite differences, energies from q, contacts following
the scene's gait phases with arbitrary (but plausible) forces, arbitrary torques and
generalised forces. It is not a solution of the dynamics: the io code only converts it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from gait_planner.model.angles import angle_names, configuration, joint_angles
from gait_planner.model.loader import load_scene
from gait_planner.model.scene import InitialPose, JointType, Scene
from gait_planner.result import PlanResult, SolverStats

START_NS = 1_700_000_000_123_456_789  # an arbitrary plan start, ns since the epoch


def _pose(scene: Scene, s: float) -> InitialPose:
    """A pose along a short motion, s in [0, 1]; roll angles stay well inside (-90, 90) deg;
    planar scenes stay in the x-z plane."""
    angles = {}
    for k, joint in enumerate(scene.joints):
        phase = 0.7 * k + 2 * np.pi * s
        if joint.type is JointType.SPHERICAL:
            angles[joint.name] = (0.5 * np.sin(phase), 0.2 * np.cos(phase), 0.3 * np.sin(2 * phase))
        else:
            angles[joint.name] = (0.4 + 0.3 * np.sin(phase),)
    base = np.asarray(scene.initial_pose.root_position)
    if scene.planar:
        return InitialPose(root_position=tuple(base + [0.3 * s, 0.0, 0.02 * s]),
                           root_angles=(0.0, 0.15 * np.sin(2 * s), 0.0), joint_angles=angles)
    shift = [0.3 * s, 0.02 * np.sin(3 * s), -0.03 + 0.02 * s]
    return InitialPose(root_position=tuple(base + shift),
                       root_angles=(0.1 * s, 0.15 * np.sin(2 * s), -0.05 * s),
                       joint_angles=angles)


def _kinetic_energy(scene: Scene, q: np.ndarray, times: np.ndarray) -> np.ndarray:
    diag = np.concatenate([np.r_[[b.mass] * 3, np.repeat(b.euler_tensor, 3)]
                           for b in scene.bodies])
    v = np.diff(q, axis=0) / np.diff(times)[:, None]
    t_interval = 0.5 * np.einsum("ij,j,ij->i", v, diag, v)
    return np.r_[t_interval[0], 0.5 * (t_interval[:-1] + t_interval[1:]), t_interval[-1]]


def _points_by_body(scene: Scene) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for c in scene.contacts:
        out.setdefault(c.body, []).append(c.name)
    return out


def make_result(scene_name: str = "walker3d", intervals: int = 10, **changes) -> PlanResult:
    """A successful-looking PlanResult with `intervals` intervals; `changes` replace fields."""
    scene = load_scene(scene_name)
    n = intervals + 1
    rng = np.random.default_rng(7)
    times = np.cumsum(np.r_[0.0, 0.01 + 0.005 * rng.random(intervals)])
    q = np.array([configuration(scene, _pose(scene, s)) for s in np.linspace(0, 1, n)])
    angles = joint_angles(scene, q)
    gait = scene.gait
    phase_of_node = np.minimum(np.arange(n) * len(gait.phases) // n, len(gait.phases) - 1)
    phases = tuple(gait.phases[i].name for i in phase_of_node)
    active = tuple(tuple(gait.phases[i].contacts) for i in phase_of_node)
    forces = {}
    for c in scene.contacts:
        f = np.zeros((n, 3))
        for node in range(n):
            if c.name in active[node]:
                f[node] = [20.0 * np.sin(node), -5.0 + node, 150.0 + 10.0 * node]
        forces[c.name] = f
    nt = len(angle_names(scene))
    k = 12 * len(scene.bodies)
    gf = rng.normal(size=(n, k))
    for i in range(len(scene.bodies)):
        gf[:, 12 * i:12 * i + 3] = 0.0  # pure couples: no force on phi
    potential = np.array([sum(b.mass * scene.gravity * row[12 * i + 2]
                              for i, b in enumerate(scene.bodies)) for row in q])
    result = PlanResult(
        success=True,
        message="synthetic result for io tests",
        scene=scene,
        cost_name="kinetic_energy",
        cost_value=41.2256,
        step_length=gait.step_length,
        friction_coefficient=gait.friction_coefficient,
        times=times,
        q=q,
        tau=rng.normal(scale=50.0, size=(n, nt)),
        joint_angle_names=angle_names(scene),
        joint_angles=angles,
        joint_velocities=np.gradient(angles, times, axis=0),
        joint_accelerations=np.gradient(np.gradient(angles, times, axis=0), times, axis=0),
        phases=phases,
        active_contacts=active,
        contact_forces=forces,
        roll_moments={b: np.where([len(pts) == 2 and not scene.planar and set(pts) <= set(a)
                                   for a in active], 3.0 * np.cos(np.arange(n)), 0.0)
                      for b, pts in _points_by_body(scene).items()},
        generalized_force=gf,
        kinetic_energy=_kinetic_energy(scene, q, times),
        potential_energy=potential,
        phase_scaling=np.array([1.5, 1.5, 1.4889, 1.4724]),
        duration=float(times[-2] - times[0]),
        stats=SolverStats(status="Solve_Succeeded", iterations=42, solve_time=1.25,
                          max_constraint_violation=3e-12, max_dynamics_residual=1e-9,
                          max_friction_violation=0.0),
        settings={"torque_weight": "1e-06", "nodes_per_phase": "2"},
    )
    return dataclasses.replace(result, **changes) if changes else result
