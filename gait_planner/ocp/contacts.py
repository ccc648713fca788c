"""Contact modes of a gait phase: which rows of q a held contact fixes, and its forces.

A phase holds a set of contact points. Points on different bodies are independent; the two
points of one body held together form a full contact (the body's pose is fixed: 6
independent rows in 3D, 3 in planar scenes). All contact rows are linear in q (a point's
world position is x = C q; the foot's roll is the z component of its director d2), so a
held contact is the chain condition C (q_{n+1} - q_n) = 0 over an interval (docs/design.md
section 5: no redundant rows), and the contact force of node n enters its discrete
Euler-Lagrange equation as +(h_{n-1} + h_n)/2 C^T lambda_n: lambda is the force the ground
exerts on the body (the multiplier of the paper's eq. 1 is its negative).

Rows per body (3D; planar scenes drop the y rows and the roll row):
  one point  p:        p_x, p_y, p_z                   lambda = ground force on p (N)
  full  (a = first, b = second point in scene order):
                       a_x, a_y, a_z, b_y, b_z, d2_z  lambda = (F_a, F_b,y, F_b,z, M_roll)
where M_roll (N m) is the generalised force on d2_z: a moment d2 x e_z M_roll about the
heel-toe line, which two point forces cannot carry. On a ramp (`gait_planner.model.ground`)
the roll row is n . d2 (n the ramp's normal; the foot flat on the ramp), and M_roll is the
moment about the heel-toe line of a foot flat on it (n . (e x d2) = 1). The net ground
force on the body is F_a + F_b with F_b = (0, F_b,y, F_b,z).

A full contact has one more multiplier, s (N), that no row sees: equal and opposite forces
along the heel-toe line e = (x_b - x_a)/|x_b - x_a| change neither the net force nor the
moment, so the two points' share of the along-line force is free. The point forces are
F_a - s e and F_b + s e; each point's friction cone is imposed on them, and they are what
is published (`point_forces`).

Friction cones and the roll moment's bound are about the ground's normal n (e_z on level
ground and on stairs): the normal force is n . F, the tangential force F - (n . F) n.
The transcription reads n from its parameters (`gait_planner.model.ground.ParametricGround`):
`phase_rows` and `establishing_rows` then are CasADi expressions of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gait_planner.model.ground import LEVEL, Ground, ParametricGround
from gait_planner.model.multibody import Multibody


@dataclass(frozen=True)
class BodyContact:
    """The held contact of one body in one phase."""

    body: str
    points: tuple[str, ...]  # contact names, scene order (1 = point, 2 = full contact)
    rows: np.ndarray  # (r, k) constant rows of q fixed by the contact
    planar: bool
    span: np.ndarray | None = None  # (3, k): x_b - x_a = span @ q (full contact)
    span_length: float = 0.0  # |x_b - x_a| (m), constant on a rigid body
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)  # the ground's unit normal

    @property
    def full(self) -> bool:
        return len(self.points) == 2

    @property
    def n_rows(self) -> int:
        return int(self.rows.shape[0])

    @property
    def n_multipliers(self) -> int:
        """Rows, plus the along-line share s of a full contact (module docstring)."""
        return self.n_rows + (1 if self.full else 0)

    def force_components(self, lam, q) -> list[list]:
        """Per point the ground force as [x, y, z] components, from this contact's
        multipliers lam (n_multipliers,) and the configuration q (k,): plain arithmetic on
        entries, so it serves numpy values and CasADi expressions alike."""
        if self.planar:
            first = [lam[0], 0.0, lam[1]]
            second = [0.0, 0.0, lam[2]] if self.full else None
        else:
            first = [lam[0], lam[1], lam[2]]
            second = [0.0, lam[3], lam[4]] if self.full else None
        if not self.full:
            return [first]
        d = [sum(self.span[i, j] * q[j] for j in np.flatnonzero(self.span[i])) for i in range(3)]
        s = lam[self.n_rows] / self.span_length  # d / length = e
        return [[a - s * e for a, e in zip(first, d)], [b + s * e for b, e in zip(second, d)]]

    def cone_rows(self, lam, q, mu, smoothing, half_width, normal=None) -> list:
        """Friction cone (>= 0) of every point's ground force F about the ground's normal n,
        mu F_n - sqrt(|F_t|^2 + smoothing^2) with F_n = n . F and F_t = F - F_n n, which
        makes it push; for a 3D full contact also the roll moment's bound (centre of
        pressure within the foot's half width (m)). lam, q as for `force_components`, as
        CasADi expressions; normal: n (3 numbers or expressions), else this contact's."""
        n = self.normal if normal is None else normal
        out = []
        for f in self.force_components(lam, q):
            normal = sum(a * b for a, b in zip(n, f) if not _zero(a))
            tangential = [fi - normal * ni for fi, ni in zip(f, n)]
            out.append(mu * normal - ca.sqrt(sum(t**2 for t in tangential) + smoothing**2))
        if self.full and not self.planar:  # net force F_a + F_b = (lam0, lam1+lam3, lam2+lam4)
            fn = n[0] * lam[0] + n[2] * (lam[2] + lam[4])
            out += [half_width * fn - lam[5], half_width * fn + lam[5]]
        return out

    def point_forces(self, lam: np.ndarray, q: np.ndarray) -> dict[str, np.ndarray]:
        """Ground force (3,) on each point (N, world) from this contact's multipliers
        (n_multipliers,) at configuration q (k,)."""
        lam, q = np.asarray(lam, dtype=float), np.asarray(q, dtype=float)
        return {p: np.array([float(c) for c in f])
                for p, f in zip(self.points, self.force_components(lam, q))}

    def roll_moment(self, lam: np.ndarray) -> float:
        """M_roll (N m) of a 3D full contact, else 0."""
        return float(lam[5]) if self.full and not self.planar else 0.0


def body_contacts(mb: Multibody, contact_names, ground: Ground = LEVEL
                  ) -> tuple[BodyContact, ...]:
    """Group held contact points by body, in scene body order, with their rows (a full
    contact's roll row n . d2 with n the ground's normal)."""
    scene = mb.scene
    normal = tuple(float(v) for v in ground.normal)
    by_body: dict[str, list[str]] = {}
    for c in scene.contacts:
        if c.name in contact_names:
            by_body.setdefault(c.body, []).append(c.name)
    out = []
    for body in mb.body_names:
        names = by_body.get(body)
        if not names:
            continue
        if len(names) > 2:
            raise ValueError(f"body {body!r} holds {len(names)} contact points; at most 2")
        first = mb.contact_rows(names[0])
        if len(names) == 1:
            out.append(BodyContact(body, tuple(names), first, scene.planar, normal=normal))
            continue
        second = mb.contact_rows(names[1])
        roll = np.zeros((1, mb.k))
        d2 = mb.block(body).start + 6
        roll[0, d2 : d2 + 3] = normal  # n . d2
        rows = (np.vstack([first, second[1:]]) if scene.planar
                else np.vstack([first, second[1:], roll]))
        a, b = (scene.contact(n) for n in names)
        span = mb.point_matrix(body, b.point) - mb.point_matrix(body, a.point)
        length = float(np.linalg.norm(np.subtract(scene.body(body).points[b.point],
                                                  scene.body(body).points[a.point])))
        out.append(BodyContact(body, tuple(names), rows, scene.planar, span, length, normal))
    return tuple(out)


def _zero(a) -> bool:
    """a is the number 0 (not an expression)."""
    return isinstance(a, (int, float)) and a == 0.0


def stacked_rows(contacts: tuple[BodyContact, ...], k: int) -> np.ndarray:
    """All rows of a phase's contacts, (sum r, k)."""
    return np.vstack([c.rows for c in contacts]) if contacts else np.zeros((0, k))


def phase_rows(mb: Multibody, contacts: tuple[BodyContact, ...],
               ground: Ground | ParametricGround):
    """`stacked_rows` of `contacts` with each full 3D contact's roll row n . d2 about
    `ground`'s normal: a CasADi (sum r, k) matrix (of a `ParametricGround`'s parameters)."""
    ground = ParametricGround.of(ground)
    rows = []
    for c in contacts:
        rows += [ca.DM(c.rows[i : i + 1]) for i in range(c.n_rows)]
        if c.full and not c.planar:
            d2 = mb.block(c.body).start + 6
            roll = np.zeros((3, mb.k))
            roll[:, d2 : d2 + 3] = np.eye(3)
            rows[-1] = ground.along_normal(roll)
    return ca.vertcat(*rows) if rows else ca.DM.zeros(0, mb.k)


def landing_treads(before: tuple[BodyContact, ...], after: tuple[BodyContact, ...],
                   tread: dict[str, int], beside: bool = False) -> dict[str, int]:
    """The stair tread of every contact point held in `after`, the phase that follows
    `before` (tread 0: the one the first phase stands on; `Ground.tread_height`), from
    `tread` (body -> tread of the bodies that have stood so far), which it updates: a body
    held in `before` keeps its tread; one that touches down after a swing steps onto the
    tread beyond the highest so far (each step of a walk on stairs climbs or descends one:
    a half cycle's landing foot onto tread 1, the next half cycle's onto tread 2), or, if
    `beside` (a stop's last step, which brings the feet together), onto the highest."""
    held = {c.body for c in before}
    for c in after:
        if c.body not in held:
            top = max(tread.values(), default=0)
            tread[c.body] = top if beside else top + 1
    return {p: tread.get(c.body, 0) for c in after for p in c.points}


def phase_treads(contacts: list[tuple[BodyContact, ...]], beside: list[bool]
                 ) -> list[dict[str, int]]:
    """Per phase k of a sequence (contacts[k] its held contacts, every phase at least one
    interval), the stair tread of each of its points: phase 0's on tread 0, each next
    phase's by `landing_treads` from the one before (beside[k]: phase k's landing foot
    sets down beside the other)."""
    tread = {c.body: 0 for c in contacts[0]}
    out = [{p: 0 for c in contacts[0] for p in c.points}]
    for k in range(1, len(contacts)):
        out.append(landing_treads(contacts[k - 1], contacts[k], tread, beside[k]))
    return out


def establishing_rows(mb: Multibody, before: tuple[BodyContact, ...],
                      after: tuple[BodyContact, ...], ground: Ground | ParametricGround = LEVEL,
                      treads: dict[str, int] | None = None):
    """Rows E (r, k) and heights e (r,) m with E q = e at the node where `after` starts:
    the height above the ground of every point that touches down there, n . p = its
    tread's height (n the ground's normal; on stairs the tread `treads` gives the point,
    `phase_treads`, else tread 0), and,
    for a body whose full contact is completed there, its roll n . d2 = 0 (foot flat on
    the ground). r may be 0. CasADi expressions (of a `ParametricGround`'s parameters;
    the roll row `phase_rows`')."""
    ground = ParametricGround.of(ground)
    held = {p for c in before for p in c.points}
    rows, heights = [], []
    for c in after:
        new = [p for p in c.points if p not in held]
        for p in new:
            point = mb.scene.contact(p)
            rows.append(ground.along_normal(mb.point_matrix(point.body, point.point)))
            heights.append(ground.tread_height((treads or {}).get(p, 0)))
        if new and c.full and not c.planar:
            rows.append(phase_rows(mb, (c,), ground)[-1, :])
            heights.append(0.0)
    return (ca.vertcat(*rows) if rows else ca.DM.zeros(0, mb.k)), ca.vertcat(*heights)
