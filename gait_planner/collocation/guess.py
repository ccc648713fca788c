"""The collocation's initial guess: the product's kinematic guess, in minimal coordinates.

`gait_planner.ocp.guess.kinematic_guess` fits a stepping motion at the DMOCC nodes of the
settings' grid; it reads only the grid's layout (mb, N, contacts per phase,
phase_of_interval), which `DmoccGrid` provides without building the DMOCC problem. Its
configurations are turned into theta (`MinimalModel.coordinates`), interpolated linearly
in time onto the knots and midpoints (all sigma at the upper bound, where the product
starts too), and differentiated for w. Torques, accelerations, velocity corrections and
impulses start at zero; contact forces at the product's weight share
(`ocp.guess.initial_multipliers`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gait_planner.collocation.transcription import CollocationTranscription
from gait_planner.model.multibody import Multibody
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


def initial_guess(tr: CollocationTranscription, step: float) -> np.ndarray:
    """x0 (scaled unknowns, `CollocationTranscription.variables` order)."""
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

    def at(values, t):  # (len(t), n) linear interpolation in time
        return np.array([np.interp(t, t_nodes, values[:, i]) for i in range(values.shape[1])]).T

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

    put("sigma", np.full(mb.scene.gait.n_scalings, sigma))
    put("theta", at(theta_nodes, t_knots[:-1]).T)
    put("w", at(w_nodes, t_knots[:-1]).T)
    for j in tr.w_minus:
        put(f"w_minus{j}", at(w_nodes, t_knots[j : j + 1]).T)
    for c, k in enumerate(mesh.phases):
        name, start, m = phases[k].name, mesh.starts[c], mesh.intervals[c]
        mid = 0.5 * (t_knots[start : start + m] + t_knots[start + 1 : start + m + 1])
        put(f"theta_mid[{name}]", at(theta_nodes, mid).T)
        put(f"w_mid[{name}]", at(w_nodes, mid).T)
        put(f"lambda[{name}]", np.tile(share[k][:, None], (1, m + 1)))
        put(f"lambda_mid[{name}]", np.tile(share[k][:, None], (1, m)))
    return x0
