"""Exact first and second derivatives of the gait NLP from per-node elements, compilable.

CasADi differentiates the expanded NLP as one SX graph: walker3d's Lagrangian Hessian is
6.7 M instructions (24 ms per evaluation in CasADi's virtual machine), far too large to
compile (about 200 MB of C). Most of it is the same few formulas at every node. Here the
parts of the NLP that are one formula per node or interval (`Transcription.elements`: the
dynamics rows, their contact terms, friction cones, held contacts' rows, swing clearances,
torso bounds, joint ranges and speeds, the kinetic energy and the twist term) are
differentiated once, as functions of one node's or one interval's unknowns: the Jacobian
and the Hessian of y . r (y the rows' multipliers, or the cost's). These are evaluated at
every node (`Function.map`); CasADi differentiates the rest of the NLP as a whole (the rows
of contacts established at a node, the pinned start, the cost's torque and share terms),
compiled too when the elements are (walker3d: its Hessian 19 000 operations, 0.5 ms in
CasADi's virtual machine; compiled, the cold plan's evaluation 0.47 -> 0.44 s, the same
iterates bit for bit, 2026-11-25).
The sparse matrices are summed from their nonzeros by index lists (`_sum`; entries of an
unknown that an element sees twice, such as a sigma shared by both of its intervals, are
added), in the order of a sum of one matrix per group: IPOPT's iterates depend on
round-off, and another order of the same additions took walker3d's cold solve from 64 to
79 iterations.

The elements are what makes compiling possible: walker3d's dynamics Hessian element is
5 MB of C, built once per machine (`ocp.compile`). A group of LANES nodes or more is
compiled as one vector pass over LANES nodes (`ocp.vectorize`; a last pass is padded with
copies of the group's last node, whose entries are not summed), bit for bit the node by
node results: walker3d's Hessian then takes 10.1 ms and the Jacobian 2.2-3.2 ms per
evaluation, node by node 14.7 and 3.1-4.1, in CasADi's one graph 24 and 6.1 (2-core
machine, 2026-11-23; the paragraph below was measured node by node).
Left in the virtual machine they are slower than CasADi's one graph (44 and 11 ms), which
shares each node's reparametrisation among all rows, so the planner uses them only
compiled. Of the Hessian's time the rest took 3 ms (1 M operations in CasADi's virtual
machine, 45 % of walker3d's Hessian and 2/3 of its Jacobian on 2026-11-24, before the
contact terms, cones, contact rows, clearances and torso bounds became elements: 13 and
5.4-6.2 ms per evaluation then, 7.6-9.1 and 3.1-3.9 ms after, on a slower hour of the VM)
and the summing 0.1 ms (with constant
0/1 matrices and sparse matrix additions 0.8-0.9 ms, and 1.1-1.7 ms of the Jacobian's). The
pieces timed alone, their code and data in the caches, add up to only 9.4 ms, but one
evaluation runs 13 MB of compiled Hessian elements and the rest's 1 M instructions: cold,
the pieces add up to 13.6 ms, 2.8 ms of it the mirrored variants (7.5 MB of code, each run
for one node; 0.3 ms warm), which is why the larger variants were interpreted instead
(`INTERPRETED_ABOVE`; still 2.2 ms of the Hessian and 0.7 ms of the Jacobian on
2026-11-25). The walkers have no such variants now: the mirror image nodes N-1 and N are
the regular elements at mirrored unknowns (`Layout.images`), whose derivatives come
back through a signed permutation (`_entries`), and they ride in the padding lanes of the
vector passes. Mapping over 2 threads (bit for bit the same) measured 1.5 ms
faster in one run and 1.2-4 ms slower in another (the second core is shared with other
jobs), so the maps run serially.

The Functions returned have the signatures of nlpsol's own (options grad_f, jac_g,
hess_lag): grad_f(x, p) -> (f, grad_f_x), jac_g(x, p) -> (g, jac_g_x) and
hess_lag(x, p, lam_f, lam_g) -> triu_hess_gamma_x_x (upper triangle). The values f and g
of grad_f and jac_g are computed only when a caller asks for them (`ValueOnRequest`):
IPOPT never does (it takes f and g from nlp_f and nlp_g), and in CasADi's virtual machine
they cost as much as the whole rest of the gradient and half of the Jacobian's time.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple, Protocol

import casadi as ca
import numpy as np

from gait_planner.ocp.compile import Source
from gait_planner.ocp.elements import ElementGroup
from gait_planner.ocp.vectorize import LANES

# Given the element derivatives to form, returns them (e.g. compiled) in the same order.
Compiler = Callable[[list[Source]], list[ca.Function]]
# Operations above which a one-node element derivative (a mirrored variant of a scene
# without `Layout.images`) is evaluated in CasADi's virtual machine instead of
# compiled. It runs once per evaluation of the NLP's derivatives: its
# machine code (~8 bytes an operation) comes from memory every time, since the vector passes
# and MUMPS have evicted it from the caches, while the virtual machine's loop stays cached
# and streams its instruction list. Measured on the 2-core EPYC (2026-11-24, A/B in fresh
# processes, the same iterates bit for bit): walker3d's six variants above it (97 000 to
# 194 000 operations) interpreted, its cold plan 1.27-1.33 s instead of 1.40-1.48 s; walker2d's
# mirrored dynamics Hessian (74 000) interpreted, 0.31-0.32 s instead of 0.30-0.31 s.
INTERPRETED_ABOVE = 90_000


class ElementNLP(Protocol):
    """What is read here of a transcription (`ocp.transcription.Transcription`, and the
    collocation baseline's `collocation.transcription.CollocationTranscription`): MX x, p,
    cost and g, the cost and g without their elements' parts, the `ElementGroup`s, and a
    layout whose element_inputs(x, p) -> (xe, pe) are the vectors the elements' z_index and
    p_index point into, xe being x followed by images sign * x[source] (plus terms free of x)
    given by layout.images {"x_source", "x_sign"} (None: no images)."""

    x: ca.MX
    p: ca.MX
    cost: ca.MX
    cost_without_elements: ca.MX
    g: ca.MX
    g_without_elements: ca.MX
    elements: list[ElementGroup]
    layout: Any


class ExpandedNLP(NamedTuple):
    """The NLP as SX expressions of SX symbols x (nx,) and p: the cost f and the rows g
    (IPOPT's nlp_f and nlp_g), and their parts that are not elements (f_rest, g_rest)."""

    x: ca.SX
    p: ca.SX
    f: ca.SX
    f_rest: ca.SX
    g: ca.SX
    g_rest: ca.SX


def expand_nlp(tr: ElementNLP) -> ExpandedNLP:
    """The MX graph of the transcription's mapped per-node Functions expanded into one SX
    graph, once for the NLP and its derivatives (walker3d: 0.18 s)."""
    x, p = ca.SX.sym("x", int(tr.x.shape[0])), ca.SX.sym("p", int(tr.p.shape[0]))
    f, f_rest, g, g_rest = ca.Function(
        "fg", [tr.x, tr.p], [tr.cost, tr.cost_without_elements, tr.g, tr.g_without_elements]
    ).expand()(x, p)
    return ExpandedNLP(x, p, f, f_rest, g, g_rest)


def nlp_derivatives(tr: ElementNLP, compiler: Compiler | None = None,
                    expanded: ExpandedNLP | None = None,
                    compile_rest: bool = True) -> dict[str, ca.Function]:
    """{"grad_f", "jac_g", "hess_lag"} of the NLP (tr.x, tr.p, tr.cost, tr.g); expanded:
    `expand_nlp(tr)` if the caller has it; compile_rest: with a compiler, the rest's
    derivatives are compiled too (else they stay in CasADi's virtual machine: the elements
    are the same Functions on every grid, the rest is not: walker3d's refined grids' rest
    took 42 s (80 intervals) and 217 s (160) to compile, and compiled or not a refined
    grid's Hessian and Jacobian took 18-31 ms an evaluation in a noisy A/B, against 4.7 ms
    saved on its own 40 intervals (9.0 against 13.7 ms); 2026-11-28, `ocp.solve.Planner`)."""
    nx, ng = int(tr.x.shape[0]), int(tr.g.shape[0])
    x_sx, p_sx, f, f_rest, g, g_rest = expand_nlp(tr) if expanded is None else expanded
    lam_f_sx, lam_g_sx = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", ng)
    lagrangian = lam_f_sx * f_rest + ca.dot(lam_g_sx, g_rest)
    rest_grad = ca.Function("nlp_rest_grad_f", [x_sx, p_sx], [ca.gradient(f_rest, x_sx)])
    rest_jac = ca.Function("nlp_rest_jac_g", [x_sx, p_sx], [ca.jacobian(g_rest, x_sx)])
    rest_hess = ca.Function("nlp_rest_hess_l", [x_sx, p_sx, lam_f_sx, lam_g_sx],
                            [ca.triu(ca.hessian(lagrangian, x_sx)[0])])

    if compiler is None:
        pairs = [(_element_jacobian(group), _element_hessian(group)) for group in tr.elements]
    else:  # a cached library is loaded, not formed; large one-node derivatives stay in the VM
        rest = [Source.formed(fn) for fn in (rest_grad, rest_jac, rest_hess)] \
            if compile_rest else []
        done = iter(compiler(rest + [s for group in tr.elements
                                     for s in _element_derivatives(group)]))
        if compile_rest:
            rest_grad, rest_jac, rest_hess = next(done), next(done), next(done)
        pairs = [(next(done), next(done)) for _ in tr.elements]

    x, p = ca.MX.sym("x", nx), ca.MX.sym("p", int(tr.p.shape[0]))
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", ng)
    grad, jac, hess = rest_grad(x, p), rest_jac(x, p), rest_hess(x, p, lam_f, lam_g)
    grads, jacs, hessians = [_whole(grad.T)], [_whole(jac)], [_whole(hess)]
    xe, pe = tr.layout.element_inputs(x, p)
    images = tr.layout.images
    source, sign = np.arange(nx), np.ones(nx)  # of each entry of xe: xe[i] = sign x[source]
    if images is not None:
        source = np.concatenate([source, images["x_source"]])
        sign = np.concatenate([sign, images["x_sign"]])
    for group, (jac_fn, hess_fn) in zip(tr.elements, pairs):
        n = group.z_index.shape[1]
        lanes = jac_fn.size2_in(0)  # nodes per call: 1, or LANES (_element_derivatives)
        calls = -(-n // lanes)
        z = xe[_padded(group.z_index, calls * lanes)]
        pz = pe[_padded(group.p_index, calls * lanes)]
        c = ca.DM(group.constants)
        z_source, z_sign = source[group.z_index], sign[group.z_index]
        if group.rows is None:  # a cost term
            y = ca.repmat(lam_f, 1, calls * lanes)
            grads.append(_entries(jac_fn.map(calls)(z, pz, c), np.zeros((1, n), dtype=int),
                                  z_source, _block(jac_fn), col_sign=z_sign))
        else:
            y = lam_g[_padded(group.rows, calls * lanes)]
            jacs.append(_entries(jac_fn.map(calls)(z, pz, c), group.rows, z_source,
                                 _block(jac_fn), col_sign=z_sign))
        hessians.append(_entries(hess_fn.map(calls)(z, pz, c, y), z_source, z_source,
                                 _block(hess_fn), z_sign, z_sign))
    return {
        "grad_f": ValueOnRequest(
            "nlp_grad_f", ca.Function("nlp_f_value", [x_sx, p_sx], [f]),
            ca.Function("nlp_grad_f_only", [x, p], [_sum(grads, (1, nx)).T]), "f", "grad_f_x"),
        "jac_g": ValueOnRequest(
            "nlp_jac_g", ca.Function("nlp_g_value", [x_sx, p_sx], [g]),
            ca.Function("nlp_jac_g_only", [x, p], [_sum(jacs, (ng, nx))]), "g", "jac_g_x"),
        "hess_lag": ca.Function("nlp_hess_l", [x, p, lam_f, lam_g],
                                [_sum(hessians, (nx, nx), upper=True)],
                                ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]),
    }


class ValueOnRequest(ca.Callback):
    """nlpsol's (x, p) -> (value, derivative) signature (grad_f: f and its gradient; jac_g:
    g and its Jacobian) from two Functions of (x, p), each evaluated only when its output
    is asked for. IPOPT asks for the derivative alone (CasADi passes it a null value
    output) and evaluates f and g through nlp_f and nlp_g, so the value, a pass over the
    whole NLP in CasADi's virtual machine (walker3d: g 1.1 ms, f 0.5 ms, 2026-11-25), is
    not computed once or twice an iteration for nothing. Other callers get both outputs,
    the same numbers as before, bit for bit. Evaluated in place through CasADi's buffer
    interface (a few microseconds a call from Python); each call binds its own buffers, so
    calls from several threads do not share state."""

    def __init__(self, name: str, value: ca.Function, derivative: ca.Function,
                 value_name: str, derivative_name: str):
        ca.Callback.__init__(self)
        self.parts = (value, derivative)
        self.names = (value_name, derivative_name)
        self.construct(name, {})

    def get_n_in(self):
        return 2

    def get_n_out(self):
        return 2

    def get_name_in(self, i):
        return ("x", "p")[i]

    def get_name_out(self, i):
        return self.names[i]

    def get_sparsity_in(self, i):
        return self.parts[1].sparsity_in(i)

    def get_sparsity_out(self, i):
        return self.parts[i].sparsity_out(0)

    def has_eval_buffer(self):
        return True

    def eval_buffer(self, arg, res):
        for function, out in zip(self.parts, res):
            if out is not None:
                buffer, evaluate = function.buffer()
                for i, a in enumerate(arg):
                    if a is not None:  # a null input is zero, as a buffer's default
                        buffer.set_arg(i, a)
                buffer.set_res(0, out)
                evaluate()
        return 0


def _element_derivatives(group: ElementGroup) -> tuple[Source, Source]:
    """The element's Jacobian and Hessian (`_element_jacobian`, `_element_hessian`) to
    compile, identified by the element's serialisation. A group of LANES nodes or more is
    compiled as maps over LANES nodes computed in one vector pass (`ocp.vectorize`). A group
    of fewer (the mirrored nodes' variants, one node each) node by node, or, above
    `INTERPRETED_ABOVE` operations, evaluated in CasADi's virtual machine
    (`Source.interpret_above`)."""
    name, key = group.function.name(), group.function.serialize()
    if group.z_index.shape[1] < LANES:
        return (Source(f"{name}_jac", f"jacobian\n{key}", lambda: _element_jacobian(group),
                       interpret_above=INTERPRETED_ABOVE),
                Source(f"{name}_hess", f"hessian\n{key}", lambda: _element_hessian(group),
                       interpret_above=INTERPRETED_ABOVE))
    jac, hess = f"{name}_jac_x{LANES}", f"{name}_hess_x{LANES}"
    return (Source(jac, f"jacobian x{LANES}\n{key}",
                   lambda: _element_jacobian(group).map(jac, "serial", LANES, [], []), LANES),
            Source(hess, f"hessian x{LANES}\n{key}",
                   lambda: _element_hessian(group).map(hess, "serial", LANES, [], []), LANES))


def _padded(index: np.ndarray, columns: int) -> np.ndarray:
    """index (m, n) with its last column repeated up to `columns` columns: the lanes of a
    last vector pass beyond the group's nodes compute a copy of its last node (their
    entries are not summed, `_entries`)."""
    return np.concatenate([index, np.repeat(index[:, -1:], columns - index.shape[1], axis=1)],
                          axis=1)


def _block(fn: ca.Function) -> ca.Sparsity:
    """The pattern of one node's matrix in the output of fn (one node's, or LANES nodes'
    side by side)."""
    pattern, lanes = fn.sparsity_out(0), fn.size2_in(0)
    rows, cols = pattern.size1(), pattern.size2() // lanes
    return pattern.sub(list(range(rows)), list(range(cols)), False)[0]


def _symbols(fn: ca.Function):
    z, pz, c = (ca.SX.sym(name, fn.sparsity_in(i)) for i, name in enumerate(("z", "pz", "c")))
    return z, pz, c, fn(z, pz, c)


def _element_jacobian(group: ElementGroup) -> ca.Function:
    """jacobian(z, pz, c) -> dr/dz of one element, sparse."""
    z, pz, c, r = _symbols(group.function)
    return ca.Function(f"{group.function.name()}_jac", [z, pz, c], [ca.jacobian(r, z)],
                       ["z", "pz", "c"], ["jac"])


def _element_hessian(group: ElementGroup) -> ca.Function:
    """hessian(z, pz, c, y) -> d2(y . r)/dz2 of one element, sparse, as a full symmetric
    matrix."""
    z, pz, c, r = _symbols(group.function)
    y = ca.SX.sym("y", r.shape[0])
    return ca.Function(f"{group.function.name()}_hess", [z, pz, c, y],
                       [ca.hessian(ca.dot(y, r), z)[0]], ["z", "pz", "c", "y"], ["hess"])


def _entries(values: ca.MX, row_index: np.ndarray, col_index: np.ndarray,
             pattern: ca.Sparsity, row_sign: np.ndarray | None = None,
             col_sign: np.ndarray | None = None):
    """(values, rows, cols, signs): the element matrices (pattern, one per column of the
    index arrays, side by side in `values`) put the k-th nonzero of `values`, entry (a, b)
    of element j, at (row_index[a, j], col_index[b, j]), times row_sign[a, j] and
    col_sign[b, j] if given (an element of mirror images, `Layout.images`: the
    chain rule through a signed permutation); signs None where all are 1 (see `_sum`).
    Nonzeros of `values` beyond the index arrays' columns (padding) are left out."""
    a, b = (np.array(v, dtype=int) for v in pattern.get_triplet())
    n = row_index.shape[1]
    signs = np.ones(a.size * n)
    for index, sign in ((a, row_sign), (b, col_sign)):
        if sign is not None:
            signs *= sign[index[:, None], np.arange(n)].T.ravel()
    return (values, row_index[a[:, None], np.arange(n)].T.ravel(),  # element-major
            col_index[b[:, None], np.arange(n)].T.ravel(),
            None if np.all(signs == 1.0) else signs)


def _whole(m: ca.MX):
    """The entries (`_entries`) of one matrix."""
    return _entries(m, np.arange(m.size1())[:, None], np.arange(m.size2())[:, None],
                    m.sparsity())


def _sum(entries: list, shape: tuple[int, int], upper: bool = False) -> ca.MX:
    """The (shape) matrix that is the sum of `entries` (`_entries`); with upper, only the
    entries on or above the diagonal (for full symmetric element matrices this gives the
    upper triangle of the sum). Bit for bit the sum of each part's matrix, part after part
    (as IPOPT's iterates depend on round-off): each part's entries at one position are
    summed in the order of its nonzeros, then these sums in the order of the parts."""
    sums, positions = [], []
    for values, rows, cols, signs in entries:
        keys = cols * shape[0] + rows  # column-major
        source = np.flatnonzero(rows <= cols) if upper else np.arange(keys.size)
        at, slot = np.unique(keys[source], return_inverse=True)
        values = ca.sparsity_cast(values, ca.Sparsity.dense(values.nnz()))  # its nonzeros
        if signs is not None:
            values = values * ca.DM(np.concatenate(
                [signs, np.ones(values.numel() - signs.size)]))  # padding lanes: unused
        sums.append(_ordered_sum(values, source, slot, at.size))
        positions.append(at)
    keys, slot = np.unique(np.concatenate(positions), return_inverse=True)
    sparsity = ca.Sparsity.triplet(shape[0], shape[1], (keys % shape[0]).tolist(),
                                   (keys // shape[0]).tolist())
    parts = ca.vertcat(*sums)
    return ca.MX(sparsity, _ordered_sum(parts, np.arange(parts.numel()), slot, keys.size))


def _ordered_sum(values: ca.MX, source: np.ndarray, slot: np.ndarray, n: int) -> ca.MX:
    """(n,) column: entry i is the sum of the nonzeros values[source[k]] with slot[k] == i
    (every slot has one), added one after the other in the order of k. Index lists only
    (CasADi copies a constant matrix into its work vector at every evaluation): step r adds
    the r-th term of every slot that has one. values: a dense column of the nonzeros (`_sum`
    casts each part's matrix to one)."""
    order = np.argsort(slot, kind="stable")
    first = np.searchsorted(slot[order], np.arange(n))
    rank = np.empty(slot.size, dtype=int)
    rank[order] = np.arange(slot.size) - first[slot[order]]  # how many precede k in its slot
    total = values.nz[source[order[first]].tolist()]
    for r in range(1, int(rank.max(initial=0)) + 1):
        k = np.flatnonzero(rank == r)
        at = slot[k].tolist()
        total.nz[at] = total.nz[at] + values.nz[source[k].tolist()]
    return total
