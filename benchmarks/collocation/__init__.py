"""Baseline for the speed-against-error comparison (issue #10): the same gait optimal
control problem as `gait_planner.ocp`, transcribed by Hermite-Simpson direct collocation in
minimal coordinates, the method of bioptim, OpenSim Moco or Drake users.

`plan_collocation(scene, settings, intervals_per_phase=None, progress=None)` returns the
product's `PlanResult`; `MinimalModel` is the minimal-coordinate model (q(theta), equations
of motion, impact map, mirror), `CollocationTranscription` the NLP. With settings.solve.compiled
its derivatives come from per-point elements compiled to C (`collocation.elements`,
through the product's `ocp.derivatives` and `ocp.compile`), otherwise from CasADi's
differentiation of the whole expanded graph (`collocation.solve`).
"""

from benchmarks.collocation.minimal import MinimalModel
from benchmarks.collocation.rnea import SpatialModel
from benchmarks.collocation.solve import plan_collocation, problem_size
from benchmarks.collocation.transcription import CollocationTranscription

__all__ = ["MinimalModel", "SpatialModel", "CollocationTranscription", "plan_collocation",
           "problem_size"]
