"""The efforts that hold a drafted robot's locked joints, and the rows that bound them.

A locked joint (`gait_planner.model.scene.Hold`) sits inside a drafted body B and moves
rigidly with it; its held part (a set of the URDF's links, one side of the joint) is
acted on by gravity and the joint only. Its director coordinates are B's: a point X of
the part (director components from B's centre of mass) is at x = phi + D X, D = [d1 d2
d3]. With the part's mass m, first moment s = m X_c and second moment E = int X X^T dm
(all constant), about the joint's point c = phi + D X_j:

    L_c = (D s_j) x phi' + sum_ab (E_ab - X_j,a s_b) d_a x d_b',   s_j = s - m X_j,
    P = m phi' + D' s,      M = dL_c/dt + c' x P - (D s_j) x g,   tau = side (D a) . M,

M the moment the joint exerts on the part (the momentum balance about the moving point
c: dL_c/dt = -c' x P + moment of the forces about c; the joint's force passes through
c), `side` -1 when the part is the rest of the body and the effort is the reaction.

Discretely, as the variational integrator and the verifier's central differences: L_c, P
and c' on each interval from the midpoint configuration and the difference quotients,
dL_c/dt at node n as (L_{n+1/2} - L_{n-1/2}) / w_n, w_n = (h_{n-1} + h_n) / 2, c' x P as
the mean of its two intervals' values: second order in h where the motion is smooth,
which `test/ocp/test_ocp_held_efforts.py` checks against Pinocchio's inverse dynamics on
the URDF. At an impact node B's velocity jumps and this quotient is the impact's impulse
divided by w_n (the effort a controller must not feed forward): the rows skip impact
nodes, where the published effort is its neighbours' mean and the impulse is published
apart (`gait_planner.verify.robot`).

`held_efforts` is the formula (the rows, the static check of a standing robot and the
tests use it); `HeldRows` declares |tau| <= the joint's effort limit at every other node
1..N-1 as dynamics-like node elements of the transcription.
"""

from __future__ import annotations

from typing import Sequence

import casadi as ca
import numpy as np

from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Hold, Scene
from gait_planner.ocp.elements import ElementGroup
from gait_planner.ocp.request_ranges import RangeError

__all__ = ["held_efforts", "holds_of", "impact_nodes", "HeldRows", "check_holds",
           "held_effort_excess", "static_held_efforts"]


def holds_of(scene: Scene) -> tuple[Hold, ...]:
    """The scene's bounded locked joints (``robot.holds``; none for a hand-written scene)."""
    return scene.robot.holds if scene.robot is not None else ()


def _part(hold: Hold) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(m, s_j (3,), E_j (3, 3), X_j (3,), s (3,)) of a hold's part (module docstring)."""
    m, c, X_j = hold.mass, np.asarray(hold.com), np.asarray(hold.point)
    ixx, iyy, izz, ixy, ixz, iyz = hold.inertia
    inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    second = m * np.outer(c, c) + 0.5 * np.trace(inertia) * np.eye(3) - inertia
    s = m * c
    return m, s - m * X_j, second - np.outer(X_j, s), X_j, s


def held_efforts(mb: Multibody, holds: Sequence[Hold]) -> ca.Function:
    """held_efforts(q_prev (k,), q (k,), q_next (k,), h_prev s, h s) -> tau (len(holds),)
    N m: the efforts that hold `holds` at node n of configurations q_{n-1}, q_n, q_{n+1}
    (module docstring; equal configurations: the static effort against gravity)."""
    q0, q1, q2 = (ca.SX.sym(n, mb.k) for n in ("q_prev", "q", "q_next"))
    h0, h1 = ca.SX.sym("h_prev"), ca.SX.sym("h")
    g = ca.DM([0.0, 0.0, -mb.scene.gravity])

    def frame(q, body):
        block = q[mb.block(body)]
        return block[0:3], ca.reshape(block[3:12], 3, 3)  # phi, D (columns d1, d2, d3)

    out = []
    for hold in holds:
        m, s_j, E_j, X_j, s = _part(hold)
        (p0, D0), (p1, D1), (p2, D2) = (frame(q, hold.body) for q in (q0, q1, q2))

        def interval(pa, Da, pb, Db, h):
            pm, Dm, pv, Dv = 0.5 * (pa + pb), 0.5 * (Da + Db), (pb - pa) / h, (Db - Da) / h
            L = ca.cross(ca.mtimes(Dm, ca.DM(s_j)), pv)
            for a in range(3):
                for b in range(3):
                    if E_j[a, b] != 0.0:
                        L += E_j[a, b] * ca.cross(Dm[:, a], Dv[:, b])
            P = m * pv + ca.mtimes(Dv, ca.DM(s))
            return L, ca.cross(pv + ca.mtimes(Dv, ca.DM(X_j)), P)

        L0, c0 = interval(p0, D0, p1, D1, h0)
        L1, c1 = interval(p1, D1, p2, D2, h1)
        moment = (L1 - L0) / (0.5 * (h0 + h1)) + 0.5 * (c0 + c1) \
            - ca.cross(ca.mtimes(D1, ca.DM(s_j)), g)
        out.append(hold.side * ca.dot(ca.mtimes(D1, ca.DM(hold.axis)), moment))
    return ca.Function("held_efforts", [q0, q1, q2, h0, h1], [ca.vertcat(*out)],
                       ["q_prev", "q", "q_next", "h_prev", "h"], ["tau"])


def static_held_efforts(mb: Multibody, q: np.ndarray) -> dict[str, float]:
    """{locked joint: N m} that hold the scene's holds in configuration q (k,) at rest."""
    holds = holds_of(mb.scene)
    if not holds:
        return {}
    tau = held_efforts(mb, holds)(q, q, q, 1.0, 1.0)
    return {h.name: float(t) for h, t in zip(holds, np.asarray(tau).ravel())}


def check_holds(scene: Scene) -> None:
    """RangeError naming the first locked joint that cannot hold the scene's standing pose
    (`configuration(scene)`, at rest) within its effort limit: no gait can."""
    if not holds_of(scene):
        return
    from gait_planner.model.angles import configuration  # noqa: PLC0415 - a robot's only

    static = static_held_efforts(Multibody(scene), configuration(scene))
    for hold in holds_of(scene):
        if abs(static[hold.name]) > hold.effort:
            raise RangeError(
                f"locked joint {hold.name} needs {abs(static[hold.name]):.4g} N m to hold "
                f"scene {scene.name!r} standing still, beyond its URDF effort limit "
                f"{hold.effort:g} N m: lock it at another angle (--lock) or raise its limit "
                f"in robot.holds")


def held_effort_excess(mb: Multibody, q: np.ndarray, h: np.ndarray, skip: set[int]) -> str:
    """The locked joint furthest beyond its limit at the nodes 1..N-1 not in `skip` of
    configurations q (N+1, k) with interval lengths h (N,), as a sentence naming the
    effort it would need."""
    holds = holds_of(mb.scene)
    fn = held_efforts(mb, holds)
    nodes = [n for n in range(1, len(q) - 1) if n not in skip]
    tau = np.array([np.asarray(fn(q[n - 1], q[n], q[n + 1], h[n - 1], h[n])).ravel()
                    for n in nodes]).reshape(len(nodes), len(holds))
    share = np.abs(tau) / np.array([hold.effort for hold in holds])
    row, col = np.unravel_index(int(share.argmax()), share.shape)
    return (f"locked joint {holds[col].name} would need {abs(tau[row, col]):.4g} N m at node "
            f"{nodes[row]}, beyond its URDF effort limit {holds[col].effort:g} N m")


def impact_nodes(contacts: Sequence[Sequence], phase_of_interval: np.ndarray) -> set[int]:
    """Nodes n in 1..N-1 where a contact point is established (held on interval n, not
    on interval n-1); contacts: per phase, its `BodyContact`s."""
    held = [{p for bc in contacts[k] for p in bc.points} for k in phase_of_interval]
    return {n for n in range(1, len(held)) if held[n] - held[n - 1]}


class HeldRows:
    """The held_effort rows of a `Transcription` (a mixin, as `PathRows`): at each node
    1..N-1 but the impact nodes, 1 + tau / limit >= 0 and 1 - tau / limit >= 0."""

    def _held(self):
        holds = holds_of(self.mb.scene)
        if not holds:
            return
        N, nh = self.N, len(holds)
        fn = held_efforts(self.mb, holds)
        scale = ca.DM(1.0 / np.array([h.effort for h in holds]))
        impacts = impact_nodes(self.contacts, self.phase_of_interval)
        nodes = [n for n in range(1, N) if n not in impacts]
        first = sum(int(e.shape[0]) for _, e in self._eq + self._ineq)
        row_of = {n: first + 2 * nh * j + np.arange(2 * nh) for j, n in enumerate(nodes)}
        for variant, chosen in self._element_nodes().items():
            chosen = [n for n in chosen if n in row_of]
            if chosen:
                self.elements.append(ElementGroup(
                    self._held_element(fn, scale, *variant),
                    np.stack([self._element_z_index(n) for n in chosen], axis=1),
                    np.stack([self._element_p_index(n) for n in chosen], axis=1),
                    np.stack([row_of[n] for n in chosen], axis=1),
                    np.array([self.settings.base_time_step])))
        idx = np.array(nodes)
        tau = fn.map(len(nodes))(self.Q[:, idx - 1], self.Q[:, idx], self.Q[:, idx + 1],
                                 self.h[idx - 1].T, self.h[idx].T)
        rows = ca.vertcat(ca.mtimes(ca.diag(scale), tau), -ca.mtimes(ca.diag(scale), tau))
        self._ineq.append(("held_effort", 1.0 + ca.vec(rows)))
        self._without_elements["held_effort"] = ca.MX(ca.DM.ones(rows.numel()))

    def _held_element(self, fn: ca.Function, scale: ca.DM, mirrored: bool,
                      next_mirrored: bool) -> ca.Function:
        """The rows' tau / limit and -tau / limit at a node as an SX Function of the
        dynamics element's inputs (`Transcription._element_configurations`)."""
        z, pz, c, q, h0, h1 = self._element_configurations(mirrored, next_mirrored)
        tau = ca.mtimes(ca.diag(scale), fn(q[0], q[1], q[2], h0, h1))
        name = "held_effort_element" + ("_mirrored" if mirrored else
                                        "_next_mirrored" if next_mirrored else "")
        return ca.Function(name, [z, pz, c], [ca.vertcat(tau, -tau)], ["z", "pz", "c"], ["r"])
