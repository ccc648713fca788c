"""An initial guess from nothing stored: a kinematic stepping motion.

Each contact point gets a target path over the half cycle: on the ground where its phase
holds it (the first stance foot where it stands in the scene pose, every later contact one
step length ahead), in between a straight line with a sine-shaped lift, and across the
cycle boundary the mirrored path of its partner (q_{n+N-1} = mirror(q_n) + step). The root
follows the mean of the contact targets at a slightly lowered height, upright. Each node's
configuration is then fitted to these targets by Gauss-Newton in the nodal
reparametrisation about the scene pose, continued from node to node, so every guess
satisfies all internal and joint constraints exactly; node 0, fitted from the scene pose,
is fitted again from node 1 where some joint jumps more than `JUMP_DEG` between them.
"""

from __future__ import annotations

from typing import Callable

import casadi as ca
import numpy as np

from gait_planner.buffered import bind
from gait_planner.model.angles import configuration, joint_angles
from gait_planner.model.ground import LEVEL, Ground
from gait_planner.ocp.mirror import contact_partners
from gait_planner.ocp.transcription import FORCE_SCALE, Transcription

LIFT = 0.05  # m, swing lift of a free contact point at the middle of its gap (plus a stair's height)
DIP = 0.07  # m, root lowered below the scene pose (legs must span a step)
_W_CONTACT, _W_ROOT, _W_UPRIGHT, _W_SMALL = 1.0, 0.1, 0.3, 1e-3
JUMP_DEG = 45.0  # a joint angle's jump from node 0 to node 1 that asks for node 0 again


def contact_targets(tr: Transcription, q_pose: np.ndarray, step: float,
                    ground: Ground = LEVEL) -> dict[str, np.ndarray]:
    """Target world positions (N+1, 3) of every contact point on `ground`."""
    mb, N = tr.mb, tr.N
    S = np.diag([1.0, -1.0, 1.0])
    held = {c.name: [n for n in range(N) if c.name in
                     {p for bc in tr.contacts[tr.phase_of_interval[n]] for p in bc.points}]
            for c in mb.scene.contacts}
    ground, G = {}, ground
    advance = np.array([step, 0.0, G.rise(step)])  # one half cycle further
    for c in mb.scene.contacts:
        x = mb.point_matrix(c.body, c.point) @ q_pose
        x[2] = x[0] * G.rise_per_step  # on the ground (`gait_planner.model.ground`)
        ground[c.name] = x + (0 if 0 in held[c.name] else 1) * advance
    lift = LIFT + abs(G.step_height)

    partner = contact_partners(mb.scene)
    samples = {}
    for c in mb.scene.contacts:
        own = {}
        for n in held[c.name]:
            own[n] = own[n + 1] = ground[c.name]
            for turns in (-2, 2):  # a full cycle away (a run's foot lands once per cycle)
                own[n + turns * (N - 1)] = own[n + 1 + turns * (N - 1)] = \
                    ground[c.name] + turns * advance
        other = partner[c.name]
        for n in held[other]:
            image = S @ ground[other]
            for m in (n, n + 1):
                own[m - (N - 1)] = image - advance
                own[m + (N - 1)] = image + advance
        samples[c.name] = own

    targets = {}
    for c in mb.scene.contacts:
        own = samples[c.name]
        if not own:  # never held (a runner's heel): placed with a held point of its body
            continue
        nodes = np.array(sorted(own))
        siblings = [d.name for d in mb.scene.contacts if d.body == c.body and d.name != c.name]
        body_nodes = np.array(sorted(set(nodes).union(*(samples[d] for d in siblings))))
        path = np.zeros((N + 1, 3))
        for n in range(N + 1):
            if n in own:
                path[n] = own[n]
                continue
            before, after = nodes[nodes < n].max(), nodes[nodes > n].min()
            if n in body_nodes:  # another point of the body is on the ground: small lift,
                # next to where this point left (or will touch) the ground
                on_ground_since = all(m in body_nodes for m in range(before, n))
                nearest = before if on_ground_since else after
                path[n] = own[nearest] + np.array([0.0, 0.0, 0.5 * lift])
                continue
            a, b = body_nodes[body_nodes < n].max(), body_nodes[body_nodes > n].min()
            frac = (n - a) / (b - a)
            path[n] = (1 - frac) * own[before] + frac * own[after]
            path[n, 2] += lift * np.sin(np.pi * frac)
        targets[c.name] = path
    for c in mb.scene.contacts:
        if c.name not in targets:
            sibling = next((d for d in mb.scene.contacts if d.body == c.body and d.name in targets),
                           None)
            if sibling is None:
                raise ValueError(f"contact point {c.name!r} is never held and no point of its "
                                 f"body is: the kinematic guess cannot place body {c.body!r}")
            offset = (mb.point_matrix(c.body, c.point)
                      - mb.point_matrix(c.body, sibling.point)) @ q_pose
            targets[c.name] = targets[sibling.name] + offset
    return targets


def kinematic_guess(tr: Transcription, step: float, ground: Ground = LEVEL) -> np.ndarray:
    """Configurations (N+1, k) of a kinematic stepping motion for transcription `tr` on
    `ground`."""
    mb = tr.mb
    q_pose = configuration(mb.scene)
    targets = contact_targets(tr, q_pose, step, ground)
    names = [c.name for c in mb.scene.contacts]
    root = mb.block(mb.scene.root.body).start
    points = [mb.point_matrix(mb.scene.contact(n).body, mb.scene.contact(n).point)
              for n in names]
    mean0 = np.mean([(C @ q_pose)[0] for C in points])
    offset = q_pose[root] - mean0

    u, qref = ca.SX.sym("u", mb.ndof), ca.DM(q_pose)
    tgt = ca.SX.sym("target", 3 * len(names) + 3)
    q = mb.reparametrise(u, qref)
    res = [_W_CONTACT * (ca.mtimes(ca.DM(C), q) - tgt[3 * i : 3 * i + 3])
           for i, C in enumerate(points)]
    res.append(_W_ROOT * (q[root : root + 3] - tgt[-3:]))
    res.append(_W_UPRIGHT * (q[root + 3 : root + 6] - ca.DM([1.0, 0, 0])))
    res.append(_W_UPRIGHT * (q[root + 9 : root + 12] - ca.DM([0, 0, 1.0])))
    res.append(_W_SMALL * u)
    r = ca.vertcat(*res)
    residual = _bound(ca.Function("guess_residual", [u, tgt],
                                  [r, ca.densify(ca.jacobian(r, u))]).expand())

    def node_targets(n):
        pts = [targets[name][n] for name in names]
        root_target = np.array([np.mean([p[0] for p in pts]) + offset,
                                q_pose[root + 1], q_pose[root + 2] - DIP])
        return np.concatenate(pts + [root_target])

    out = np.zeros((tr.N + 1, mb.k))
    x, xs = np.zeros(mb.ndof), []
    for n in range(tr.N + 1):
        x = _levenberg_marquardt(residual, x, node_targets(n))
        xs.append(x)
        out[n] = np.array(mb.reparametrise(x, qref)).ravel()
    # node 0 again from node 1's fit: from the scene pose the fit can end in another branch
    # that meets the targets as well (Romeo's held right foot rolled 80 deg about the line
    # through its two contact points at node 0 only: a joint angle jumps 87 deg to node
    # 1); where a joint jumps more than JUMP_DEG, the branch continued from node 1 is kept
    # if it fits no worse (walker3d's 24 deg jump at node 0 is kept: its shipped plans)
    if np.abs(np.degrees(joint_angles(mb.scene, out[0]) - joint_angles(mb.scene, out[1]))
              ).max() > JUMP_DEG:
        t0 = node_targets(0)
        again = _levenberg_marquardt(residual, xs[1], t0)
        first, second = (float(np.sum(residual(v, t0)[0] ** 2)) for v in (xs[0], again))
        if second <= first:
            out[0] = np.array(mb.reparametrise(again, qref)).ravel()
    return out


def standing_guess(tr: Transcription, step: float, ground: Ground = LEVEL) -> np.ndarray:
    """Configurations (N+1, k): the scene pose at every node (a cold start that knows
    nothing of walking; `step` and `ground` unused)."""
    return np.tile(configuration(tr.mb.scene), (tr.N + 1, 1))


def perturbed_guess(tr: Transcription, step: float, ground: Ground = LEVEL,
                    amplitude: float = 0.3, seed: int = 0) -> np.ndarray:
    """Configurations (N+1, k): the kinematic guess with every node turned by seeded random
    rotation increments of up to `amplitude` rad in each rotational entry of u (the nodal
    reparametrisation, so joints stay assembled): a deliberately poor guess."""
    mb, rng = tr.mb, np.random.default_rng(seed)
    out = kinematic_guess(tr, step, ground)
    for n in range(out.shape[0]):
        u = rng.uniform(-amplitude, amplitude, mb.ndof) * mb.rotation_mask
        out[n] = np.array(mb.reparametrise(u, out[n])).ravel()
    return out


GUESSES = {"kinematic": kinematic_guess, "standing": standing_guess, "poor": perturbed_guess}


def _bound(f: ca.Function) -> Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """f (x, t) -> (r, dense dr/dx) evaluated through bound buffers (`gait_planner.buffered`:
    the guess's ~1400 evaluations cost 4 times less than through Function calls); returns
    copies (r (nr,), J (nr, nx))."""
    x_in, t_in = np.zeros(f.nnz_in(0)), np.zeros(f.nnz_in(1))
    r_out, j_out = np.zeros(f.nnz_out(0)), np.zeros(f.nnz_out(1))
    evaluate = bind(f, [x_in, t_in], [r_out, j_out])
    jacobian = j_out.reshape(f.size1_out(1), f.size2_out(1), order="F")  # a view

    def residual(x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x_in[:], t_in[:] = x, t
        evaluate()
        return r_out.copy(), np.array(jacobian, order="C")

    return residual


def _levenberg_marquardt(f: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
                         x: np.ndarray, t: np.ndarray, iterations: int = 100) -> np.ndarray:
    """Minimise |r(x, t)|^2 from x; f returns (r, dr/dx). Damped, monotone steps."""
    damping = 1e-3
    r, J = f(x, t)
    cost = float(r @ r)
    for _ in range(iterations):
        A = J.T @ J
        dx = -np.linalg.solve(A + damping * np.diag(np.diag(A) + 1e-9), J.T @ r)
        r_new, J_new = f(x + dx, t)
        cost_new = float(r_new @ r_new)
        if cost_new < cost:
            x, r, J, cost = x + dx, r_new, J_new, cost_new
            damping = max(damping / 3, 1e-9)
            if np.abs(dx).max() < 1e-10:
                break
        else:
            damping *= 4
            if damping > 1e8:
                break
    return x


def initial_multipliers(tr: Transcription) -> np.ndarray:
    """Scaled lambda: the weight shared by the bodies in contact, split over full-contact
    points, no tangential force (and no along-line share)."""
    weight = sum(b.mass for b in tr.mb.scene.bodies) * tr.mb.scene.gravity
    out = []
    for n in tr.lam_nodes:
        contacts = tr.contacts[tr.phase_of_interval[n]]
        for bc in contacts:
            lam = np.zeros(bc.n_multipliers)
            share = weight / len(contacts) / FORCE_SCALE
            z_rows = ([1] if bc.planar else [2]) if not bc.full else \
                ([1, 2] if bc.planar else [2, 4])
            lam[z_rows] = share / len(z_rows)
            out.append(lam)
    return np.concatenate(out) if out else np.zeros(0)


def guess_x(tr: Transcription, scaling_upper: float) -> np.ndarray:
    """The NLP's x (nx,) of a cold start: zero torques and node multipliers, the scaled
    contact multipliers (`initial_multipliers`) and sigma, the phases' time scalings
    (dimensionless), at `scaling_upper`."""
    return np.concatenate([np.zeros(tr.U.numel() + tr.T.numel()), initial_multipliers(tr),
                           np.full(int(tr.S.shape[0]), scaling_upper)])
