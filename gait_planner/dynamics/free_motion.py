"""Free-floating motion from a scene's initial pose, and its error report.

Backs ``gait-planner simulate``, the structure-preservation tests and the benchmarks: the
walker starts in its scene pose with seeded random generalised velocities (so the limbs
really swing) and, optionally, seeded random smooth internal joint torques. Optionally one
contact point is pinned (held at its initial position): with gravity the walker then swings
about it like a multiple pendulum, a bounded motion whose energy error must stay bounded.

Conserved quantities: a free root conserves all components of the linear and angular
momentum without gravity and without pin; a planar root only L_x, L_z and J_y (the planar
constraints phi_y = const, d2 = e_y exert forces along y and moments about x and z).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Callable

import numpy as np

from gait_planner.dynamics.discrete import DiscreteMechanics
from gait_planner.dynamics.forward import Simulator, Trajectory
from gait_planner.model.angles import configuration
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene

# Random torques accelerate each joint's child by about this much (rad/s^2) at most.
TORQUE_ACCELERATION = 2.0


def random_velocity(mb: Multibody, q0: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """nu_0 (ndof,): rotation rates ~ N(0, 1) rad/s; the root's translational velocity is
    chosen so that the total linear momentum is zero (the centre of mass stays at rest
    without gravity, so positions, and with them the round-off, stay bounded)."""
    nu = rng.normal(0.0, 1.0, mb.ndof)
    translation = [0, 1, 2] if mb.root_dof == 6 else [0, 1]
    nu[translation] = 0.0
    P = np.array(mb.null_space(q0))
    mass = sum(b.mass for b in mb.scene.bodies)
    phis = [slice(12 * i, 12 * i + 3) for i in range(mb.nb)]
    com_velocity = sum(b.mass * (P[s] @ nu) for b, s in zip(mb.scene.bodies, phis)) / mass
    nu[translation] = -com_velocity[[0, 1, 2] if mb.root_dof == 6 else [0, 2]]
    return nu


def pinned_velocity(mb: Multibody, q0: np.ndarray, nu: np.ndarray, contact: str) -> np.ndarray:
    """nu (ndof,) with the root's translational velocity changed so that the contact point
    `contact` is at rest (the pinned motion starts consistent with its constraint)."""
    translation = [0, 1, 2] if mb.root_dof == 6 else [0, 1]
    CP = mb.contact_rows(contact) @ np.array(mb.null_space(q0))
    nu = np.array(nu, dtype=float)
    nu[translation] -= np.linalg.solve(CP[:, translation], CP @ nu)
    return nu


def conserved_components(mb: Multibody) -> tuple[list[int], list[int]]:
    """Indices of the linear and angular momentum components conserved without gravity,
    pin and external torque: all for a free root; (x, z) and (y) for a planar root."""
    return ([0, 1, 2], [0, 1, 2]) if mb.root_dof == 6 else ([0, 2], [1])


def random_torques(mb: Multibody, rng: np.random.Generator) -> Callable[[float], np.ndarray]:
    """Smooth random internal torques tau(t) (nt,), N m: per component a sum of three
    sinusoids (0.5-5 rad/s), amplitude TORQUE_ACCELERATION times the child's largest
    principal inertia, so light feet are not spun up faster than the step can resolve."""
    scale = np.concatenate([
        np.full(j.dof, TORQUE_ACCELERATION * max(mb.scene.body(j.child).inertia))
        for j in mb.scene.joints
    ])
    amp = rng.normal(0.0, 1.0, (3, mb.nt)) * scale / np.sqrt(3)
    omega = rng.uniform(0.5, 5.0, (3, mb.nt))
    phase = rng.uniform(0.0, 2 * np.pi, (3, mb.nt))
    return lambda t: np.sum(amp * np.sin(omega * t + phase), axis=0)


@dataclasses.dataclass(frozen=True)
class FreeMotionReport:
    """Errors of a free-floating run (see `report`)."""

    steps: int
    dt: float
    gravity: bool
    torques: str
    seed: int
    energy_error_max: float  # max |E_n - E_0| / max T (dimensionless)
    # conserved components only (`conserved_components`); not conserved with a pin
    linear_momentum_error_max: float  # max |L_n - L_0|, kg m/s
    angular_momentum_error_max: float  # max |J_n - J_0|, kg m^2/s
    linear_momentum_scale: float  # max_n sum_bodies |p_phi|: what round-off is relative to
    angular_momentum_scale: float  # max_n sum_bodies |phi x p_phi| + sum_i |d_i x p_di|
    constraint_violation_max: float  # max |g(q_n)|
    newton_iterations_mean: float
    wall_time_s: float


def energies(mech: DiscreteMechanics, traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Per interval: kinetic energy T(v_n), v_n = (q_{n+1} - q_n)/h_n, and the total
    energy E_n = T(v_n) + (V(q_n) + V(q_{n+1}))/2 (J); shapes (N,)."""
    h = np.diff(traj.times)[:, None]
    v = np.diff(traj.q, axis=0) / h
    T = 0.5 * np.einsum("ni,i,ni->n", v, mech.mb.mass_diagonal, v)
    V = traj.q @ mech.gravity_gradient
    return T, T + 0.5 * (V[:-1] + V[1:])


def momenta(mech: DiscreteMechanics, traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Linear (N+1, 3) and angular (N+1, 3) momentum of the discrete momenta p_n."""
    L = np.array(mech.linear_momentum.map(traj.p.shape[0])(traj.p.T)).T
    J = np.array(mech.angular_momentum.map(traj.p.shape[0])(traj.q.T, traj.p.T)).T
    return L, J


def momentum_scales(traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """(N+1,) sums of the magnitudes of the terms that make up L and J: the size that
    round-off in the momenta is relative to (L itself may be zero)."""
    n, k = traj.q.shape
    q = traj.q.reshape(n, k // 3, 3)
    p = traj.p.reshape(n, k // 3, 3)
    scale_L = np.linalg.norm(p[:, 0::4], axis=2).sum(axis=1)
    scale_J = np.linalg.norm(np.cross(q, p), axis=2).sum(axis=1)
    return scale_L, scale_J


def run_free_motion(scene: Scene, *, steps: int, dt: float, gravity: bool = True,
                    torques: str = "zero", seed: int = 0,
                    pin: str | None = None) -> tuple[Trajectory, FreeMotionReport]:
    """Simulate `steps` steps of size `dt` (s) and measure the structure-preservation errors.

    torques: "zero" (passive) or "random" (`random_torques`). pin: a contact name of the
    scene held at its initial position (its multipliers are in the trajectory), or None.
    Without gravity and pin the (conserved components of the) linear and angular momentum
    must be conserved to round-off; the energy error of a passive run must stay bounded.
    """
    if torques not in ("zero", "random"):
        raise ValueError(f"torques must be 'zero' or 'random', got {torques!r}")
    if steps < 1 or not np.isfinite(dt) or dt <= 0:
        raise ValueError(f"need steps >= 1 and a finite dt > 0, got steps={steps}, dt={dt}")
    contacts = [c.name for c in scene.contacts]
    if pin is not None and pin not in contacts:
        raise ValueError(f"scene {scene.name!r} has no contact {pin!r} (it has: "
                         f"{', '.join(contacts) or 'none'})")
    scene = dataclasses.replace(scene, gravity=scene.gravity if gravity else 0.0)
    mb = Multibody(scene)
    mech = DiscreteMechanics(mb)
    sim = Simulator(mech, contacts=(pin,) if pin else ())
    rng = np.random.default_rng(seed)
    q0 = configuration(scene)
    nu0 = random_velocity(mb, q0, rng)
    if pin:
        nu0 = pinned_velocity(mb, q0, nu0, pin)
    tau = random_torques(mb, rng) if torques == "random" else None
    start = time.perf_counter()
    traj = sim.run(q0, nu0, np.full(steps, dt), tau)
    wall = time.perf_counter() - start
    T, E = energies(mech, traj)
    L, J = momenta(mech, traj)
    lin, ang = conserved_components(mb)
    L, J = L[:, lin], J[:, ang]
    scale_L, scale_J = momentum_scales(traj)
    g = np.array(mb.constraints.map(steps + 1)(traj.q.T))
    report = FreeMotionReport(
        steps=steps, dt=dt, gravity=gravity, torques=torques, seed=seed,
        energy_error_max=float(np.abs(E - E[0]).max() / T.max()),
        linear_momentum_error_max=float(np.linalg.norm(L - L[0], axis=1).max()),
        angular_momentum_error_max=float(np.linalg.norm(J - J[0], axis=1).max()),
        linear_momentum_scale=float(scale_L.max()),
        angular_momentum_scale=float(scale_J.max()),
        constraint_violation_max=float(np.abs(g).max()),
        newton_iterations_mean=float(traj.newton_iterations.mean()),
        wall_time_s=wall,
    )
    return traj, report
