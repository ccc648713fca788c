"""The time mesh of the collocated half cycle: phases, their intervals and durations.

The physical problem is the product's (`gait_planner.ocp.transcription`): phase k of the
scene lasts sigma_{s(k)} * base_time_step * n_k with n_k = settings.intervals[k], except the
last phase, whose first DMOCC interval is the mirror image of the first phase's (nodes N-1,
N mirror nodes 0, 1): in the half cycle t_0 .. t_{N-1} it lasts n_k - 1 base steps. A phase
of zero duration there (the compass's one-interval stance_l) is dropped and only its contact
switch at the end of the half cycle remains. The collocation mesh can be finer or coarser
than the DMOCC grid (`intervals_per_phase`) without changing the problem: phase durations
and their bounds stay those of `settings`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gait_planner.model.scene import Scene
from gait_planner.ocp.settings import GaitSettings


@dataclass(frozen=True)
class Mesh:
    """phases: scene phase index of each collocated phase; intervals: its collocation
    intervals; base_steps: its duration in base time steps (times its sigma)."""

    phases: tuple[int, ...]
    intervals: tuple[int, ...]
    base_steps: tuple[int, ...]

    @property
    def K(self) -> int:
        """Number of collocation intervals (knots 0..K; knot K is the image of knot 0)."""
        return int(sum(self.intervals))

    @property
    def starts(self) -> tuple[int, ...]:
        """First knot of each collocated phase."""
        return tuple(int(s) for s in np.cumsum((0,) + self.intervals[:-1]))

    @property
    def phase_of_interval(self) -> np.ndarray:
        """(K,) collocated phase index of each interval."""
        return np.repeat(np.arange(len(self.phases)), self.intervals)


def mesh_of(scene: Scene, settings: GaitSettings, intervals_per_phase: int | None = None) -> Mesh:
    """The mesh of (scene, settings): with intervals_per_phase None the knots are the
    DMOCC nodes 0..N-1 (the last phase gets n_k - 1 intervals), otherwise every
    collocated phase gets intervals_per_phase intervals."""
    last = len(scene.gait.phases) - 1
    steps = [n - (1 if k == last else 0) for k, n in enumerate(settings.intervals)]
    kept = [k for k in range(last + 1) if steps[k] > 0]
    if intervals_per_phase is not None and intervals_per_phase < 1:
        raise ValueError(f"intervals_per_phase must be >= 1, got {intervals_per_phase}")
    return Mesh(tuple(kept),
                tuple(steps[k] if intervals_per_phase is None else int(intervals_per_phase)
                      for k in kept),
                tuple(steps[k] for k in kept))
