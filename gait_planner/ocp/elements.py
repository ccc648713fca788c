"""The NLP's elements: parts of g and of the cost that are one Function of one node's or
one interval's unknowns, and where those unknowns sit in x and p (`Layout`).

x = (vec U, vec T, L, sigma): U (ndof, N-1) the nodal reparametrisations u_n of the free
nodes 0..N-2, T (nt, N-1) their scaled torques, L the scaled contact multipliers of nodes
1..N-1 (`lam_sizes` each), sigma the phase scalings. p = (vec Qref, step length, mu, the
ground's parameters (`gait_planner.model.ground.PARAMETERS`), 1 / speed (0: free)): the
request's values are parameters of one compiled problem, not constants of its code.
Nodes N-1 and N are mirror images of nodes 0 and 1 (`Transcription`); where the mirror
commutes with the reparametrisation their elements read mirror images of x and p appended
to them (`Layout.images`, `Layout.element_inputs`) and so are the regular elements, which
join the regular nodes' vector passes (`ocp.derivatives`); otherwise (the compass) they are
variants of their own that mirror the configuration they compute (`Layout.mirrored`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from gait_planner.model.ground import PARAMETERS, parametric_rise
from gait_planner.model.multibody import Multibody


@dataclass(frozen=True)
class ElementGroup:
    """Constraint rows (or cost terms) that are one SX Function of a few entries of x and
    p, evaluated at several nodes: g[rows[:, j]] += function(xe[z_index[:, j]],
    pe[p_index[:, j]], constants), or, with rows None, cost += function(...), where
    (xe, pe) = `Layout.element_inputs(x, p)`: x and p followed by the mirror images
    that the nodes N-1 and N read (`Layout.images`). Settings
    enter as `constants` (an input, not folded in), so one compiled function serves them
    all."""

    function: ca.Function  # (z (nz,), pz (np,), c (nc,)) -> r (nr,)
    z_index: np.ndarray  # (nz, n) int
    p_index: np.ndarray  # (np, n) int
    rows: np.ndarray | None  # (nr, n) int; None: a term of the cost
    constants: np.ndarray  # (nc,) c: the base time step (s), then settings values


class Layout:
    """Indices of each node's and interval's unknowns in x and parameters in p, and the
    element Functions of one node or interval.

    mb: the multibody; N: intervals; lam_sizes: contact multipliers of nodes 1..N-1;
    n_scalings: entries of sigma; scaling_of_interval (N,): the entry each interval's time
    step scales with;
    A, along, up, B, M: the configuration mirror and its position masks
    (`ocp.mirror.mirror_parts`), the torque and increment mirrors (`ocp.mirror`; M None
    where the increments have no mirror image); transition: the ends are given, not
    mirror images (`ocp.transition`): every node 0..N has unknowns of its own, the
    contact multipliers are those of nodes 0..N-1, the torques those of nodes 0..N-1 (rest:
    a transition that stops, nodes N-1 and N are node N-2, `source`), and
    p ends with the start's momentum (k,), the last interval's scaling and the gait's
    torques at nodes 0..N ((N + 1) nt,), `ocp.cost_terms`."""

    def __init__(self, mb: Multibody, N: int, lam_sizes: list[int], n_scalings: int,
                 scaling_of_interval: np.ndarray, A: np.ndarray, along: np.ndarray,
                 up: np.ndarray, B: np.ndarray, M: np.ndarray | None,
                 transition: bool = False, rest: bool = False):
        self.mb, self.N, self.lam_sizes = mb, N, list(lam_sizes)
        self.scaling_of_interval = scaling_of_interval
        self.A, self.along, self.up, self.B, self.M = A, along, up, B, M
        self.transition, self.rest = transition, rest
        # nodes with unknowns of their own; a transition that ends at rest: 0..N-2, nodes
        # N-1 and N being node N-2
        self.free = N + 1 if transition and not rest else N - 1
        self.first_lam_node = 0 if transition else 1
        self.n_u, self.n_tau = mb.ndof * self.free, mb.nt * (N if transition else N - 1)
        self.n_lam = int(sum(self.lam_sizes))
        self.nx = self.n_u + self.n_tau + self.n_lam + n_scalings
        self.step_index = mb.k * self.free  # of the step length in p; mu follows it
        self.mu_index = self.step_index + 1
        self.ground_index = self.step_index + 2 + np.arange(len(PARAMETERS))
        self.inverse_speed_index = int(self.ground_index[-1]) + 1
        self.np = self.inverse_speed_index + 1
        if transition:  # the start's momentum (k,), the last interval's scaling, tau_N
            self.np += mb.k + 1 + (N + 1) * mb.nt

    # ---- indices ------------------------------------------------------------------------

    @property
    def imaged(self) -> bool:
        """Whether nodes N-1 and N are the mirror images of nodes 0 and 1 read from
        images of x and p (`images`)."""
        return self.M is not None and not self.transition

    def source(self, m: int) -> int:
        """The free node (or interval) whose unknowns give node m (or interval m): itself, or
        for the mirror images N-1 and N (interval N-1) of a periodic half cycle, node 0 and
        1 (interval 0)."""
        if self.transition:
            return min(m, self.N - 2) if self.rest else m
        return m - (self.N - 1) if m >= self.N - 1 else m

    def u_index(self, node: int) -> np.ndarray:
        """Indices into (x, its images) of node `node`'s u: its own, or for N-1 and N the
        images of u_0 and u_1 (`images`), or without images u_0 and u_1 themselves."""
        nd = self.mb.ndof
        if node >= self.N - 1 and self.imaged:
            return self.nx + (node - (self.N - 1)) * nd + np.arange(nd)
        return np.arange(nd) + self.source(node) * nd

    def lam_index(self, node: int) -> np.ndarray:
        """Indices into x of node `node`'s contact multipliers (1 <= node <= N-1; a
        transition's from node 0)."""
        j = node - self.first_lam_node
        start = self.n_u + self.n_tau + sum(self.lam_sizes[:j])
        return np.arange(start, start + self.lam_sizes[j])

    def qref_index(self, node: int) -> np.ndarray:
        """Indices into (p, its images) of node `node`'s reference (see `u_index`)."""
        k = self.mb.k
        if node >= self.N - 1 and self.imaged:
            return self.np + (node - (self.N - 1)) * k + np.arange(k)
        return np.arange(k) + self.source(node) * k

    def node_p_index(self, node: int) -> np.ndarray:
        """Indices into p of a node element's pz (qref_n, step length, ground)."""
        return np.concatenate([self.qref_index(node), [self.step_index], self.ground_index])

    def tau_index(self, node: int) -> np.ndarray:
        """Indices into (x, its images) of node `node`'s torques (see `u_index`; a
        transition's nodes 0..N-1 have their own, at rest too)."""
        nt = self.mb.nt
        if node == self.N - 1 and self.imaged:
            return self.nx + 2 * self.mb.ndof + np.arange(nt)
        return self.n_u + np.arange(nt) + (node if self.transition else self.source(node)) * nt

    def scaling_index(self, interval: int) -> int:
        return self.n_u + self.n_tau + self.n_lam + int(self.scaling_of_interval[interval])

    def interval_z_index(self, n: int) -> np.ndarray:
        """Indices into x of an interval element's z (`interval_element`) at interval n."""
        return np.concatenate([self.u_index(n), self.u_index(n + 1), [self.scaling_index(n)]])

    def interval_p_index(self, n: int) -> np.ndarray:
        """Indices into p of an interval element's pz at interval n."""
        return np.concatenate([self.qref_index(n), self.qref_index(n + 1), [self.step_index],
                               self.ground_index])

    def mirrored(self, image: bool) -> bool:
        """Whether an element of a mirror image node (or interval) is a variant of its own:
        only where its unknowns have no images (`images`); a transition has no images."""
        return image and self.M is None and not self.transition

    # ---- mirror images ------------------------------------------------------------------

    @cached_property
    def images(self) -> dict[str, np.ndarray] | None:
        """The mirror images the elements of nodes N-1 and N read, None if they mirror
        their configurations themselves (`M` None). Images of x: M u_0, M u_1, B T_0,
        entry i being x_sign[i] x[x_source[i]] (signed permutations); images of p: the
        references A qref_0 + s e + c and A qref_1 + s e + c (s the step length, e and c
        the shift and lift of `ocp.mirror.configuration_mirror` from p's ground), entry i
        being p_sign[i] p[p_source[i]] + p_along[i] s + p_up[i] rise(s)."""
        if not self.imaged:
            return None
        nd, k = self.mb.ndof, self.mb.k

        def signed(P: np.ndarray, offset: int):
            j = np.argmax(np.abs(P), axis=1)
            return offset + j, P[np.arange(P.shape[0]), j]

        parts = [signed(self.M, 0), signed(self.M, nd), signed(self.B, self.n_u)]
        refs = [signed(self.A, 0), signed(self.A, k)]
        return {"x_source": np.concatenate([a for a, _ in parts]),
                "x_sign": np.concatenate([b for _, b in parts]),
                "p_source": np.concatenate([a for a, _ in refs]),
                "p_sign": np.concatenate([b for _, b in refs]),
                "p_along": np.tile(self.along, 2), "p_up": np.tile(self.up, 2)}

    def element_inputs(self, x, p):
        """(xe, pe): x and p (numbers or CasADi expressions) followed by their mirror
        images (`images`), the vectors the elements' z_index and p_index point into."""
        im = self.images
        if im is None:
            return x, p
        step = p[self.step_index]
        rise = parametric_rise(p[int(self.ground_index[0]) :], step)
        if isinstance(x, np.ndarray):
            return (np.concatenate([x, im["x_sign"] * x[im["x_source"]]]),
                    np.concatenate([p, im["p_sign"] * p[im["p_source"]] + im["p_along"] * step
                                    + im["p_up"] * rise]))
        return (ca.vertcat(x, ca.DM(im["x_sign"]) * x[im["x_source"].tolist()]),
                ca.vertcat(p, ca.DM(im["p_sign"]) * p[im["p_source"].tolist()]
                           + ca.DM(im["p_along"]) * step + ca.DM(im["p_up"]) * rise))

    def image(self, q, step, ground):
        """The mirror image A q + step e + c of a configuration (SX or MX; `images`) on the
        ground of parameters `ground` (`gait_planner.model.ground.PARAMETERS`)."""
        return (ca.mtimes(ca.DM(self.A), q) + step * ca.DM(self.along)
                + parametric_rise(ground, step) * ca.DM(self.up))

    # ---- element Functions --------------------------------------------------------------

    def node_element(self, fn: ca.Function, mirrored: bool) -> ca.Function:
        """fn(q_n, c[, ground]) of node n as an SX Function of z = u_n, pz = (qref_n, step
        length, ground) and c (node N-1, mirrored, is the image of node 0)."""
        mb, nd, k, G = self.mb, self.mb.ndof, self.mb.k, len(PARAMETERS)
        z, pz = ca.SX.sym("z", nd), ca.SX.sym("pz", k + 1 + G)
        c = ca.SX.sym("c", fn.sparsity_in(1))
        ground = pz[k + 1 :]
        q = mb.reparametrise(z, pz[0:k])
        if mirrored:
            q = self.image(q, pz[k], ground)
        name = f"{fn.name()}_element" + ("_mirrored" if mirrored else "")
        out = fn(q, c, ground) if fn.n_in() == 3 else fn(q, c)
        return ca.Function(name, [z, pz, c], [out], ["z", "pz", "c"], ["r"])

    def interval_element(self, fn: ca.Function, next_mirrored: bool) -> ca.Function:
        """fn(q_n, q_{n+1}, h_n, c[, ground]) of interval n as an SX Function of
        z = (u_n, u_{n+1}, sigma_n), pz = (qref_n, qref_{n+1}, step length, ground) and
        c = (base time step, constants: one for most, one per joint for "joint_speeds")."""
        mb, nd, k, G = self.mb, self.mb.ndof, self.mb.k, len(PARAMETERS)
        z, pz = ca.SX.sym("z", 2 * nd + 1), ca.SX.sym("pz", 2 * k + 1 + G)
        c = ca.SX.sym("c", fn.size1_in(3))
        ground = pz[2 * k + 1 :]
        q0 = mb.reparametrise(z[0:nd], pz[0:k])
        q1 = mb.reparametrise(z[nd : 2 * nd], pz[k : 2 * k])
        if next_mirrored:
            q1 = self.image(q1, pz[2 * k], ground)
        name = f"{fn.name()}_element" + ("_next_mirrored" if next_mirrored else "")
        args = (q0, q1, c[0] * z[2 * nd], c) + ((ground,) if fn.n_in() == 5 else ())
        return ca.Function(name, [z, pz, c], [fn(*args)], ["z", "pz", "c"], ["r"])
