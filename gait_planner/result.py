"""The plain result of a plan: numpy arrays and statistics, nothing else.

`gait_planner.ocp.plan` returns a `PlanResult`; MCAP, rerun and ROS messages only consume
it (`gait_planner.io.messages` owns the conversion to message layouts).

Node and interval conventions (docs/design.md section 7): nodes n = 0 .. N, intervals
n = 0 .. N-1 between t_n and t_{n+1}. Joint torques are node values tau[n], linear in
time between nodes; node n's discrete equation applies (h_{n-1} + h_n)/2 B^T(q_n) tau[n]
(`gait_planner.ocp.transcription`). Nodes N-1 and N
are the mirror images of nodes 0 and 1 (shifted by the step length), so the half cycle
lasts t_{N-1} - t_0 (`duration`).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np

from gait_planner.model.ground import LEVEL, Ground
from gait_planner.model.scene import Scene


class PlanStatus(enum.Enum):
    """How a plan ended; `PlanResult.message` says it in words, with the solver's detail."""

    CONVERGED = "converged"  # the solver met its tolerances: success True
    FAILED = "failed"  # did not converge (iteration cap, infeasible, time limit, error)
    STOPPED = "stopped"  # ended on request (`Planner.stop`: a cancel, the node's shutdown)


@dataclass(frozen=True)
class SolverStats:
    """What the solver reports about one solve."""

    status: str  # IPOPT's return status in words, e.g. "Solve_Succeeded"
    iterations: int
    solve_time: float  # s, wall clock of the NLP solve alone
    build_time: float = 0.0  # s, building the transcription (cached builds cost ~0)
    evaluation_time: float = 0.0  # s of solve_time spent evaluating functions/derivatives
    max_constraint_violation: float = float("nan")  # largest |g| of holonomic constraints, m
    max_dynamics_residual: float = float("nan")  # largest reduced DEL residual, N / N m
    max_friction_violation: float = float("nan")  # largest cone violation, N
    most_violated: str = ""  # name of the most violated constraint group on failure


@dataclass(frozen=True)
class PlanResult:
    """A planned half-cycle gait (or a failed attempt, with `success = False`). Built once:
    a step that adds to it (the certificate, a refinement's note, the joined half cycles)
    makes a new one (`dataclasses.replace`); its arrays and dicts are not changed after.

    Shapes: N intervals, N + 1 nodes, nb bodies, k = 12 nb, na joint angles,
    nt joint torque components (= na), C contact points of the scene.

    Attributes:
        times: (N+1,) s, times[0] = 0.
        q: (N+1, k) director coordinates per node, bodies in scene order, each
            (phi, d1, d2, d3) in world coordinates (m, -).
        tau: (N+1, nt) joint torques per node, N m; spherical joints: components along
            the parent's directors; revolute joints: about the joint axis.
        joint_angle_names / joint_angles: (N+1, na) rad, `gait_planner.model.angles`.
        joint_velocities, joint_accelerations: (N+1, na) rad/s, rad/s^2: three-point
            central differences of the angles, at nodes 0 and N with the periodic
            continuation (`gait_planner.ocp.solution.joint_rates`).
        phases: (N+1,) phase name of each node.
        active_contacts: (N+1,) names of the contacts held at each node.
        contact_forces: contact name -> (N+1, 3) ground force on the body, N, world frame;
            zero where the contact is not active.
        roll_moments: body name -> (N+1,) N m, the moment of the ground about the heel-toe
            line of a body in 3D full contact, acting as M (d2 x n), n the ground's normal
            (`ocp.contacts`), which two point forces on that line cannot carry; zero
            elsewhere.
        generalized_force: (N+1, k) f+_{n-1} + f-_n (N s: discrete forces are impulses
            over half intervals; director form, zero on phi).
        kinetic_energy, potential_energy: (N+1,) J.
        phase_scaling: sigma, (n_sigma,).
        cost_value: J of `cost_name` over the half cycle (J s for kinetic_energy).
        held_efforts: a scene drafted from a URDF: locked joint -> (N+1,) N m, what holds
            it (inverse dynamics on the URDF, `gait_planner.verify.robot`); set with the
            certificate, published in the JointTrajectory beside the planned joints; at a
            node where a contact is established, its neighbours' mean.
        held_impulses: locked joint -> (N+1,) N m s, the impact's impulse on it at a node
            where a contact is established (zero elsewhere; MultibodyState's
            held_joint_impulses), kept out of the efforts (`gait_planner.verify.robot`).
    """

    success: bool
    message: str
    scene: Scene
    cost_name: str
    cost_value: float
    step_length: float
    friction_coefficient: float
    times: np.ndarray
    q: np.ndarray
    tau: np.ndarray
    joint_angle_names: tuple[str, ...]
    joint_angles: np.ndarray
    joint_velocities: np.ndarray
    joint_accelerations: np.ndarray
    phases: tuple[str, ...]
    active_contacts: tuple[tuple[str, ...], ...]
    contact_forces: dict[str, np.ndarray]
    roll_moments: dict[str, np.ndarray]
    generalized_force: np.ndarray
    kinetic_energy: np.ndarray
    potential_energy: np.ndarray
    phase_scaling: np.ndarray
    duration: float
    stats: SolverStats
    settings: dict[str, str] = field(default_factory=dict)  # extra metadata, strings
    ground: Ground = LEVEL  # what the plan stands on (`gait_planner.model.ground`)
    held_efforts: dict[str, np.ndarray] = field(default_factory=dict)
    held_impulses: dict[str, np.ndarray] = field(default_factory=dict)
    status: PlanStatus | None = None  # None: CONVERGED if success else FAILED

    def __post_init__(self) -> None:
        if self.status is None:
            object.__setattr__(self, "status", PlanStatus.CONVERGED if self.success
                               else PlanStatus.FAILED)

    @property
    def n_nodes(self) -> int:
        return int(self.times.shape[0])

    @property
    def body_names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.scene.bodies)
