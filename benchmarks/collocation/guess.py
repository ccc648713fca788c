"""The collocation's initial guesses: the product's kinematic guess, in minimal coordinates.

`gait_planner.ocp.guess.kinematic_guess` fits a stepping motion at the DMOCC nodes of the
settings' grid; it reads only the grid's layout (mb, N, contacts per phase,
phase_of_interval), which `DmoccGrid` provides without building the DMOCC problem. Its
configurations are turned into theta (`MinimalModel.coordinates`) and interpolated
linearly in time onto the knots (all sigma at the upper bound, where the product starts
too). The rest of the state has two mappings (`initial_guess`, kinematics=):

* "linear": w differentiated on the DMOCC nodes, theta_mid and w_mid interpolated
  linearly, a = 0;
* "spline": theta, w and a at the knots and midpoints of one cubic spline through the
  knots 0..K (knot K the mirror image of knot 0; the spline continued over three mirrored
  knots at either end). A cubic meets every Hermite-Simpson defect exactly, so this guess
  starts on the collocation's own kinematics.

Torques, velocity corrections and impulses start at zero, w before an impact at the w of
the knot; contact forces at the product's weight share (`ocp.guess.initial_multipliers`).

Why two (2026-11-23, relaxed first stage, inertia-free IPOPT as `collocation.solve`): the
kinematic guess of walker3d bends the right knee backwards and the left one forwards, so
knot K, the mirror image of knot 0, is 100 deg away in both knees from knot K-1. From
"linear" the last interval's defects were off by up to 12 and the held contact velocities
by up to 10 m/s; IPOPT's steps were 1e3-1e4 (scaled, mostly accelerations) at step sizes
of 1e-2-1e-3, and the stage had not converged after 1000 iterations (4 intervals per
phase). From "spline" it converged in 245 + 114 iterations (4 per phase) and 338 + 27 (8).
walker2d the other way round: from "linear" 74 + 20 iterations (8 per phase); from
"spline", whose second derivative at the kinks of the kinematic guess (root at rest in
double support, then moving) put 12.5 kN into a dynamics row, the stage cycled between two
iterates (friction cone violated by 83 and 330 N, full steps) until 500 iterations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from benchmarks.collocation.transcription import ACCELERATION_SCALE, CollocationTranscription
from gait_planner.model.multibody import Multibody
from gait_planner.model.ground import LEVEL, Ground
from gait_planner.ocp.contacts import BodyContact, body_contacts
from gait_planner.ocp.guess import initial_multipliers, kinematic_guess


@dataclass(frozen=True)
class DmoccGrid:
    """The node layout of the product's transcription for the same settings (what
    `kinematic_guess` and `initial_multipliers` read): N intervals, the phase of each,
    the contacts of each phase, and the nodes that carry contact forces."""

    mb: Multibody
    N: int
    phase_of_interval: np.ndarray
    contacts: list[tuple[BodyContact, ...]]
    lam_nodes: range
    ground: Ground = LEVEL  # the baseline plans on level ground only


def initial_guess(tr: CollocationTranscription, step: float,
                  kinematics: str = "linear") -> np.ndarray:
    """x0 (scaled unknowns, `CollocationTranscription.variables` order); kinematics
    "linear" or "spline" (module docstring)."""
    if kinematics not in ("linear", "spline"):
        raise ValueError(f"kinematics must be 'linear' or 'spline', got {kinematics!r}")
    model, mb, s, mesh = tr.model, tr.mb, tr.settings, tr.mesh
    phases = mb.scene.gait.phases
    contacts = [body_contacts(mb, p.contacts) for p in phases]
    N = int(sum(s.intervals))
    grid = DmoccGrid(mb, N, np.repeat(np.arange(len(phases)), s.intervals), contacts,
                     range(1, N))
    sigma = s.scaling_bounds[1]
    q_nodes = kinematic_guess(grid, step)[:N]  # nodes 0..N-1: the half cycle
    t_nodes = s.base_time_step * sigma * np.arange(N)
    theta_nodes = np.unwrap(model.coordinates(q_nodes), axis=0)
    w_nodes = np.gradient(theta_nodes, t_nodes, axis=0)
    h = np.concatenate([[s.base_time_step * sigma * mesh.base_steps[c] / mesh.intervals[c]]
                        * mesh.intervals[c] for c in range(len(mesh.phases))])
    t_knots = np.concatenate([[0.0], np.cumsum(h)])
    K, T = tr.K, t_knots[-1]

    def at(values, t):  # (len(t), n) linear interpolation in time
        return np.array([np.interp(t, t_nodes, values[:, i]) for i in range(values.shape[1])]).T

    theta_knots = at(theta_nodes, t_knots[:-1])  # (K, n)
    if kinematics == "spline":
        def mirror(theta, shift):
            return np.array(model.mirror(theta, shift)).ravel()

        ends = min(3, K)  # mirrored knots beyond either end of the half cycle
        before = [mirror(theta_knots[K - j], -step) for j in range(ends, 0, -1)]
        after = [mirror(theta_knots[j], step) for j in range(ends + 1)]  # j = 0: knot K
        spline = CubicSpline(np.concatenate([t_knots[K - ends : K] - T, t_knots[:-1],
                                             t_knots[: ends + 1] + T]),
                             np.vstack(before + [theta_knots] + after))

    weights = initial_multipliers(DmoccGrid(mb, len(phases), np.arange(len(phases)), contacts,
                                            range(len(phases))))
    share, offset = {}, 0
    for k, cs in enumerate(contacts):
        size = sum(bc.n_multipliers for bc in cs)
        share[k], offset = weights[offset : offset + size], offset + size

    x0 = np.zeros(tr.x.shape[0])
    V = tr.variables

    def put(name, values):  # values (rows, cols) -> the block's column-major entries
        x0[V.index(name)] = np.asarray(values, float).ravel(order="F")

    def velocity(t):  # (len(t), n)
        return spline(t, 1) if kinematics == "spline" else at(w_nodes, t)

    put("sigma", np.full(mb.scene.gait.n_scalings, sigma))
    put("theta", theta_knots.T)
    put("w", velocity(t_knots[:-1]).T)
    for j in tr.w_minus:
        put(f"w_minus{j}", velocity(t_knots[j : j + 1]).T)
    for c, k in enumerate(mesh.phases):
        name, start, m = phases[k].name, mesh.starts[c], mesh.intervals[c]
        knots = t_knots[start : start + m + 1]
        mid = 0.5 * (knots[:-1] + knots[1:])
        put(f"theta_mid[{name}]", (spline(mid) if kinematics == "spline"
                                   else at(theta_nodes, mid)).T)
        put(f"w_mid[{name}]", velocity(mid).T)
        if kinematics == "spline":
            put(f"a[{name}]", spline(knots, 2).T / ACCELERATION_SCALE)
            put(f"a_mid[{name}]", spline(mid, 2).T / ACCELERATION_SCALE)
        put(f"lambda[{name}]", np.tile(share[k][:, None], (1, m + 1)))
        put(f"lambda_mid[{name}]", np.tile(share[k][:, None], (1, m)))
    return x0
