"""The text of a `VerificationReport` (`gait-planner report`, ``python -m gait_planner.verify``).

`report_lines(report)` opens with the scene and the ground checked against ("ground: ramp 10
deg up", `gait_planner.verify.ground`), then groups the measured numbers by what they test
(constraints, contacts, ground forces, discrete dynamics, actuation, periodicity, time and
cost, physical plausibility, continuous dynamics, legs apart), one line per number::

    held points: drift over an interval      2.1e-13 m      limit 1e-09 m       ok

value and unit, then the limit and a mark: ``ok``, ``FAILED``, ``noted`` (outside the limit,
but the scene allows it: reported, not a failure) or nothing (measured, not judged). Then the
notes, the failures' sentences and, last, the verdict, which is the verifier's (`failures`):
a mark is computed from the printed value and limit, and for the few checks whose tolerance
scales with a quantity that is not printed or that a scene may exempt (normal force,
friction, scuffing, segments through the stairs, zigzags) from the failure sentence of that
check.
"""

from __future__ import annotations

import math

from gait_planner.verify.continuous import LIMITS as CONTINUOUS_LIMITS, MOMENT_ARM
from gait_planner.verify.physical import GROUND_BAND, SOLID_TOLERANCE
from gait_planner.verify.effort_limits import LIMIT_TOLERANCE
from gait_planner.verify.limits import LIMITS

__all__ = ["report_lines"]

_COST_UNITS = {"kinetic_energy": "J s", "torque_squared": "N^2 m^2 s"}


def _number(value, unit: str = "", digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    text = f"{value:.{digits}g}"
    return f"{text} {unit}".rstrip()


class _Rows:
    """Collects the lines of one report and counts the judged checks."""

    def __init__(self, failures: tuple[str, ...]):
        self.failures = failures
        self.lines: list[str] = []
        self.judged = 0

    def group(self, title: str) -> None:
        self.lines.append(f"{title}:")

    def row(self, label: str, value: str, limit: str = "", mark: str = "") -> None:
        self.judged += bool(mark)
        self.lines.append(f"  {label:<50s} {value:<16s} {limit:<32s} {mark}".rstrip())

    def within(self, label: str, value: float, unit: str, limit: float) -> None:
        """A value judged by value <= limit (NaN: not measured)."""
        if value is None or math.isnan(value):
            self.row(label, "n/a (not measured)")
            return
        self.row(label, _number(value, unit), f"limit {limit:g} {unit}".rstrip(),
                 "ok" if value <= limit else "FAILED")

    def failed(self, *words: str) -> bool:
        """Whether a failure sentence holds all of `words` (checks with scaled tolerances)."""
        return any(all(w in f for w in words) for f in self.failures)


def _constraints(r, rows: _Rows, planar: bool) -> None:
    rows.group("holonomic constraints, every node (max |g|)")
    limit = LIMITS["constraint"]
    rows.within("internal: orthonormal directors", r.max_internal_violation, "rel.", limit)
    rows.within("joints: gaps and axis alignment", r.max_joint_violation, "m", limit)
    if planar:
        rows.within("planar root: y and d2 in the plane", r.max_planar_violation, "m", limit)


def _contacts(r, rows: _Rows, planar: bool) -> None:
    rows.group("contacts")
    limit = LIMITS["contact"]
    rows.within("held points: drift over an interval", r.max_contact_drift, "m", limit)
    rows.within("held points: height above the ground", r.max_contact_height, "m", limit)
    if not planar:
        rows.within("feet in full contact: tilt |n . d2|", r.max_full_contact_roll, "rel.",
                    limit)
    rows.within("published points vs phi + X_i d_i", r.max_contact_point_error, "m", limit)
    lowest = r.min_contact_point_height
    below = lowest < -LIMITS["ground"]
    mark = ("noted" if any("below the ground" in n for n in r.notes) else "FAILED") \
        if below else "ok"
    rows.row("lowest contact point, any node", _number(lowest, "m"),
             f"limit >= -{LIMITS['ground']:.0e} m", mark)


def _forces(r, rows: _Rows) -> None:
    rows.group(f"ground forces (friction coefficient mu = {r.friction_coefficient:g})")
    rows.row("smallest normal force n . F", _number(r.min_normal_force, "N"),
             "limit >= 0 N", "FAILED" if rows.failed("pulls on the ground") else "ok")
    rows.row("friction of each foot's force |F_t| / (mu F_n)",
             _number(r.max_friction_ratio, "rel.", 4), "limit <= 1 rel.",
             "FAILED" if rows.failed("leaves the friction cone") else "ok")
    if r.physical is not None:
        rows.row("friction of each point's force", _number(r.physical.max_point_friction_ratio,
                                                           "rel.", 4), "limit <= 1 rel.",
                 "FAILED" if rows.failed("its own friction cone") else "ok")


def _dynamics(r, rows: _Rows, planar: bool) -> None:
    rows.group("discrete dynamics (Euler-Lagrange equations, nodes 1..N-1)")
    rows.within(f"residual, relative (worst: node {r.worst_dynamics_node})",
                r.max_dynamics_residual, "rel.", LIMITS["dynamics"])
    rows.row("residual, absolute", _number(r.max_dynamics_residual_absolute, "N s"))
    if not planar:
        rows.row("roll moment of feet in full contact", _number(r.max_roll_moment, "N m"))
        rows.row("its lateral centre-of-pressure offset", _number(r.max_roll_offset, "m"))


def _actuation(r, rows: _Rows) -> None:
    rows.group("actuation (joint couples only; relative to the largest)")
    limit = LIMITS["actuation"]
    rows.within("generalised force on body positions phi", r.max_actuation_phi, "rel.", limit)
    rows.within("not of the couple form 1/2 m x d_i", r.max_couple_form_error, "rel.", limit)
    rows.within("net moment of all couples", r.max_net_moment, "rel.", limit)
    rows.within("revolute couples off their axis", r.max_revolute_off_axis, "rel.", limit)
    rows.within("efforts vs generalised force", r.max_effort_mismatch, "rel.", limit)
    if r.effort_shares:  # a robot's URDF: every published effort against its limit
        name, (share, node, _) = max(r.effort_shares.items(), key=lambda kv: kv[1][0])
        rows.within(f"largest effort / URDF limit ({name}, node {node})", share, "",
                    1.0 + LIMIT_TOLERANCE)


def _periodicity(r, rows: _Rows) -> None:
    rows.group("periodicity (nodes N-1, N = mirrored nodes 0, 1 shifted by the step and rise)")
    rows.within("configuration", r.max_periodicity_error, "m", LIMITS["periodicity"])
    rows.within("contact forces", r.max_periodic_force_error, "rel.", LIMITS["periodic_force"])
    rows.within("joint couples", r.max_periodic_torque_error, "rel.", LIMITS["actuation"])


def _time_and_cost(r, rows: _Rows) -> None:
    rows.group("time and cost")
    unit = _COST_UNITS.get(r.cost_name, "")
    rows.within(f"cost {r.cost_name} {_number(r.cost_recorded, unit, 6)}: vs recomputed",
                r.cost_relative_error, "rel.", LIMITS["cost"])
    difference = abs(r.duration_recorded - r.duration_recomputed)
    limit = LIMITS["time"] * max(1.0, abs(r.duration_recomputed))
    rows.within(f"duration {_number(r.duration_recorded, 's', 6)}: vs t_(N-1) - t_0",
                difference, "s", limit)
    rows.within("time steps vs base step x sigma of the phase", r.max_interval_error, "rel.",
                LIMITS["time"])
    rows.within("sigma beyond its bounds (< 0: inside)", r.max_scaling_bound_excess, "rel.",
                LIMITS["scaling"])
    rows.within("potential energy vs sum m g z", r.max_potential_energy_error, "rel.",
                LIMITS["energy"])


def _physical(p, rows: _Rows) -> None:
    rows.group("physical plausibility")
    if math.isfinite(p.min_swing_height):
        scuffing = p.min_swing_height < GROUND_BAND
        rows.row("lowest swing point or foot edge (not held)",
                 _number(p.min_swing_height, "m"), f"limit >= {GROUND_BAND:g} m",
                 ("FAILED" if rows.failed("scuffing") else "noted") if scuffing else "ok")
    if p.edge_clearance_at is not None:  # stairs, and a swing segment crosses an edge
        point, node = p.edge_clearance_at
        rows.row(f"lowest stair-edge crossing ({point}, {node}-{node + 1})",
                 _number(p.min_edge_clearance, "m"), f"limit >= -{SOLID_TOLERANCE:g} m",
                 "FAILED" if rows.failed("through the stairs") else
                 ("noted" if p.min_edge_clearance < -SOLID_TOLERANCE else "ok"))
    label = "fastest strike (along the ground, interval before)"
    if p.strike_speed_bound > 0:
        rows.row(label, _number(p.max_strike_speed, "m/s"), f"limit {p.strike_speed_bound:g} m/s",
                 "FAILED" if rows.failed("strikes at") else "ok")
    else:
        rows.row(label, _number(p.max_strike_speed, "m/s"), "no bound (strike_speed_max)")
    rows.within(f"fastest joint ({p.fastest_joint})", p.max_joint_speed, "deg/s",
                p.joint_speed_bound)
    rows.row("torque 2nd difference away from switches", _number(
        p.max_torque_second_difference, "of peak"), "no zigzag",
        "FAILED" if rows.failed("zigzag") else "ok")
    share, joint, node = p.roughest_joint
    rows.row(f"  of its own joint's peak ({joint}, node {node})", _number(share, "of its peak"))
    if rows.failed("before its strike"):
        rows.row("strike approach (strike_deceleration_max)", "", "", "FAILED")


def _continuous(c, rows: _Rows) -> None:
    rows.group(f"continuous dynamics (Pinocchio inverse dynamics; ground wrenches: "
               f"{c.wrench_source}; peak effort {c.peak_effort:.4g} N m)")
    for label, value, limit in (
            ("torque error away from switches, of peak", c.max_torque_calm,
             CONTINUOUS_LIMITS["torque"]),
            ("torque error at switches, of peak", c.max_torque_switch,
             CONTINUOUS_LIMITS["torque_switch"])):
        rows.row(label, f"{100 * value:.3g} %", f"limit {100 * limit:g} %",
                 "ok" if value <= limit else "FAILED")
    weight, limit = c.weight, CONTINUOUS_LIMITS["force"]
    rows.row("base residual force away from switches", f"{c.max_force_calm:.3g} N",
             f"limit {limit * weight:.3g} N ({100 * limit:g} % of weight)",
             "ok" if c.max_force_calm <= limit * weight else "FAILED")
    rows.row("base residual force at switches", f"{c.max_force_switch:.3g} N")
    limit = CONTINUOUS_LIMITS["moment"] * weight * MOMENT_ARM
    rows.row("base residual moment away from switches", f"{c.max_moment_calm:.3g} N m",
             f"limit {limit:.3g} N m", "ok" if c.max_moment_calm <= limit else "FAILED")
    rows.row("base residual moment at switches", f"{c.max_moment_switch:.3g} N m")


def _legs(legs, rows: _Rows) -> None:
    rows.group(f"legs apart: {legs.source}")
    a, b = legs.pair
    kept = legs.clearance == legs.clearance  # not nan: the plan kept its legs apart
    mark = ("FAILED" if rows.failed("the legs touch") else "ok") if kept else \
        ("noted" if not legs.smallest > 0 else "")
    rows.row(f"smallest distance ({a}, {b}, node {legs.node})", _number(legs.smallest, "m"),
             "limit > 0 m" if kept else "not kept apart", mark)
    rows.row("the plan's leg_clearance (between its spheres)", _number(legs.clearance, "m"))


def report_lines(r) -> list[str]:
    """The lines of `r` (a `VerificationReport`), in the order of the module docstring."""
    rows = _Rows(r.failures)
    planar = bool(r.continuous.planar) if r.continuous is not None else r.max_planar_violation > 0
    rows.lines.append(f"{r.path}: scene {r.scene}, cost {r.cost_name}, {r.n_nodes} nodes, "
                      f"ground: {r.ground}")
    rows.row("planner", "converged" if r.planner_success else "reported failure", "",
             "ok" if r.planner_success else "FAILED")
    _constraints(r, rows, planar)
    _contacts(r, rows, planar)
    _forces(r, rows)
    _dynamics(r, rows, planar)
    _actuation(r, rows)
    _periodicity(r, rows)
    _time_and_cost(r, rows)
    if r.physical is not None:
        _physical(r.physical, rows)
    if r.continuous is not None:
        _continuous(r.continuous, rows)
    if r.legs is not None:
        _legs(r.legs, rows)
    lines = rows.lines
    lines += [f"note: {n}" for n in r.notes]
    lines += [f"FAILED: {f}" for f in r.failures]
    lines.append(f"verdict: all checks passed ({rows.judged} judged lines above)" if r.ok else
                 f"verdict: {len(r.failures)} check(s) FAILED (listed above)")
    return lines
