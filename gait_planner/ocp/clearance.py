"""Swing clearance: how high a contact point must be at a node where it is not held.

A point that is neither held in the interval before a node nor in the one after it is a
swing point there; the scene's `swing_clearance` keeps it off the ground so that it never
slides along z = 0 at zero force (a scuff, which a real foot would catch on). Demanding the
full margin already at the first node after a release and at the last node before a strike
made the foot whip: walker3d's heel had to rise 10 mm within one 15 ms interval before its
strike, the plan applied 12 deg of one-interval error there against the continuous
dynamics (`gait_planner.verify.simulation`), and the collocation baseline rang at 560 N m
after heel-off. `swing_clearance_ramp` (s) lets the required height grow from the release
and fall towards the strike over that time, as a foot lifts and lowers, along a quarter
sine: rising at once, and joining the full height without a corner (with a linear ramp the
minimal-energy foot rode the bound and the swing knee's torque zigzagged at the corner,
walker2d). Every swing node still clears `GROUND_BAND` (1 mm) of the verifier while
sin(pi / (2 ramp_nodes)) > GROUND_BAND / swing_clearance.

Used by both transcriptions (`gait_planner.ocp.transcription`,
`gait_planner.collocation.transcription`), so the two solve the same problem.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import casadi as ca

from gait_planner.model.multibody import Multibody
from gait_planner.model.scene import Scene
from gait_planner.ocp.mirror import contact_partners
from gait_planner.ocp.settings import GaitSettings


def required_clearances(scene: Scene, held: Sequence[frozenset[str] | set[str]], margin: float,
                        ramp_nodes: float) -> dict[int, dict[str, float]]:
    """Swing points and their required heights (m) at the nodes 1..P of a half cycle.

    held (P,): the contact points held in each interval 0..P-1; interval i + P holds the
    mirror partners of interval i's points (the next half cycle) and i - P likewise, so
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

    def is_held(point: str, interval: int) -> bool:
        turns, inner = divmod(interval, period)
        return (partner[point] if turns % 2 else point) in held[inner]

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


def clearance_schedule(scene: Scene, held: Sequence[set[str]], settings: GaitSettings,
                       node_spacing: float) -> dict[int, dict[str, float]]:
    """`required_clearances` of the settings (held as there; node_spacing s the time
    between nodes at sigma = 1); {} without settings.ground_clearance."""
    if not settings.ground_clearance:
        return {}
    return required_clearances(scene, held, settings.swing_clearance,
                               settings.swing_clearance_ramp / node_spacing)


def clearance_rows(mb: Multibody, q_at: Callable[[int], ca.MX],
                   schedule: dict[int, dict[str, float]]) -> tuple[list, list[float]]:
    """The "ground_clearance" rows z - height >= 0 of every swing point of `schedule`
    (`clearance_schedule`; q_at(n) the configuration (k,) of node n) and their heights (m),
    in row order."""
    rows: list = []
    heights: list[float] = []
    for n, points in schedule.items():
        for name, height in points.items():
            rows.append(ca.mtimes(ca.DM(mb.contact_rows(name)[-1:]), q_at(n)) - height)
            heights.append(height)
    return rows, heights
