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

The fine start follows the coarse plan in time (`coarse_times`: fine node n at coarse time
n / factor, the last phase compressed so that both grids' node N - 1 is the image of
node 0). A fine node at coarse time m + t (0 <= t < 1) has coarse node m as its reference
configuration (`Transcription.Qref`, which must satisfy every holonomic constraint) and
the increment u = t times the increment from node m to node m + 1 (`_increments`); node
torques are interpolated linearly in time, contact multipliers linearly between the
coarse nodes of the same phase, an impact node's scaled by the factor (`_multipliers`),
the phase scalings sigma kept. Until 2026-11-27 the start stood at node m (u = 0) and put
the last free node on the image of node 0 twice: 7.8 kN of residual in walker3d's dynamics
rows, and refinements of walker3d's 0.9 m step took ~190 iterations where they now take
50-60 (benchmarks/HISTORY.md).
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from gait_planner.memory import PEAK_PER_KEPT
from gait_planner.ocp.warm_starts import StoredPlan
from gait_planner.ocp.settings import GaitSettings
from gait_planner.ocp.transcription import TORQUE_SCALE, Transcription

FACTOR = 2  # intervals per coarse interval


def refined_memory(kept: int, factor: int = FACTOR) -> int:
    """Bytes the build of a grid `factor` times finer is expected to take at its peak, from
    `kept`, the bytes its coarse problem kept (`ocp.solve.Planner.memory_kept`): the
    problem's memory grows with its intervals (Unitree G1 on 40 and 80 intervals: 3.64 and
    6.99 GB) and a build peaks at `memory.PEAK_PER_KEPT` times what it keeps."""
    return int(factor * kept * PEAK_PER_KEPT)


def refined_settings(s: GaitSettings, factor: int = FACTOR) -> GaitSettings:
    """The settings of the same half cycle on a grid `factor` times finer (the base time
    step divided, every phase's intervals multiplied)."""
    return dataclasses.replace(s, base_time_step=s.base_time_step / factor,
                               intervals=tuple(factor * i for i in s.intervals))


def refined_start(coarse: Transcription, plan: StoredPlan, fine: Transcription,
                  settings: GaitSettings) -> tuple[np.ndarray, np.ndarray]:
    """(x0 (nx_fine,), qref (N_fine - 1, k)): a start on `fine` from an optimum `plan` of
    `coarse` (its x and reference configurations) for the request `settings`.

    Raises ValueError unless `fine` is `coarse`'s grid refined by a whole factor."""
    factor = fine.N // coarse.N
    if factor < 2 or fine.N != factor * coarse.N or \
            not np.array_equal(np.repeat(coarse.phase_of_interval, factor), fine.phase_of_interval):
        raise ValueError(f"a grid of {fine.N} intervals is not a refinement of {coarse.N}")
    x = plan.x
    p = coarse.parameters(plan.qref, settings)
    Q, TAU = (np.array(v) for v in ca.Function("q_tau", [coarse.x, coarse.p],
                                               [coarse.Q, coarse.TAU])(x, p))
    times = coarse_times(coarse, fine)
    m = np.floor(times).astype(int)  # below N - 1: the last free node lies before the image
    t = times - m
    qref_fine = Q[:, m].T
    tau = (1 - t) * TAU[:, m] + t * TAU[:, m + 1]
    u = _increments(coarse, Q, m, t)
    parts = _multipliers(coarse, fine, coarse.node_multipliers(x), factor, times)
    sigma = x[-int(coarse.S.shape[0]):]
    x0 = np.concatenate([u.reshape(-1), (tau / TORQUE_SCALE).T.reshape(-1), *parts, sigma])
    return x0, qref_fine


def coarse_times(coarse: Transcription, fine: Transcription) -> np.ndarray:
    """(N_fine - 1,) the time of each free fine node in coarse intervals. Node N - 1 is the
    mirror image of node 0 on both grids, so the half cycle is N - 1 intervals: 2 N_c - 1
    fine intervals are N_c - 1/2 coarse ones, and the last phase (whose final interval is
    the image of the first) is one fine interval longer than twice its coarse length.
    Every phase but the last maps fine node n to n / factor; the last is compressed so
    that its free nodes end at the coarse image of node 0. (Mapping n to n / factor there
    put fine node N - 2 on the image of node 0 and node N - 1 on it again: one interval
    standing still, a residual of 7.8 kN in walker3d's dynamics rows.)"""
    factor = fine.N // coarse.N
    n = np.arange(fine.N - 1, dtype=float)
    last = first_interval(coarse, coarse.phase_of_interval[-1])
    squeeze = (coarse.N - 1 - last) / (fine.N - 1 - factor * last)
    return np.where(n <= factor * last, n / factor, last + (n - factor * last) * squeeze)


def first_interval(tr: Transcription, phase: int) -> int:
    """The first interval (and node) of `phase` on the grid of `tr`."""
    return int(np.argmax(tr.phase_of_interval == phase))


def _increments(coarse: Transcription, Q: np.ndarray, m: np.ndarray, t: np.ndarray
                ) -> np.ndarray:
    """u (len(m), ndof) of the fine nodes at fraction t of coarse interval m, about coarse
    node m (Q (k, N + 1) the coarse nodes): t times the increment from node m to node m + 1
    (`Multibody.increment`: the root's displacement and every joint's turn). A start that
    stood at node m for the whole coarse interval (u = 0) left 16 kN in walker3d's dynamics
    rows; this one leaves under 1 kN, most rows under 100 N. (Catmull-Rom in the
    increments left less still, but overshot the joint speed limits and walker3d's
    0.15 m stairs up then failed to refine; 2026-11-27.)"""
    steps = np.array([coarse.mb.increment(Q[:, j], Q[:, j + 1]) for j in range(coarse.N)])
    return steps[m] * t[:, None]


def _multipliers(coarse: Transcription, fine: Transcription, coarse_lam: dict,
                 factor: int, times: np.ndarray) -> list[np.ndarray]:
    """The fine nodes' contact multipliers (forces, scaled as in x): linear in time between
    the coarse nodes of the same phase; a node that establishes a contact (an impact: the
    first node of a phase holding a point the phase before did not) carries the impulse
    over its weight w_n, which is `factor` times smaller on the fine grid, so its multiplier
    is `factor` times the coarse one's and the nodes after it interpolate from the next
    coarse node on."""
    phases = coarse.mb.scene.gait.phases
    impact = {k for k in range(1, len(phases))
              if set(phases[k].contacts) - set(phases[k - 1].contacts)}
    first = {k: first_interval(coarse, k) for k in impact}
    parts = []
    for n, size in zip(fine.lam_nodes, fine.lam_sizes):  # a phase's nodes share a layout
        phase = fine.phase_of_interval[n]
        if phase in impact and n == factor * first[phase]:
            parts.append(factor * coarse_lam[first[phase]])
            continue
        same = [j for j in coarse.lam_nodes if coarse.phase_of_interval[j] == phase
                and not (phase in impact and j == first[phase])]
        if not same:
            parts.append(np.zeros(size))
            continue
        lam = np.array([coarse_lam[j] for j in same])
        t = times[n] if n < times.size else coarse.N - 1
        parts.append(np.array([np.interp(t, same, lam[:, i]) for i in range(size)]))
    return parts
