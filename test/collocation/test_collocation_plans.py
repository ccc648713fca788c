"""Plans of `benchmarks.collocation.plan_collocation` (the baseline of issue #10).

compass and walker2d at the scenes' requests, on the DMOCC nodes (intervals_per_phase None):

* IPOPT converges to the product's tolerances; sigma within its bounds; the problem size
  is reported;
* the published plan is a valid recording for the product's checks in what collocation
  shares with DMOCC: every constraint at round-off (q(theta) is exact), contacts held and
  on the ground, mirror periodicity of q, torques and forces, actuation as joint couples,
  forces pushing within their cones;
* every plastic impact leaves the contacts at rest and loses kinetic energy;
* what it does not share is reported, not hidden: the DMOCC's discrete Euler-Lagrange
  residual, the cost the verifier recomputes from the knots (the collocation's J is
  Simpson's rule on the cubic states) and, with intervals_per_phase set, the DMOCC interval
  lengths. Measured, not by construction: the continuous certificate, which differentiates
  the knots as the DMOCC's equations do, fails (walker2d: torque error 104 % of the peak,
  knot torques zigzag; with the full swing clearance one node after each release the
  optimum rang at 560 N m, before `ocp.clearance`'s ramp), and the collocation's own knot
  velocity, which the problem's mean joint speeds do not bound, turns an ankle faster
  than the verifier's 600 deg/s just after a heel strike (625 deg/s). The recording test
  allows exactly these failures.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from benchmarks.collocation import plan_collocation
from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.verify import verify_result

# checks a collocation plan fails (module docstring), as the beginnings of the verifier's
# failure sentences
NOT_SHARED = ("the discrete Euler-Lagrange equation", "metadata cost_value",
              "continuous dynamics", "joint efforts zigzag", "joint ankle_l turns at")


@functools.cache
def _plan(name: str):
    scene = load_scene(name)
    settings = settings_for(scene)
    return scene, settings, plan_collocation(scene, settings)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["compass", "walker2d"])
def test_plan_converges(name):
    _, settings, result = _plan(name)
    assert result.success, result.message
    lo, hi = settings.scaling_bounds
    assert np.all(result.phase_scaling >= lo - 1e-8) and np.all(result.phase_scaling <= hi + 1e-8)
    assert result.stats.max_constraint_violation < 1e-10
    assert result.stats.max_dynamics_residual < 1e-6  # N
    for key in ("variables", "constraints", "jacobian_nonzeros", "hessian_nonzeros"):
        assert int(result.settings[key]) > 0
    assert result.duration == pytest.approx(result.times[-2])
    assert float(result.settings["kinetic_energy"]) > 0


@pytest.mark.slow
@pytest.mark.parametrize("name", ["compass", "walker2d"])
def test_recording_checks(name):
    _, _, result = _plan(name)
    report = verify_result(result)
    failures = [f for f in report.failures if not f.startswith(NOT_SHARED)]
    assert not failures, report.summary()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["compass", "walker2d"])
def test_impacts_stop_the_contacts_and_lose_energy(name):
    _, _, result = _plan(name)
    impacts = [tuple(float(v) for v in entry.split(":"))
               for entry in result.settings["impacts"].split(",")]
    touch_downs = [n for n in range(1, result.n_nodes - 1)
                   if set(result.active_contacts[n]) - set(result.active_contacts[n - 1])]
    assert sorted(int(j) for j, *_ in impacts) == touch_downs
    for _, before, after, speed in impacts:
        assert after < before  # a plastic impact dissipates
        assert speed < 1e-9  # m/s: every contact of the new phase at rest
