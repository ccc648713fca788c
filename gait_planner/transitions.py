"""Planning a transition: from a given start state onto the request's periodic gait
(`ocp.transition`), then as many of the gait's half cycles as the request's steps ask, as
one motion, certified against the continuous dynamics like every plan.

The gait is planned (or found in the planner's store) first, with `strategies.
plan_certified`; the transition is then solved on the gait's grid, starting from the gait
itself: its inner nodes, torques and phase durations, the start at node 0 and the gait's
next half cycle at nodes N-1 and N. From the gait's own first state that start is the
optimum (`start_of_plan`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from gait_planner.model.scene import Scene
from gait_planner.ocp.guess import initial_multipliers
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.solution import failed_result
from gait_planner.ocp.solve import Clock, Planner, Start
from gait_planner.ocp.transcription import TORQUE_SCALE, Transcription
from gait_planner.ocp.transition import (StartState, check_start, join, join_targets,
                                         stance_offset, transition_settings)
from gait_planner.ocp.walk_on import walk_on
from gait_planner.result import PlanResult
from gait_planner.strategies import COLD_ATTEMPTS, WARM_ATTEMPTS, plan_certified

VARIANTS = ("warm", "cold", "cold_inertia")  # the IPOPT instances a transition may use


def transition_start(tr: Transcription, gait: PlanResult, start: StartState,
                     targets: np.ndarray, end_scaling: float) -> Start:
    """The transition's first iterate: every node at its reference (u = 0), the references
    the start, the gait's inner nodes 1..N-2 and the targets; the gait's node torques and
    phase scalings; the contact multipliers of `ocp.guess.initial_multipliers`."""
    N = tr.N
    qref = np.vstack([start.q, gait.q[1 : N - 1], targets])
    x = np.concatenate([np.zeros(tr.U.numel()), gait.tau[:N].ravel() / TORQUE_SCALE,
                        initial_multipliers(tr), gait.phase_scaling, [end_scaling]])
    zeros_g = np.zeros(int(tr.g.shape[0]))
    return Start(x, np.zeros_like(x), zeros_g, qref,
                 f"from {start.origin}, onto the gait's next half cycle")


def plan_transition(planner: Planner, scene: Scene, settings: GaitSettings,
                    start: StartState, *, steps: int = 1, warm_start: bool = True
                    ) -> PlanResult:
    """The transition from `start` onto the gait of (scene, settings), followed by `steps`
    of the gait's half cycles, certified (module docstring). `ocp.transition.StartError`
    if the start cannot be planned from; a failed plan (of the gait or the transition)
    has success False and says which in its message."""
    from gait_planner.verify.certify import certificate_metadata, certified

    check_start(scene, settings, start)
    gait, _ = plan_certified(planner, scene, settings, warm_start=warm_start)
    if not gait.success:
        return dataclasses.replace(gait, message=f"the gait to join: {gait.message}")
    tr_settings = transition_settings(settings, gait, start)
    offset = stance_offset(scene, start, gait)
    planner.stage("building the transition")
    try:
        tr = planner.build(scene, tr_settings, VARIANTS, refinement=True)
    except (ValueError, RuntimeError) as err:
        return failed_result(scene, tr_settings, f"could not build the transition: {err}")
    first = transition_start(tr, gait, start, join_targets(gait, offset),
                             tr_settings.end_scaling)
    clock = Clock.begin(settings.solve.max_solve_time)
    reached = planner.attempt(scene, tr_settings, WARM_ATTEMPTS[0], first, clock)
    origin = first.origin
    for attempt in COLD_ATTEMPTS if not reached.success else ():
        if planner.stopped() or clock.expired():
            break
        origin += f"; the warm attempt stopped ({reached.status}), then cold"
        reached = planner.attempt(scene, tr_settings, attempt, first, clock)
        if reached.success:
            break
    result = planner.result(scene, tr_settings, reached, clock, origin)
    if not result.success:
        return result
    joined, cert = certified(join(result, walk_on(gait, steps + 1), offset))
    return dataclasses.replace(joined, settings={
        **joined.settings, **certificate_metadata(cert),
        "gait_cost_value": repr(gait.cost_value)})
