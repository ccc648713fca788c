"""The collocation NLP's elements: its rows and cost terms that are one SX Function of one
collocation point's, one knot's or one interval's unknowns (`ocp.elements.ElementGroup`),
so that `ocp.derivatives.nlp_derivatives` forms their Jacobians and Lagrangian Hessians
point by point, mapped over the mesh and compiled, as it does for the DMOCC nodes.

Every element is z (entries of x and of the mirror images below), pz = p = (step length,
mu), c (constants) -> rows (or a cost term), with the transcription's scalings inside
(accelerations ACCELERATION_SCALE, forces FORCE_SCALE, torques TORQUE_SCALE). The split of
a point's dynamics row is that of the equations: J^T (...) is linear in the director force,
so the row is `dynamics_element` (inertia, gravity, torques: one Function for every point of
every phase) plus `contact_element` (-J^T C^T lambda, one per contact set; also the
impulse's term of an impact row, whose scaling cancels the same way).

Knot K is the mirror image of knot 0 (`CollocationTranscription`): its theta, tau and (with
no impact at the end) w are the images x_sign x[x_source] (+ step e for theta) appended to
x (`ImageLayout`), where the mirror is a signed permutation of theta plus the step along
x (the walkers'; not the compass's, whose planar root takes its partner leg's pose).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from benchmarks.collocation.minimal import MinimalModel
from gait_planner.ocp.contacts import BodyContact
from gait_planner.ocp.elements import ElementGroup

P_INDEX = np.array([0, 1])  # pz of every element: p = (step length, mu)


def contact_force(contacts: tuple[BodyContact, ...], lam, k: int):
    """The director force C^T lambda_rows (k,) of multipliers lam (n_multipliers of the
    contacts; the along-line shares of full contacts move nothing, `ocp.contacts`)."""
    parts, offset = [], 0
    for bc in contacts:
        parts.append(ca.mtimes(ca.DM(bc.rows).T, lam[offset : offset + bc.n_rows]))
        offset += bc.n_multipliers
    return sum(parts) if parts else ca.DM.zeros(k)


def cone_rows(contacts: tuple[BodyContact, ...], lam, q, mu, smoothing, half_width) -> list:
    """The friction cones and roll bounds (`BodyContact.cone_rows`) of multipliers lam (N)."""
    out, offset = [], 0
    for bc in contacts:
        out += bc.cone_rows(lam[offset : offset + bc.n_multipliers], q, mu, smoothing, half_width)
        offset += bc.n_multipliers
    return out


class ImageLayout:
    """Where the elements' z_index point (`ocp.derivatives.nlp_derivatives` reads
    `element_inputs` and `images`): x followed by the images of knot 0's theta, w and tau,
    image i = x_sign[i] x[x_source[i]] + x_shift[i] step."""

    def __init__(self, x_source: np.ndarray, x_sign: np.ndarray, x_shift: np.ndarray):
        self.images = {"x_source": x_source, "x_sign": x_sign}
        self.x_shift = x_shift

    def element_inputs(self, x, p):
        """(xe, pe) = ((x, images), p), numbers or CasADi expressions."""
        im = self.images
        if isinstance(x, np.ndarray):
            return np.concatenate([x, im["x_sign"] * x[im["x_source"]] + self.x_shift * p[0]]), p
        return ca.vertcat(x, ca.DM(im["x_sign"]) * x[im["x_source"].tolist()]
                          + ca.DM(self.x_shift) * p[0]), p


def signed_permutation(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(source, sign) with matrix @ v = sign * v[source], or None if matrix is not a
    signed permutation."""
    source = np.argmax(np.abs(matrix), axis=1)
    sign = matrix[np.arange(matrix.shape[0]), source]
    if not np.array_equal(np.abs(sign), np.ones(matrix.shape[0])) or \
            np.count_nonzero(matrix) != matrix.shape[0]:
        return None
    return source, sign


def mirror_map(model: MinimalModel) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(source, sign, shift) with mirror(theta, step) = sign * theta[source] + shift step,
    or None if the mirror is not of that form (the compass)."""
    theta, step = ca.SX.sym("theta", model.n), ca.SX.sym("step")
    image = model.mirror(theta, step)
    jac, shift = ca.jacobian(image, theta), ca.jacobian(image, step)
    if not (jac.is_constant() and shift.is_constant()) or \
            np.any(np.array(model.mirror(np.zeros(model.n), 0.0)) != 0.0):
        return None
    perm = signed_permutation(np.array(ca.DM(jac)))
    return None if perm is None else (*perm, np.array(ca.DM(shift)).ravel())


@dataclass
class _Instances:
    function: ca.Function
    constants: np.ndarray
    z: list = field(default_factory=list)  # (nz,) int arrays; images encoded as -1 - i
    rows: list = field(default_factory=list)  # [(group name, local rows)] per instance


class ElementSet:
    """Element instances collected while the transcription is built, grouped by (Function,
    constants); their rows are named by constraint group and resolved into rows of g, and
    image entries (-1 - i: the i-th image) into indices of (x, images), once g and x are
    complete (`groups`)."""

    def __init__(self):
        self._instances: dict[tuple, _Instances] = {}

    def add(self, function: ca.Function, constants, z: np.ndarray, rows=None) -> None:
        """One instance: function(xe[z], p, constants) adds to g at rows, a list of (group
        name, local rows) in the order of the function's outputs, or with rows None to the
        cost."""
        c = np.atleast_1d(np.asarray(constants, dtype=float))
        entry = self._instances.setdefault((function.name(), c.tobytes()),
                                           _Instances(function, c))
        entry.z.append(np.asarray(z, dtype=int))
        entry.rows.append(rows)

    def groups(self, nx: int, offsets: dict[str, int]) -> list[ElementGroup]:
        """The `ElementGroup`s, with x of nx entries and offsets[name] the first row of
        each constraint group in g."""
        out = []
        for e in self._instances.values():
            z = np.stack(e.z, axis=1)
            z = np.where(z < 0, nx - 1 - z, z)
            rows = None if e.rows[0] is None else np.stack(
                [np.concatenate([offsets[name] + np.asarray(local) for name, local in r])
                 for r in e.rows], axis=1)
            out.append(ElementGroup(e.function, z, np.repeat(P_INDEX[:, None], z.shape[1], 1),
                                    rows, e.constants))
        return out


# ---- element Functions (z, pz, c) -> r ---------------------------------------------------

def _function(name: str, z, pz, c, r) -> ca.Function:
    return ca.Function(name, [z, pz, c], [r], ["z", "pz", "c"], ["r"])


def _split(z, sizes):
    out, start = [], 0
    for size in sizes:
        out.append(z[start : start + size])
        start += size
    return out


def dynamics_element(model: MinimalModel, scales: tuple[float, float, float]) -> ca.Function:
    """A point's dynamics row without its contact term, `MinimalModel.dynamics` (n,) /
    FORCE_SCALE, of z = (theta, w, a, tau0, tau1) (a, tau scaled) with the torque
    c0 tau0 + c1 tau1 (a knot: (1, 0), a midpoint: (0.5, 0.5) of its interval's knots).
    scales: (ACCELERATION_SCALE, TORQUE_SCALE, FORCE_SCALE)."""
    n, nt = model.n, model.mb.nt
    z, pz, c = ca.SX.sym("z", 3 * n + 2 * nt), ca.SX.sym("pz", 2), ca.SX.sym("c", 2)
    theta, w, a, tau0, tau1 = _split(z, (n, n, n, nt, nt))
    acc, torque, force = scales
    r = model.dynamics(theta, w, acc * a, torque * (c[0] * tau0 + c[1] * tau1),
                       ca.DM.zeros(model.k)) / force
    return _function("collocation_dynamics", z, pz, c, r)


def impact_element(model: MinimalModel) -> ca.Function:
    """An impact row without its impulse term, `MinimalModel.impact` (n,) / c0, of
    z = (theta, w_minus, w_plus); c0 = FORCE_SCALE * base time step."""
    n = model.n
    z, pz, c = ca.SX.sym("z", 3 * n), ca.SX.sym("pz", 2), ca.SX.sym("c", 1)
    theta, w0, w1 = _split(z, (n, n, n))
    return _function("collocation_impact", z, pz, c,
                     model.impact(theta, w0, w1, ca.DM.zeros(model.k)) / c[0])


def contact_element(model: MinimalModel, contacts, name: str, force_scale: float) -> ca.Function:
    """The contact term -J^T C^T lambda / FORCE_SCALE (n,) of a point's dynamics row (or of
    an impact row) and the friction cones (`cone_rows`) of z = (theta, lambda) (lambda
    scaled), pz = (step, mu), c = (friction smoothing N, foot half width m)."""
    n, nl = model.n, sum(bc.n_multipliers for bc in contacts)
    z, pz, c = ca.SX.sym("z", n + nl), ca.SX.sym("pz", 2), ca.SX.sym("c", 2)
    theta, lam = _split(z, (n, nl))
    r = ca.vertcat(-model.project(theta, contact_force(contacts, lam, model.k)),
                   *cone_rows(contacts, force_scale * lam, model.configuration(theta), pz[1],
                              c[0], c[1]))
    return _function(f"collocation_contact_{name}", z, pz, c, r)


def velocity_element(model: MinimalModel, C: np.ndarray, name: str) -> ca.Function:
    """C J w (r,) of z = (theta, w); c unused."""
    n = model.n
    z, pz, c = ca.SX.sym("z", 2 * n), ca.SX.sym("pz", 2), ca.SX.sym("c", 0)
    theta, w = _split(z, (n, n))
    return _function(f"collocation_velocity_{name}", z, pz, c,
                     ca.mtimes(ca.DM(C), model.velocity(theta, w)))


def acceleration_element(model: MinimalModel, C: np.ndarray, name: str,
                         acc: float) -> ca.Function:
    """C qdd / ACCELERATION_SCALE (r,) of z = (theta, w, a) (a scaled by acc); c unused."""
    n = model.n
    z, pz, c = ca.SX.sym("z", 3 * n), ca.SX.sym("pz", 2), ca.SX.sym("c", 0)
    theta, w, a = _split(z, (n, n, n))
    return _function(f"collocation_acceleration_{name}", z, pz, c,
                     ca.mtimes(ca.DM(C), model.acceleration(theta, w, acc * a)) / acc)


def interval_element(model: MinimalModel, C: np.ndarray, name: str, acc: float) -> ca.Function:
    """An interval's Hermite-Simpson defects (4n,) and held contacts C (q_1 - q_0) (r,)
    (`collocation.transcription`) of z = (theta0, theta1, w0, w1, a0, a1, theta_m, w_m, a_m,
    gamma, sigma) (a scaled by acc), c = (interval length at sigma = 1, s)."""
    n, nr = model.n, C.shape[0]
    z, pz, c = ca.SX.sym("z", 9 * n + nr + 1), ca.SX.sym("pz", 2), ca.SX.sym("c", 1)
    th0, th1, w0, w1, a0, a1, tm, wm, am, gam, sig = _split(z, (n,) * 9 + (nr, 1))
    a0, a1, am = acc * a0, acc * a1, acc * am
    h = c[0] * sig
    correction = model.project(tm, ca.mtimes(ca.DM(C).T, gam)) if nr else 0
    r = [tm - 0.5 * (th0 + th1) - h / 8 * (w0 - w1),
         wm - 0.5 * (w0 + w1) - h / 8 * (a0 - a1),
         th1 - th0 - h / 6 * (w0 + 4 * wm + w1) - h * correction,
         w1 - w0 - h / 6 * (a0 + 4 * am + a1)]
    if nr:
        r.append(ca.mtimes(ca.DM(C), model.configuration(th1) - model.configuration(th0)))
    return _function(f"collocation_interval_{name}", z, pz, c, ca.vertcat(*r))


def cost_element(model: MinimalModel, kinetic: bool, twist_fn: ca.Function | None) -> ca.Function:
    """An interval's Simpson terms of the kinetic energy (if `kinetic`) and of the twist
    regulariser (`ocp.posture.twist_squares`, if given) of z = (theta0, w0, theta_m, w_m,
    theta1, w1, sigma), c = (interval length at sigma = 1 s, twist weight, base time step s)."""
    n = model.n
    z, pz, c = ca.SX.sym("z", 6 * n + 1), ca.SX.sym("pz", 2), ca.SX.sym("c", 3)
    th0, w0, tm, wm, th1, w1, sig = _split(z, (n,) * 6 + (1,))
    h = c[0] * sig

    def simpson(f0, fm, f1):
        return h / 6 * (f0 + 4 * fm + f1)

    total = 0
    if kinetic:
        total += simpson(*(model.kinetic_energy(t, w) for t, w in ((th0, w0), (tm, wm), (th1, w1))))
    if twist_fn is not None:
        weights = ca.vertcat(c[2], 1.0)
        total += c[1] * simpson(*(twist_fn(q, q, 1.0, weights) for q in
                                  (model.configuration(t) for t in (th0, tm, th1))))
    return _function("collocation_cost", z, pz, c, total)


def knot_element(model: MinimalModel, fn: ca.Function) -> ca.Function:
    """fn(q(theta), c) of a knot as a Function of z = theta."""
    z, pz = ca.SX.sym("z", model.n), ca.SX.sym("pz", 2)
    c = ca.SX.sym("c", fn.sparsity_in(1))
    return _function(f"collocation_{fn.name()}", z, pz, c, fn(model.configuration(z), c))


def heights_element(model: MinimalModel, fn: ca.Function) -> ca.Function:
    """fn(q(theta)) (`ocp.clearance.ground_heights`) of a knot as a Function of z = theta;
    c unused."""
    z, pz, c = ca.SX.sym("z", model.n), ca.SX.sym("pz", 2), ca.SX.sym("c", 0)
    return _function(f"collocation_{fn.name()}", z, pz, c, fn(model.configuration(z)))


def knot_pair_element(model: MinimalModel, fn: ca.Function) -> ca.Function:
    """fn(q(theta0), q(theta1), h, c_fn) (`ocp.posture.joint_speed_margins`,
    `ocp.clearance.strike_rows`) of an interval as a Function of z = (theta0, theta1,
    sigma), c = (interval length at sigma = 1 s, c_fn)."""
    n, nc = model.n, fn.numel_in(3)
    z, pz, c = ca.SX.sym("z", 2 * n + 1), ca.SX.sym("pz", 2), ca.SX.sym("c", nc + 1)
    th0, th1, sig = _split(z, (n, n, 1))
    return _function(f"collocation_{fn.name()}", z, pz, c,
                     fn(model.configuration(th0), model.configuration(th1), c[0] * sig, c[1:]))
