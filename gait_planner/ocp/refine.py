"""Grid refinement: the same half cycle on a grid `factor` times finer, started from a plan
on the coarse grid.

Why: the discrete Euler-Lagrange equations are second-order accurate, so a plan's distance
from the continuous dynamics (`gait_planner.verify.continuous`) grows like (alpha h)^2 with
the joints' angular accelerations alpha. walker3d's torque-squared optimum swings the leg
hard around toe-off (hip and knee at 110-130 rad/s^2, the light ankle at up to 600): on
the default 15 ms intervals it misses the certificate (0.47 % of the peak torque against
0.2 %). The same local minimum on intervals half as long (refined from that plan) passes
it, 0.099 %, with J 1018.46 instead of 1021.28 J s; planned cold on the fine grid IPOPT finds
another minimum (J 1336, 0.34 %). Measured 2026-11-23 (benchmarks/HISTORY.md, "Grid refinement").

The fine start keeps the coarse plan where the grids share nodes: fine node n sits at
coarse node n / factor; its reference configuration (`Transcription.Qref`, which must
satisfy every holonomic constraint) is coarse node floor(n / factor) and its increment u
is zero; node torques are interpolated linearly in time, contact multipliers taken from the
nearest coarse node of the same phase, the phase scalings sigma kept.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from gait_planner.ocp.library import StoredPlan
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.transcription import TORQUE_SCALE, Transcription

FACTOR = 2  # intervals per coarse interval


def refined_settings(s: GaitSettings, factor: int = FACTOR) -> GaitSettings:
    """The settings of the same half cycle on a grid `factor` times finer (the base time
    step divided, every phase's intervals multiplied)."""
    return dataclasses.replace(s, base_time_step=s.base_time_step / factor,
                               intervals=tuple(factor * i for i in s.intervals))


def refined_start(coarse: Transcription, plan: StoredPlan,
                  fine: Transcription) -> tuple[np.ndarray, np.ndarray]:
    """(x0 (nx_fine,), qref (N_fine - 1, k)): a start on `fine` from an optimum `plan` of
    `coarse` (its x and reference configurations).

    Raises ValueError unless `fine` is `coarse`'s grid refined by a whole factor."""
    factor = fine.N // coarse.N
    if factor < 2 or fine.N != factor * coarse.N or \
            not np.array_equal(np.repeat(coarse.phase_of_interval, factor), fine.phase_of_interval):
        raise ValueError(f"a grid of {fine.N} intervals is not a refinement of {coarse.N}")
    x = plan.x
    p = np.concatenate([plan.qref.reshape(-1), [plan.step, plan.mu]])
    Q, TAU = (np.array(v) for v in ca.Function("q_tau", [coarse.x, coarse.p],
                                               [coarse.Q, coarse.TAU])(x, p))
    m, r = np.divmod(np.arange(fine.N - 1), factor)  # fine node -> coarse node, remainder
    qref_fine = Q[:, m].T
    w = (r / factor)[None, :]
    tau = (1 - w) * TAU[:, m] + w * TAU[:, m + 1]
    coarse_lam = coarse.node_multipliers(x)
    parts = []
    for n, size in zip(fine.lam_nodes, fine.lam_sizes):  # a phase's nodes share a layout
        phase, nearest = fine.phase_of_interval[n], round(n / factor)
        same = [j for j in coarse.lam_nodes if coarse.phase_of_interval[j] == phase]
        parts.append(coarse_lam[min(same, key=lambda j: abs(j - nearest))] if same
                     else np.zeros(size))
    sigma = x[-int(coarse.S.shape[0]):]
    x0 = np.concatenate([np.zeros(fine.U.numel()), (tau / TORQUE_SCALE).T.reshape(-1),
                         *parts, sigma])
    return x0, qref_fine
