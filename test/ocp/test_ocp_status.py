"""How a plan ended, as a `PlanStatus` on the result (not read from its message): converged,
failed, or stopped on request; and a result is not changed by the steps after the solve
(the certificate and its metadata make a new one)."""

from __future__ import annotations


from gait_planner.model.loader import load_scene
from gait_planner.ocp.settings import settings_for
from gait_planner.ocp.solve import STOPPED, Planner
from gait_planner.strategies import plan_once
from gait_planner.pipeline import plan_joined
from gait_planner.result import PlanStatus


def test_converged_failed_and_stopped():
    scene = load_scene("compass")
    settings = settings_for(scene)
    converged = plan_once(Planner(), scene, settings, warm_start=False)
    assert converged.success and converged.status is PlanStatus.CONVERGED
    capped = plan_once(Planner(), scene, settings.with_solve(max_iterations=2),
                       warm_start=False)
    assert not capped.success and capped.status is PlanStatus.FAILED
    stopped = plan_once(Planner(stop=lambda: True), scene, settings, warm_start=False)
    assert stopped.status is PlanStatus.STOPPED and stopped.message == STOPPED


def test_the_certificate_makes_a_new_result():
    """plan_joined certifies and notes the certificate in the settings of a new result:
    the one the planner returned keeps its settings (as a library or a warm-start store
    holding it would see them)."""
    scene = load_scene("compass")
    planner = Planner()
    returned = []
    make_result = planner.result

    def recording_result(*args, **kwargs):
        result = make_result(*args, **kwargs)
        returned.append((result, dict(result.settings)))
        return result

    planner.result = recording_result
    joined = plan_joined(planner, scene, settings_for(scene))
    assert "continuous_dynamics" in joined.settings
    assert returned and all(result.settings == before and "continuous_dynamics" not in before
                            for result, before in returned)
