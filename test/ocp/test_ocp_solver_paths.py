"""Every way the planner can reach a plan returns one that passes the independent checker
(`gait_planner.verify`): cold from the kinematic guess with CasADi's derivatives and with
the compiled elements, a warm re-plan, a warm start from the warm-start store of an earlier
process, and the restart with IPOPT's inertia test after a failed inertia-free attempt.
Each test also checks that the path it names was the one taken (the result's
`initial_guess` says how the plan started). The continuation from the scene's step length
and grid refinement are checked the same way in test_ocp_hard_cases.py and
test_ocp_refine.py."""

from __future__ import annotations

import pytest

from gait_planner.model.loader import load_scene
from gait_planner.ocp import solve
from gait_planner.ocp.warm_starts import WarmStartStore
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import Planner
from gait_planner.strategies import plan_once
from gait_planner.verify import verify_result


@pytest.fixture(scope="module")
def walker2d():
    return load_scene("walker2d")


def _passes(result) -> None:
    assert result.success, result.message
    report = verify_result(result)
    assert report.ok, "\n".join(report.failures)


@pytest.mark.parametrize("compiled", [pytest.param(False, marks=pytest.mark.slow), True],
                         ids=["casadi_derivatives", "compiled"])
def test_cold_and_warm_plans_pass_the_checker(walker2d, compiled):
    planner, settings = Planner(), settings_for(walker2d, compiled=compiled)
    cold = plan_once(planner, walker2d, settings, warm_start=False)
    assert cold.settings["initial_guess"].startswith("kinematic guess")
    assert ("compiled" in cold.settings["derivatives"]) is compiled
    _passes(cold)
    warm = plan_once(planner, walker2d, settings_for(walker2d, compiled=compiled,
                                                     step_length=1.03 * settings.step_length))
    assert warm.settings["initial_guess"].startswith("warm start")
    _passes(warm)


def test_a_warm_start_from_the_warm_start_store_passes_the_checker(walker2d, tmp_path):
    settings = settings_for(walker2d, compiled=True)
    assert plan_once(Planner(library=WarmStartStore(tmp_path)), walker2d, settings).success
    fresh = plan_once(Planner(library=WarmStartStore(tmp_path)), walker2d,
                      settings_for(walker2d, compiled=True, friction_coefficient=0.6))
    assert "(the warm-start store" in fresh.settings["initial_guess"]
    _passes(fresh)


@pytest.mark.slow
def test_the_inertia_test_restart_passes_the_checker(walker2d, monkeypatch):
    monkeypatch.setitem(solve.VARIANTS, "cold", {**solve.VARIANTS["cold"], "ipopt.max_iter": 3})
    result = plan_once(Planner(), walker2d, settings_for(walker2d, compiled=True),
                       warm_start=False)
    assert "restarted with IPOPT's inertia test" in result.settings["initial_guess"]
    _passes(result)
