"""Exact first and second derivatives of the gait NLP from per-node elements, compilable.

CasADi differentiates the expanded NLP as one SX graph: walker3d's Lagrangian Hessian is
6.7 M instructions (26 ms per evaluation in CasADi's virtual machine), far too large to
compile (about 200 MB of C). Most of it is the same few formulas at every node. Here the
phase-independent part of the dynamics rows and the kinetic energy of each interval
(`Transcription.elements`) are differentiated once, as functions of one node's or one
interval's unknowns: the Jacobian and the Hessian of y . r (y the rows' multipliers, or
the cost's). These are evaluated at every node (`Function.map`) and scattered into the
sparse matrices by constant 0/1 matrices (entries of an unknown that an element sees twice,
such as a sigma shared by both of its intervals, are summed); CasADi differentiates the
rest of the NLP (contact forces, contacts, path constraints, torque term) as a whole.

The elements are what makes compiling possible: walker3d's dynamics Hessian element is
5 MB of C, built once per machine (`ocp.compile`), and then the Hessian takes 11 ms and the
Jacobian 6 ms per evaluation instead of 26 and 13. Left in the virtual machine they are
slower than CasADi's one graph (49 ms), which shares each node's reparametrisation among
all rows, so the planner uses them only compiled.

The Functions returned have the signatures of nlpsol's own (options grad_f, jac_g,
hess_lag): grad_f(x, p) -> (f, grad_f_x), jac_g(x, p) -> (g, jac_g_x) and
hess_lag(x, p, lam_f, lam_g) -> triu_hess_gamma_x_x (upper triangle).
"""

from __future__ import annotations

from typing import Callable

import casadi as ca
import numpy as np

from gait_planner.ocp.compile import Source
from gait_planner.ocp.transcription import ElementGroup, Transcription

# Given the element derivatives to form, returns them (e.g. compiled) in the same order.
Compiler = Callable[[list[Source]], list[ca.Function]]


def nlp_derivatives(tr: Transcription, compiler: Compiler | None = None) -> dict[str, ca.Function]:
    """{"grad_f", "jac_g", "hess_lag"} of the NLP (tr.x, tr.p, tr.cost, tr.g)."""
    nx, ng = int(tr.x.shape[0]), int(tr.g.shape[0])
    x_sx, p_sx = ca.SX.sym("x", nx), ca.SX.sym("p", int(tr.p.shape[0]))
    lam_f_sx, lam_g_sx = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", ng)
    f, f_rest, g, g_rest = ca.Function(
        "fg", [tr.x, tr.p], [tr.cost, tr.cost_without_elements, tr.g, tr.g_without_elements]
    ).expand()(x_sx, p_sx)
    lagrangian = lam_f_sx * f_rest + ca.dot(lam_g_sx, g_rest)
    rest_grad = ca.Function("nlp_rest_grad_f", [x_sx, p_sx], [f, ca.gradient(f_rest, x_sx)])
    rest_jac = ca.Function("nlp_rest_jac_g", [x_sx, p_sx], [g, ca.jacobian(g_rest, x_sx)])
    rest_hess = ca.Function("nlp_rest_hess_l", [x_sx, p_sx, lam_f_sx, lam_g_sx],
                            [ca.triu(ca.hessian(lagrangian, x_sx)[0])])

    if compiler is None:
        pairs = [(_element_jacobian(group), _element_hessian(group)) for group in tr.elements]
    else:  # every element, also those of one node: a cached library is loaded, not formed
        done = iter(compiler([source for group in tr.elements for source in _sources(group)]))
        pairs = [(next(done), next(done)) for _ in tr.elements]

    x, p = ca.MX.sym("x", nx), ca.MX.sym("p", int(tr.p.shape[0]))
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", ng)
    f_val, grad = rest_grad(x, p)
    g_val, jac = rest_jac(x, p)
    hess = rest_hess(x, p, lam_f, lam_g)
    for group, (jac_fn, hess_fn) in zip(tr.elements, pairs):
        n = group.z_index.shape[1]
        z, pz, c = x[group.z_index], p[group.p_index], ca.DM(group.constants)
        if group.rows is None:  # a cost term
            y = ca.repmat(lam_f, 1, n)
            grad = grad + _scatter(jac_fn.map(n)(z, pz, c), jac_fn.sparsity_out(0),
                                   np.zeros((1, n), dtype=int), group.z_index, (1, nx),
                                   upper=False).T
        else:
            y = lam_g[group.rows]
            jac = jac + _scatter(jac_fn.map(n)(z, pz, c), jac_fn.sparsity_out(0), group.rows,
                                 group.z_index, (ng, nx), upper=False)
        hess = hess + _scatter(hess_fn.map(n)(z, pz, c, y), hess_fn.sparsity_out(0),
                               group.z_index, group.z_index, (nx, nx), upper=True)
    return {
        "grad_f": ca.Function("nlp_grad_f", [x, p], [f_val, grad],
                              ["x", "p"], ["f", "grad_f_x"]),
        "jac_g": ca.Function("nlp_jac_g", [x, p], [g_val, jac], ["x", "p"], ["g", "jac_g_x"]),
        "hess_lag": ca.Function("nlp_hess_l", [x, p, lam_f, lam_g], [hess],
                                ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]),
    }


def _sources(group: ElementGroup) -> tuple[Source, Source]:
    """The element's Jacobian and Hessian (`_element_jacobian`, `_element_hessian`) to
    compile, identified by the element's serialisation."""
    name, key = group.function.name(), group.function.serialize()
    return (Source(f"{name}_jac", f"jacobian\n{key}", lambda: _element_jacobian(group)),
            Source(f"{name}_hess", f"hessian\n{key}", lambda: _element_hessian(group)))


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


def _scatter(mapped: ca.MX, pattern: ca.Sparsity, row_index: np.ndarray,
             col_index: np.ndarray, shape: tuple[int, int], upper: bool) -> ca.MX:
    """Sum the element matrices (pattern, one per column of the index arrays, side by side
    in `mapped`) into one (shape) matrix: element entry (a, b) of element j goes to
    (row_index[a, j], col_index[b, j]); with upper, only entries on or above the diagonal
    (for a full symmetric element matrix this gives the upper triangle of the sum)."""
    a, b = (np.array(v) for v in pattern.get_triplet())
    n = row_index.shape[1]
    rows = row_index[a[:, None], np.arange(n)].T.ravel()  # element-major, like mapped's nonzeros
    cols = col_index[b[:, None], np.arange(n)].T.ravel()
    source = np.arange(rows.size)
    if upper:
        keep = rows <= cols
        rows, cols, source = rows[keep], cols[keep], source[keep]
    keys, target = np.unique(cols * shape[0] + rows, return_inverse=True)  # column-major
    sparsity = ca.Sparsity.triplet(shape[0], shape[1], (keys % shape[0]).tolist(),
                                   (keys // shape[0]).tolist())
    gather = ca.DM(ca.Sparsity.triplet(keys.size, pattern.nnz() * n, target.tolist(),
                                       source.tolist()), 1.0)
    return ca.MX(sparsity, ca.mtimes(gather, ca.vec(mapped.nz[:])))
