"""Legs that keep apart: the node rows of the leg clearance (docs/design.md section 8).

A scene gives its lower legs' bodies spheres that contain their collision geometry
(`Body.collision`: fitted to a URDF's by `gait_planner.model.urdf_collision`, written by
hand for walker3d). A leg is the subtree of one joint of the root; every sphere (c_i, r_i)
of one leg and every sphere (c_j, r_j) of another make a pair, the sphere centres
c = phi_b + D_b p placed by their body's configuration (director coordinates, p the
sphere's body-fixed centre). With R_ij = r_i + r_j + clearance, the pair's margin

    m_ij = (|c_i - c_j|^2 - R_ij^2) / (2 R_ij)   (m)

is >= 0 exactly when the spheres are at least `clearance` apart, equals the distance
|c_i - c_j| - R_ij to first order at 0 and is smooth everywhere (no square root at
coincident centres). Saturated, s_ij = M tanh(m_ij / M) (M = SATURATION) keeps its sign,
is m_ij within 0.6 % for |m_ij| <= 1 cm and never beyond m_ij, and lies in (-M, M). One
row per node keeps every pair:

    row = -eps log sum_ij exp(-s_ij / eps) >= 0,   eps = SMOOTHING,

a smooth minimum, min_ij s_ij - eps log(pairs) <= row <= min_ij s_ij: the row at 0 puts
every pair at least its clearance apart (conservative by at most eps log(pairs), 1.8 mm
for Talos's 1225 pairs). With M / eps = 300 each exp(-s / eps) lies within
(5e-131, 2e130): no pair far apart underflows the sum S to 0, and no overlap overflows
S^2, which the row's second derivatives divide by (with M / eps = 600 Talos's first
Hessian was NaN).
One row, not one per pair: Talos's legs have 35 spheres each, and 1225 rows per node would
be 48,000 inequality rows on its 40 intervals, each with its slack in IPOPT's KKT system.

The rows are built with the gait option legs_apart (default true; walker3d's gait sets it
false, keeping the paper's problem, whose optimum passes one foot through the other).
The spheres contain the bodies, so the true distance between the legs' collision geometry
is at least the spheres' (`leg_sphere_distances`); the verifier measures the former with
coal (`gait_planner.verify.legs`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene

__all__ = ["SATURATION", "SMOOTHING", "leg_bodies", "leg_clearance_rows",
           "leg_sphere_distances"]

SMOOTHING = 2.5e-4  # m: eps of the smooth minimum
SATURATION = 0.075  # m: M of the margins' saturation M tanh(m / M); M / eps = 300


def leg_bodies(scene: Scene) -> list[tuple[str, ...]]:
    """The legs with collision spheres: per joint of the root whose subtree has bodies with
    `collision` spheres, those bodies (scene order); [] for a planar scene."""
    if scene.planar:
        return []
    children: dict[str, list[str]] = {}
    for j in scene.joints:
        children.setdefault(j.parent, []).append(j.child)
    legs = []
    for top in children.get(scene.root.body, []):
        subtree, stack = [], [top]
        while stack:
            body = stack.pop()
            subtree.append(body)
            stack += children.get(body, [])
        with_spheres = tuple(b.name for b in scene.bodies
                             if b.name in subtree and b.collision)
        if with_spheres:
            legs.append(with_spheres)
    return legs


def _pairs(mb: Multibody, q) -> tuple:
    """(c_i - c_j (3, n), r_i + r_j (n,)) of every pair of spheres of different legs at
    configuration q (SX, k)."""
    legs = leg_bodies(mb.scene)
    centres, radii = [], []
    for leg in legs:
        c, r = [], []
        for name in leg:
            block = mb.block(name).start
            phi, D = q[block : block + 3], ca.reshape(q[block + 3 : block + 12], 3, 3)
            for x, y, z, radius in mb.scene.body(name).collision:
                c.append(phi + ca.mtimes(D, ca.DM([x, y, z])))
                r.append(radius)
        centres.append(ca.horzcat(*c))
        radii.append(np.array(r))
    diffs, sums = [], []
    for a in range(len(legs)):
        for b in range(a + 1, len(legs)):
            i, j = np.meshgrid(np.arange(len(radii[a])), np.arange(len(radii[b])),
                               indexing="ij")
            i, j = i.ravel().tolist(), j.ravel().tolist()
            diffs.append(centres[a][:, i] - centres[b][:, j])
            sums.append(radii[a][i] + radii[b][j])
    return ca.horzcat(*diffs), np.concatenate(sums)


def leg_sphere_distances(mb: Multibody) -> ca.Function:
    """CasADi Function "leg_sphere_distances": q (k,) -> (n,) the distances |c_i - c_j| -
    r_i - r_j (m) between the spheres of every pair of different legs (module docstring),
    legs and spheres in scene order, each leg's spheres against the next legs'."""
    q = ca.SX.sym("q", mb.k)
    d, r = _pairs(mb, q)
    out = ca.sqrt(ca.sum1(d ** 2)).T - ca.DM(r)
    return ca.Function("leg_sphere_distances", [q], [out], ["q"], ["distance"])


def leg_clearance_rows(mb: Multibody) -> ca.Function | None:
    """CasADi Function "leg_clearance": (q (k,), c (2,) = (clearance m, eps m)) -> the
    row (1,) (m; M = SATURATION), >= 0 when every pair of spheres of different legs is at least the
    clearance apart (module docstring); None when the scene has fewer than two legs
    with spheres (`leg_bodies`)."""
    if len(leg_bodies(mb.scene)) < 2:
        return None
    q, c = ca.SX.sym("q", mb.k), ca.SX.sym("c", 2)
    d, r = _pairs(mb, q)
    R = ca.DM(r).T + c[0]
    margins = SATURATION * ca.tanh((ca.sum1(d ** 2) - R ** 2) / (2 * R * SATURATION))
    row = -c[1] * ca.log(ca.sum2(ca.exp(-margins / c[1])))
    return ca.Function("leg_clearance", [q, c], [row], ["q", "c"], ["row"])
