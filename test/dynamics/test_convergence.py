"""Order of convergence of the variational integrator (diffrax `test_ode_order` style).

The configuration at t = 0.2 s with steps h, h/2, h/4, h/8 (h = 0.02 s) is compared with a
reference run at h/64; the slope of log(error) against log(step) must be 2 (1.8 < slope <
2.3), for a free-flying walker3d with gravity (passive and with joint torques) and for a
compass held at its foot (with the contact multiplier as an unknown).
"""

from __future__ import annotations

import numpy as np
import pytest

from gait_planner.dynamics.free_motion import pinned_velocity, random_torques, random_velocity
from gait_planner.dynamics.forward import Simulator
from gait_planner.model.angles import configuration

HORIZON, H0 = 0.2, 0.02


@pytest.mark.parametrize(
    "scene, pin, torques",
    [("walker3d", None, False), ("walker3d", None, True), ("compass", "foot_r", False)],
)
def test_second_order_convergence(model, scene, pin, torques):
    m = model(scene)
    sim = Simulator(m.mech, contacts=(pin,) if pin else ())
    rng = np.random.default_rng(5)
    q0 = configuration(m.scene)
    nu0 = 2.0 * random_velocity(m.mb, q0, rng)
    if pin:
        nu0 = pinned_velocity(m.mb, q0, nu0, pin)
    tau = random_torques(m.mb, rng) if torques else None

    def final(h):
        return sim.run(q0, nu0, np.full(int(round(HORIZON / h)), h), tau).q[-1]

    reference = final(H0 / 64)
    steps = H0 / 2.0 ** np.arange(4)
    errors = np.array([np.abs(final(h) - reference).max() for h in steps])
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 1.8 < slope < 2.3, (slope, errors)
    assert errors[0] < 0.05  # the coarsest step is still in the asymptotic range
