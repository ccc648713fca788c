"""Swing clearance: how high a contact point must be at a node where it is not held.

A point that is neither held in the interval before a node nor in the one after it is a
swing point there; the scene's `swing_clearance` keeps it off the ground so that it never
slides along z = 0 at zero force (a scuff, which a real foot would catch on). Demanding the
full margin already at the first node after a release and at the last node before a strike
made the foot whip: walker3d's heel had to rise 10 mm within one 15 ms interval before its
strike, the plan applied 12 deg of one-interval error there against the continuous
dynamics (`gait_planner.verify.drift`), and the collocation baseline rang at 560 N m
after heel-off. `swing_clearance_ramp` (s) lets the required height grow from the release
and fall towards the strike over that time, as a foot lifts and lowers, along a quarter
sine: rising at once, and joining the full height without a corner (with a linear ramp the
minimal-energy foot rode the bound and the swing knee's torque zigzagged at the corner,
walker2d). Every swing node still clears `GROUND_BAND` (1 mm) of the verifier while
sin(pi / (2 ramp_nodes)) > GROUND_BAND / swing_clearance.

In 3D scenes the foot is as wide as the plan's full contact assumes (`foot_half_width`,
the roll moment's lever): the height is required of both edges of a swing point, the point
+- foot_half_width along its body's lateral director d2, not only of the point on the
heel-toe line. With the centre line alone walker3d's minimal-energy swing foot rolled up
to 28 deg and put an edge 14 mm below the ground, and a simulated foot of that width
struck early and fell (`gait-planner walk`, benchmarks/HISTORY.md).

A strike is perfectly plastic: whatever speed the point brings to the ground is lost in
the impact, and the minimal-energy optimum uses that as a brake. walker3d's heel arrived at
3 m/s forward and 0.3 m/s down (a 6 degree approach), so a body a few millimetres lower,
as on a compliant ground or a robot's soft sole, struck 24 ms early and 7.6 cm short, and
a simulated walker's feedback doubled (`gait-planner walk`). `strike_speed_max` (m/s)
bounds the striking point's mean horizontal speed over the interval that ends at its
strike (`strike_schedule`, `strike_rows`): the foot comes down rather than in. That bound
alone brakes the swing leg in the last intervals (walker3d's swing knee torque 7 -> 14 ->
19 -> 46 -> -24 N m over nodes 12-16, a spike for a robot's torque loop);
`strike_deceleration_max` (m/s^2) bounds the point's speed over the swing's earlier
intervals too, growing by that much per second (of base time) before the strike
(`approach_schedule`), so that the leg slows over its swing.

On a ramp or stairs (`gait_planner.model.ground`) a height is measured from the ground
the scene stands on: along the ramp's normal, or above the tread under the point, each
stair edge a smooth step (`ground_heights`); a strike's speed is its speed along the
ground. On stairs up the step is moved `EDGE_MARGIN` towards the lower tread, so that the
segment between two nodes clears the edge's corner while a point moves less than that per
interval. On stairs down the step sits at the edge (5 widths past it) and each segment
between two nodes a point is not held over is kept above the corner exactly
(`segment_heights`): each end must clear the staircase at its own x and at the other
end's. A point's position is linear in the director coordinates, so the segment is the
verifier's. The 7.5 cm margin these replace put the smooth step's shoulder past the edge,
where walker3d's swing heel touched it and then dropped 15 cm in four intervals; its plan
missed the continuous-dynamics certificate (1.23 % on 40 intervals, 0.36 % on 80).

A cold plan on stairs down starts from a plan with the margin instead
(`Ground.segment_rows` False, `gait_planner.ocp.solve`): cold from the kinematic guess
with the segment rows, 0.10 m down found no plan in 300-600 s on either walker. That plan
keeps its segments above the corners by the midpoint of every interval a point is not
held over (`midpoint_heights`; the midpoint of two nodes' points is the point of the mean
configuration): without it walker2d's forefoot, released 3 cm before the edge of a
0.15 m stair down, went 10 cm per interval and its segment passed 3.5 mm through the
corner while both nodes cleared the smooth step. Stairs up need neither: their plans
cleared every corner, and with midpoint rows walker2d's 0.15 m stairs up found no plan in
120 s (it converges in 14 s without; 2026-11-27).

Used by both transcriptions (`gait_planner.ocp.transcription`,
`benchmarks.collocation.transcription`), so the two solve the same problem.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import casadi as ca
import numpy as np

from gait_planner.model.ground import LEVEL, Ground, ParametricGround
from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.mirror import contact_partners
from gait_planner.ocp.settings import GaitSettings


def next_half_mirrored(scene: Scene) -> bool:
    """Whether the half cycle after the scene's gait is its gait's mirror image: a periodic
    half cycle's is; a transition of K half cycles (`ocp.transition.transition_scene`, its
    copies' phases named "<phase>~<j>") is followed by the gait's half cycle K, the mirror
    image for odd K."""
    copies = 1 + max((int(p.name.rsplit("~", 1)[1]) - 1 for p in scene.gait.phases
                      if "~" in p.name), default=0)
    return copies % 2 == 1


def required_clearances(scene: Scene, held: Sequence[frozenset[str] | set[str]], margin: float,
                        ramp_nodes: float) -> dict[int, dict[str, float]]:
    """Swing points and their required heights (m) at the nodes 1..P of a half cycle.

    held (P,): the contact points held in each interval 0..P-1; interval i + P holds the
    mirror partners of interval i's points (the next half cycle; its own points after a
    transition of an even number of half cycles, `next_half_mirrored`) and i - P likewise, so
    node P (the image of node 0) and the points released or struck across the cycle
    boundary are handled. margin m: swing_clearance; ramp_nodes: swing_clearance_ramp /
    base_time_step (<= 1: the full margin from the first swing node on).

    Returns {node: {point: height}} in the scene's contact order, a point listed at node n
    if it is held neither in interval n-1 nor in interval n, with height
    margin * sin(pi/2 * min(1, k / ramp_nodes)), k = min(k_release, k_strike): k_release
    the nodes since its release (the node that ended its last held interval), k_strike the
    nodes to its strike (the node that starts its next held interval); a point never held
    keeps the full margin."""
    period = len(held)
    partner = contact_partners(scene)
    flips = next_half_mirrored(scene)

    def is_held(point: str, interval: int) -> bool:
        turns, inner = divmod(interval, period)
        return (partner[point] if turns % 2 and flips else point) in held[inner]

    ramp = max(float(ramp_nodes), 1.0)
    out: dict[int, dict[str, float]] = {}
    for n in range(1, period + 1):
        out[n] = {}
        for contact in scene.contacts:
            name = contact.name
            if is_held(name, n - 1) or is_held(name, n):
                continue
            since = next((n - i - 1 for i in range(n - 2, n - 2 - 2 * period, -1)
                          if is_held(name, i)), None)
            until = next((i - n for i in range(n + 1, n + 1 + 2 * period)
                          if is_held(name, i)), None)
            steps = min((k for k in (since, until) if k is not None), default=None)
            out[n][name] = margin if steps is None else \
                margin * math.sin(0.5 * math.pi * min(1.0, steps / ramp))
    return out


def strike_schedule(scene: Scene, held: Sequence[frozenset[str] | set[str]],
                    last: set[str] | None = None) -> dict[int, tuple[str, ...]]:
    """{interval n: contact points that strike at its end}: held in interval n + 1, not in
    interval n; held (P,) as in `required_clearances`; `last`: the points held in interval
    P (a transition's last interval: its own phase's, the gait's joined or standing
    still; None: the mirror image of interval 0's, as a periodic half cycle's, or its own
    after a transition of an even number of half cycles, `next_half_mirrored`). Only
    intervals with a strike are listed, points in the scene's order."""
    period = len(held)
    partner = contact_partners(scene)
    if last is None:
        last = {partner[p] for p in held[0]} if next_half_mirrored(scene) else set(held[0])
    after = list(held[1:]) + [last]
    out = {}
    for n in range(period):
        points = tuple(c.name for c in scene.contacts
                       if c.name in after[n] and c.name not in held[n])
        if points:
            out[n] = points
    return out


def approach_schedule(strikes: dict[int, tuple[str, ...]],
                      held: Sequence[frozenset[str] | set[str]]
                      ) -> dict[int, dict[int, tuple[str, ...]]]:
    """{j: {interval m: points}}: the intervals m = n - j (j >= 1, m >= 0) of the swing of
    each point that strikes at the end of interval n (`strike_schedule`), back to the
    interval after its release (held as there); points in the strikes' order. Their
    strike speed rows get the bound of `GaitSettings.strike_deceleration_max`."""
    out: dict[int, dict[int, tuple[str, ...]]] = {}
    for n, points in strikes.items():
        for point in points:
            m = n - 1
            while m >= 0 and point not in held[m]:
                by_interval = out.setdefault(n - m, {})
                by_interval[m] = by_interval.get(m, ()) + (point,)
                m -= 1
    return {j: dict(sorted(by_interval.items())) for j, by_interval in sorted(out.items())}


def strike_rows(mb: Multibody, points: Sequence[str], ground: Ground | ParametricGround = LEVEL
                ) -> ca.Function:
    """CasADi Function (q_n, q_{n+1}, h_n, c[, ground]) -> one margin (>= 0) per striking
    point (ground: the parameters of a symbolic `ParametricGround`):
    ((v h_n)^2 - |d|^2) / (v c0)^2, c = (base time step s, v = strike speed bound m/s),
    d = x_{n+1} - x_n less its component along the ground's normal n: the point's mean
    speed along the ground over the interval below v (horizontal on level ground and
    stairs; the row is smooth, and O(1) at sigma = 1). In planar scenes in the x-z plane."""
    q0, q1, h, c = ca.SX.sym("q", mb.k), ca.SX.sym("q_next", mb.k), ca.SX.sym("h"), \
        ca.SX.sym("c", 2)
    ground = ParametricGround.of(ground)
    rows = []
    for point in points:
        contact = mb.scene.contact(point)
        P = mb.point_matrix(contact.body, contact.point)
        d = ca.mtimes(ca.DM(P), q1 - q0)
        step = d - ca.vertcat(*ground.normal) * ca.mtimes(ground.along_normal(P), q1 - q0)
        rows.append(((c[1] * h) ** 2 - ca.sumsqr(step)) / (c[1] * c[0]) ** 2)
    return ca.Function("strike_speed_" + "_".join(points), [q0, q1, h, c, *ground.inputs],
                       [ca.vertcat(*rows)], ["q", "q_next", "h", "c", *_names(ground)],
                       ["margin"])


def clearance_schedule(scene: Scene, held: Sequence[set[str]], settings: GaitSettings,
                       node_spacing: float) -> dict[int, dict[str, float]]:
    """`required_clearances` of the settings (held as there; node_spacing s the time
    between nodes at sigma = 1); {} without settings.ground_clearance."""
    if not settings.ground_clearance:
        return {}
    return required_clearances(scene, held, settings.swing_clearance,
                               settings.swing_clearance_ramp / node_spacing)


def _names(ground: ParametricGround) -> list[str]:
    return ["ground"] * len(ground.inputs)


def edge_heights(mb: Multibody, point: str, half_width: float,
                 ground: Ground | ParametricGround = LEVEL):
    """Rows (Z, X), each (r, k), of what must clear the ground for a swing contact
    point: its two foot edges p_C -+ half_width d2 (r = 2) in a 3D scene with half_width
    > 0, else the point itself (r = 1). Z q is their height along the ground's normal n
    (n . p: above a ramp's plane; z on level ground and stairs), X q their x (m). Z is a
    CasADi expression (of a `ParametricGround`'s parameters), X a numpy array."""
    c = mb.scene.contact(point)
    P = mb.point_matrix(c.body, c.point)
    if mb.scene.planar or half_width <= 0:
        edges = [P]
    else:
        d2 = np.zeros((3, mb.k))
        start = mb.block(c.body).start + 6
        d2[:, start : start + 3] = half_width * np.eye(3)
        edges = [P - d2, P + d2]
    ground = ParametricGround.of(ground)
    return ca.vertcat(*[ground.along_normal(E) for E in edges]), np.array([E[0] for E in edges])


def _stacked_edges(mb: Multibody, points: Sequence[str], half_width: float,
                   ground: ParametricGround):
    """(Z, X), each (r, k): the `edge_heights` rows of `points`, stacked in order."""
    blocks = [edge_heights(mb, name, half_width, ground) for name in points]
    return ca.vertcat(*[z for z, _ in blocks]), ca.DM(np.vstack([x for _, x in blocks]))


def ground_heights(mb: Multibody, points: Sequence[str], half_width: float,
                   ground: Ground | ParametricGround = LEVEL) -> ca.Function:
    """CasADi Function "ground_heights" (q (k,)[, ground]) -> (r,) m: the heights above the
    ground of the `edge_heights` of `points`, in order: Z q on level ground and ramps; on
    stairs Z q - `Ground.clearance_height`(X q), the height above the treads with each
    edge a smooth step moved towards the lower tread (`gait_planner.model.ground`);
    ground: the parameters of a symbolic `ParametricGround`."""
    q = ca.SX.sym("q", mb.k)
    ground = ParametricGround.of(ground)
    Z, X = _stacked_edges(mb, points, half_width, ground)
    height = ca.mtimes(Z, q)
    if ground.stairs:
        height = height - ground.clearance_height(ca.mtimes(X, q), _logistic)
    return ca.Function("ground_heights_" + "_".join(points), [q, *ground.inputs], [height],
                       ["q", *_names(ground)], ["z"])


def segment_heights(mb: Multibody, points: Sequence[str], half_width: float,
                    ground: Ground | ParametricGround) -> ca.Function:
    """CasADi Function "segment_heights" (q_n, q_{n+1}, h_n, c[, ground]) -> (2 r,) m, the
    rows that
    keep the straight segment between two nodes' `edge_heights` points above stairs down:
    first Z q_n - g(X q_{n+1}), then Z q_{n+1} - g(X q_n), each less the required height
    c[1] (g: `Ground.clearance_height`; c[0], the base time step, and h_n are unused, the
    interval element signature). With the nodes' own `ground_heights` rows, each end of a
    segment is above g at both ends' x; g falls monotonically across the one edge a
    segment crosses, so the whole segment is above the smooth staircase, which lies above
    the edge's corner (module docstring)."""
    q0, q1, h, c = ca.SX.sym("q", mb.k), ca.SX.sym("q_next", mb.k), ca.SX.sym("h"), \
        ca.SX.sym("c", 2)
    ground = ParametricGround.of(ground)
    Z, X = _stacked_edges(mb, points, half_width, ground)

    def g(x):
        return ground.clearance_height(x, _logistic)

    rows = ca.vertcat(ca.mtimes(Z, q0) - g(ca.mtimes(X, q1)),
                      ca.mtimes(Z, q1) - g(ca.mtimes(X, q0))) - c[1]
    return ca.Function("segment_heights_" + "_".join(points), [q0, q1, h, c, *ground.inputs],
                       [rows], ["q", "q_next", "h", "c", *_names(ground)], ["z"])


def midpoint_heights(mb: Multibody, points: Sequence[str], half_width: float,
                     ground: Ground | ParametricGround) -> ca.Function:
    """CasADi Function (q_n, q_{n+1}, h_n, c[, ground]) -> (r,) m: the `ground_heights` of
    `points` at
    the mean configuration (q_n + q_{n+1}) / 2, whose contact points are the midpoints of
    the nodes' (positions are linear in q); h_n and c are unused (the interval element
    signature)."""
    q0, q1, h, c = ca.SX.sym("q", mb.k), ca.SX.sym("q_next", mb.k), ca.SX.sym("h"), \
        ca.SX.sym("c", 2)
    ground = ParametricGround.of(ground)
    heights = ground_heights(mb, points, half_width, ground)(0.5 * (q0 + q1), *ground.inputs)
    return ca.Function("midpoint_heights_" + "_".join(points), [q0, q1, h, c, *ground.inputs],
                       [heights], ["q", "q_next", "h", "c", *_names(ground)], ["z"])


def segment_schedule(scene: Scene, held: Sequence[frozenset[str] | set[str]],
                     ground: Ground | ParametricGround,
                     clearances: dict[int, dict[str, float]]
                     ) -> dict[int, tuple[tuple[str, ...], float]]:
    """{interval n: (contact points not held over it, required height m)} of intervals
    0..P-1 (held (P,) as in `required_clearances`), on stairs down only, the intervals of
    `segment_heights` (or of `midpoint_heights` without segment rows); {} otherwise: above
    a plane a segment is lowest at one of its ends, and stairs up keep `EDGE_MARGIN`
    (module docstring). The required height is the least of those points' required
    heights at nodes n and n + 1 (`clearance_schedule`; 0 at a node where a point is
    held), so that a segment ending in a contact asks only to stay above the treads.
    Points in the scene's order."""
    if not ground.descending:
        return {}
    out = {}
    for n, points in enumerate(held):
        free = tuple(c.name for c in scene.contacts if c.name not in points)
        if free:
            out[n] = (free, min(clearances.get(m, {}).get(p, 0.0)
                                for p in free for m in (n, n + 1)))
    return out


def _logistic(x):
    """1 / (1 + e^-x), elementwise on a CasADi expression."""
    return 1.0 / (1.0 + ca.exp(-x))


def schedule_heights(mb: Multibody, points: dict[str, float], half_width: float
                     ) -> list[float]:
    """The required heights (m) of the `edge_heights` rows of every point of one node of a
    `clearance_schedule`, in row order."""
    return [h for name, h in points.items()
            for _ in range(edge_heights(mb, name, half_width)[0].shape[0])]


def clearance_rows(mb: Multibody, q_at: Callable[[int], ca.MX],
                   schedule: dict[int, dict[str, float]], half_width: float,
                   ground: Ground | ParametricGround = LEVEL, ground_values=()
                   ) -> tuple[list, list[float]]:
    """The "ground_clearance" rows height - required >= 0 of every swing point of
    `schedule` (`clearance_schedule`; q_at(n) the configuration (k,) of node n), at its two
    foot edges (`ground_heights`, half_width m), and their required heights (m), in row
    order; ground_values: what a symbolic ground's parameters are (the NLP's entries)."""
    rows: list = []
    heights: list[float] = []
    for n, points in schedule.items():
        if points:
            h = schedule_heights(mb, points, half_width)
            rows.append(ground_heights(mb, tuple(points), half_width, ground)(
                q_at(n), *ground_values) - ca.DM(h))
            heights += h
    return rows, heights
