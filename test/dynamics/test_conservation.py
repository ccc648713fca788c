"""Structure preservation of the variational integrator (docs/design.md section 3).

* Without gravity and with random internal joint torques, 10^4 steps: the conserved
  components of linear and angular momentum (all for a free root; L_x, L_z, J_y for a
  planar one) stay constant to round-off relative to the size of their terms, and every
  constraint holds to round-off. The torques really act (the energy changes).
* With gravity, free fall: the linear momentum changes by exactly -h m g e_z per step.
* Passive with gravity, bounded motion (a pinned compass = a double pendulum swinging
  chaotically; a walker3d hanging from its right heel): the energy error does not grow
  with the number of steps, and its size is O(h^2).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gait_planner.dynamics.free_motion import (
    energies,
    momenta,
    random_velocity,
    run_free_motion,
)
from gait_planner.dynamics.forward import Simulator
from gait_planner.model.angles import configuration

ROUND_OFF = 1e-10  # momentum errors relative to linear/angular_momentum_scale


def check_momentum_conservation(scene, steps, dt):
    traj, report = run_free_motion(scene, steps=steps, dt=dt, gravity=False,
                                   torques="random", seed=1)
    assert report.linear_momentum_error_max <= ROUND_OFF * report.linear_momentum_scale
    assert report.angular_momentum_error_max <= ROUND_OFF * report.angular_momentum_scale
    assert report.constraint_violation_max <= 1e-12
    assert report.energy_error_max > 1e-3  # the torques do work: not a trivial motion
    assert report.newton_iterations_mean < 5
    return report


@pytest.mark.parametrize("scene", ["compass", "walker2d"])
def test_momentum_conserved_with_internal_torques(model, scene):
    check_momentum_conservation(model(scene).scene, steps=10_000, dt=0.01)


def test_momentum_conserved_walker3d_short(model):
    scene = model("walker3d").scene
    assert not scene.body("torso").is_realisable  # the paper's torso: M is indefinite
    check_momentum_conservation(scene, steps=2_000, dt=0.01)


@pytest.mark.slow
def test_momentum_conserved_walker3d_long(model):
    report = check_momentum_conservation(model("walker3d").scene, steps=10_000, dt=0.01)
    assert report.angular_momentum_error_max > 0.0  # measured, not skipped


def test_linear_momentum_in_free_fall(model):
    m = model("walker3d")
    sim = Simulator(m.mech)
    q0 = configuration(m.scene)
    h, steps = 0.01, 300
    traj = sim.run(q0, random_velocity(m.mb, q0, np.random.default_rng(2)), np.full(steps, h))
    L, _ = momenta(m.mech, traj)
    weight = sum(b.mass for b in m.scene.bodies) * m.scene.gravity
    expected = L[0] - np.outer(traj.times, [0.0, 0.0, weight])
    assert np.abs(L - expected).max() <= ROUND_OFF * weight * traj.times[-1]


def energy_error(m, pin, steps, dt, seed=0, scene=None):
    traj, _ = run_free_motion(scene or m.scene, steps=steps, dt=dt, gravity=True, seed=seed,
                              pin=pin)
    T, E = energies(m.mech, traj)
    return np.abs(E - E[0]) / T.max()


def test_energy_error_bounded_pinned_compass(model):
    """A double pendulum falling from upright and swinging chaotically for 40 s (8000 steps):
    the error in each quarter is no larger than in the first, i.e. no drift."""
    m = model("compass")
    err = energy_error(m, "foot_r", steps=8000, dt=0.005)
    quarters = err.reshape(4, -1).max(axis=1)
    assert quarters.max() <= 2.0 * quarters[0]
    assert err[4000:].max() <= 2.0 * err[:4000].max()
    assert err.max() < 1e-2


def test_energy_error_is_second_order_pinned_compass(model):
    """Same 20 s motion at h and h/2: the largest energy error shrinks by ~4."""
    m = model("compass")
    coarse = energy_error(m, "foot_r", steps=2000, dt=0.01).max()
    fine = energy_error(m, "foot_r", steps=4000, dt=0.005).max()
    assert 3.0 < coarse / fine < 5.5


def hanging(scene):
    """The scene's pose upside down: the walker hangs from its feet."""
    pose = dataclasses.replace(scene.initial_pose, root_angles=(0.0, np.pi, 0.0))
    return dataclasses.replace(scene, initial_pose=pose)


@pytest.mark.slow
def test_energy_error_bounded_hanging_walker3d(model):
    """walker3d hanging from its right heel, random rates, 10^4 steps of 1 ms. The pinned
    foot is a short light link under the whole body's weight: a stiff mode (~100 rad/s,
    more under dynamic load) makes 1 ms the sensible step. Fast episodes raise the error
    briefly; its typical level (median) must not grow."""
    m = model("walker3d")
    err = energy_error(m, "foot_r_heel", steps=10_000, dt=1e-3, scene=hanging(m.scene))
    first, second = err[:5000], err[5000:]
    assert np.median(second) <= 3.0 * np.median(first)
    assert err.max() < 1e-2
