"""Settings of one gait optimisation: the scene's gait block merged with request overrides.

Every field is validated once, here, with an error that names the setting.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from gait_planner.model.ground import Ground, GroundError
from gait_planner.model.scene import Scene
from gait_planner.model.posture import (PostureError, check_joint_limits, check_phase_joint_limits,
                                       check_posture, check_torso_lean_max, human_phase_limits)

COSTS = ("kinetic_energy", "torque_squared")


class SettingsError(ValueError):
    """A request or scene option that cannot be planned, with the reason."""


@dataclass(frozen=True)
class SolveOptions:
    """How IPOPT solves a gait problem, apart from what the problem is (`GaitSettings`):
    tolerance (IPOPT tol), constraint_tolerance (IPOPT constr_viol_tol), max_iterations,
    max_solve_time s (with refinements, the time of all plans of a request), compiled:
    build the per-node derivative elements as C (`gait_planner.ocp.compile`; a one-time
    cost per machine, cached; off here, on by default in the command line, the node and
    the benchmarks' runs; without a C compiler for what the cache lacks, the planner falls
    back to CasADi's derivatives). Scene files and `settings_for` take them by these names,
    as gait options."""

    tolerance: float = 1e-8
    constraint_tolerance: float = 1e-10
    max_iterations: int = 3000
    max_solve_time: float = 600.0
    compiled: bool = False

    def __post_init__(self):
        for name in ("tolerance", "constraint_tolerance", "max_solve_time"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value) or value <= 0:
                raise SettingsError(f"{name}: must be a positive number, got {value!r}")
        if isinstance(self.max_iterations, bool) or not isinstance(self.max_iterations, int) \
                or self.max_iterations < 1:
            raise SettingsError(f"max_iterations: must be a whole number >= 1, got "
                                f"{self.max_iterations!r}")
        if not isinstance(self.compiled, bool):
            raise SettingsError(f"compiled: must be true or false, got {self.compiled!r}")


@dataclass(frozen=True)
class GaitSettings:
    """What the transcription needs beyond the scene's bodies.

    Attributes (units): step_length m; base_time_step s; scaling_bounds (lower, upper);
    friction_coefficient -; cost one of COSTS; intervals per phase;
    torque_regularisation weight on sum h |tau|^2 (J s per (N m)^2 s, i.e. 1/(N s)) added to
    any cost; friction_smoothing delta (N) of mu f_z - sqrt(f_x^2 + f_y^2 + delta^2) >= 0;
    torso_lean_max deg in [0, 90) (the root body's d3, a drafted robot's base link z
    axis, within this angle of vertical; 0 = off; the transcription takes its cosine); torso_height_min m (torso
    centre-of-mass height; 0 = off); joint_limits ((angle name, lower rad, upper rad), ...)
    from the option ``joint_limits: {name: [lo, hi]}`` in degrees, converted by
    `gait_planner.model.posture.check_joint_limits` in `settings_for`; effort_limits
    ((revolute joint, N m), ...) from ``effort_limits: {joint: N m}``: |tau| <= limit, as
    bounds on the torque variables (`check_effort_limits`); foot_half_width m
    (|roll moment| <= half width * normal force of a full contact; the paper's foot breadth
    is 0.0915 m); ground_clearance: free contact points stay at or above the ground (off for
    the rigid-legged compass, which must scuff at mid-stance);
    swing_clearance m: with ground_clearance, a contact point that is neither held nor
    striking at a node (nor released there) stays at least this high, so no swing point
    slides along the ground at zero force; swing_clearance_ramp s: that height is required
    in full only this long (at sigma = 1) after the point's release and before its strike,
    and grows along a quarter sine over it (`gait_planner.ocp.clearance`; 0 = in full from
    the first swing node); strike_speed_max m/s (0 = off): a contact point's mean horizontal
    speed over the interval that ends at its strike stays below this (`gait_planner.ocp.
    clearance`); strike_deceleration_max m/s^2 (0 = off; with strike_speed_max): over the
    earlier intervals of the swing that ends in a strike, j intervals before the last, the
    bound is strike_speed_max + strike_deceleration_max * j * base_time_step, so the
    point slows towards the strike over its swing rather than in one interval
    (`gait_planner.ocp.clearance.approach_schedule`); joint_speed_max deg/s (0 = off):
    every joint's relative rotation over an interval stays below joint_speed_max * h_n;
    joint_speed_limits ((joint, deg/s), ...) from the option ``joint_speed_limits: {joint:
    deg/s}``: the joints named keep their own bound instead (a URDF's <limit velocity>,
    `check_joint_speed_limits`; the rest keep joint_speed_max; `joint_speed_bounds`);
    speed m/s (0 = free durations): the half cycle's mean forward speed step_length / (t_{N-1} - t_0), held by one
    equality row on sigma (`gait_planner.ocp.transcription.speed_row`); `settings_for`
    refuses a speed outside `speed_range`; speed_max m/s (0 = none): the fastest mean
    speed of this gait the scene declares plannable, a measured limit (faster requests
    found no plan, the joint speed rows or the cones most violated; no bound computable
    before building is near it: benchmarks/HISTORY.md): `speed_range` ends there;
    step_length_free: with a speed, the step length
    is the one of least cost per metre within `step_range` (`gait_planner.strategies.
    plan_free_step`; step_length is where the search starts); step_length_bounds m (lower,
    upper): the scene's range of step lengths for such a search (empty: 0.5 to 1.5 times
    the scene's step); slope deg (uphill positive) and step_height m
    (stairs, per step; negative: down): the ground (`gait_planner.model.ground`,
    `ground_of`); `settings_for` refuses a ground the scene cannot stand on or reach
    (`check_ground`); stair_segment_rows: on stairs down, each swing segment is kept above
    the stair edges' corners by the segment rows (True) or by the edge margin (False: the
    start of a cold plan, `gait_planner.ocp.solve`; `gait_planner.model.ground.Ground`);
    stairs_down_scaling_bounds, speed_scaling_bounds (lower, upper): sigma's bounds on
    stairs down, at a requested speed (empty: scaling_bounds); `settings_for` sets
    scaling_bounds to the widest of those that apply;
    phase_joint_limits: ((phase, ((angle, lo rad, hi rad), ...)), ...) from the option
    ``phase_joint_limits: {phase: {angle: [lo, hi]}}`` in degrees, ranges at the nodes that
    start an interval of that phase only; posture "paper" (the scene's declared ranges) or
    "human" (adds normative stance-knee ranges in single support,
    `gait_planner.model.posture.human_phase_limits`); twist_regularisation (units of the
    cost, per s): weight w of w sum_n h_n sum_joints (1 - (d2_parent . d2_child)^2) added to
    the cost (sin^2 of a joint's roll or yaw; the J reported excludes it); the option may
    be a number or a weight per cost, ``{kinetic_energy: 1, torque_squared: 50}`` (the
    costs differ in size by ~60 on walker3d; a cost it does not name gets 0);
    torque_smoothness (units of the cost per (N m)^2; 0 = off): weight w of w sum_n |tau_{n+1}
    - 2 tau_n + tau_{n-1}|^2 over the node torques, across the mirrored join, added to the
    cost (the J reported excludes it; `ocp.cost_terms`): no torque jumps at one node and
    back, where an inequality row touches its bound for one node (walker2d's strike rows);
    legs_apart: keep the collision spheres of different legs (`Body.collision`) leg_clearance
    m apart (`gait_planner.ocp.legs`; rows only where the scene gives two legs spheres: the
    drafts of URDF robots, walker3d; walker3d's gait sets it false: the paper's problem,
    whose optimum passes one foot through the other);
    refinements: how many times a converged plan that misses the continuous-dynamics
    certificate is planned again on a grid twice as fine, from itself
    (`gait_planner.strategies.plan_certified`, `gait_planner.ocp.refine`; 0 = never);
    start_momentum: empty for a periodic half cycle; else the problem is a transition
    (`gait_planner.ocp.transition`) whose node 0 is given with this discrete momentum
    (k,) N s, director coordinates; end_scaling, end_torque: a transition's last
    interval's sigma and the gait's torques walked as far, nodes 0..N ((N+1) nt,) N m;
    end_at_rest: a transition that stops: its nodes N-1 and N are its node N-2 (at rest).
    stairs_shift m: how far along x the stairs' edges lie from where the gait has them
    (`ground_of`): a transition from standing joins the gait that far back and carries
    the stairs with it (`gait_planner.transitions`).
    solve: how the problem is solved, not what it is (`SolveOptions`).
    """

    step_length: float
    base_time_step: float
    scaling_bounds: tuple[float, float]
    friction_coefficient: float
    cost: str
    intervals: tuple[int, ...]
    torque_regularisation: float = 1e-4
    friction_smoothing: float = 1.0
    torso_lean_max: float = 0.0
    torso_height_min: float = 0.0
    joint_limits: tuple[tuple[str, float, float], ...] = ()
    effort_limits: tuple[tuple[str, float], ...] = ()
    foot_half_width: float = 0.04575
    ground_clearance: bool = True
    swing_clearance: float = 0.0
    swing_clearance_ramp: float = 0.0
    strike_speed_max: float = 0.0
    strike_deceleration_max: float = 0.0
    joint_speed_max: float = 0.0
    joint_speed_limits: tuple[tuple[str, float], ...] = ()
    speed: float = 0.0
    speed_max: float = 0.0
    step_length_free: bool = False
    step_length_bounds: tuple[float, ...] = ()
    slope: float = 0.0
    step_height: float = 0.0
    stair_segment_rows: bool = True
    stairs_down_scaling_bounds: tuple[float, ...] = ()
    speed_scaling_bounds: tuple[float, ...] = ()
    twist_regularisation: float = 0.0
    torque_smoothness: float = 0.0
    legs_apart: bool = True
    leg_clearance: float = 0.01
    phase_joint_limits: tuple[tuple[str, tuple[tuple[str, float, float], ...]], ...] = ()
    posture: str = "paper"
    refinements: int = 2
    start_momentum: tuple[float, ...] = ()
    end_scaling: float = 0.0
    end_torque: tuple[float, ...] = ()
    end_at_rest: bool = False
    stairs_shift: float = 0.0
    solve: SolveOptions = SolveOptions()

    def with_solve(self, **changes) -> "GaitSettings":
        """These settings with their `SolveOptions` changed (e.g. max_solve_time)."""
        return dataclasses.replace(self, solve=dataclasses.replace(self.solve, **changes))

    def __post_init__(self):
        def bad(name, why):
            raise SettingsError(f"{name}: {why}")

        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            values = v if isinstance(v, tuple) else (v,)
            for x in values:
                if isinstance(x, (int, float)) and not math.isfinite(x):
                    bad(f.name, f"must be finite, got {x}")
        if self.step_length <= 0:
            bad("step_length", f"must be positive (m), got {self.step_length}")
        if self.base_time_step <= 0:
            bad("base_time_step", f"must be positive (s), got {self.base_time_step}")
        lo, hi = self.scaling_bounds
        if not 0 < lo <= hi:
            bad("scaling_bounds", f"need 0 < lower <= upper, got {self.scaling_bounds}")
        if self.friction_coefficient <= 0:
            bad("friction_coefficient", f"must be positive, got {self.friction_coefficient}")
        if self.cost not in COSTS:
            bad("cost", f"unknown cost {self.cost!r}; known: {', '.join(COSTS)}")
        if any(i < 1 for i in self.intervals):
            bad("intervals", f"every phase needs at least 1 interval, got {self.intervals}")
        if isinstance(self.refinements, bool) or not isinstance(self.refinements, int) \
                or not 0 <= self.refinements <= 3:
            bad("refinements", f"must be a whole number from 0 to 3, got {self.refinements!r}")
        try:  # degrees, validated and made a float
            object.__setattr__(self, "torso_lean_max", check_torso_lean_max(self.torso_lean_max))
        except PostureError as err:
            raise SettingsError(str(err)) from None
        for name, unit in (("step_length_bounds", " m"), ("stairs_down_scaling_bounds", ""),
                           ("speed_scaling_bounds", "")):
            bounds = getattr(self, name)
            if bounds != ():
                if (not isinstance(bounds, (list, tuple)) or len(bounds) != 2
                        or not all(isinstance(b, (int, float)) and math.isfinite(b)
                                   for b in bounds)
                        or not 0 < bounds[0] <= bounds[1]):
                    bad(name, f"need [lower, upper]{unit} with 0 < lower <= upper, got "
                              f"{bounds!r}")
                object.__setattr__(self, name, tuple(float(b) for b in bounds))
        if not isinstance(self.legs_apart, bool):
            bad("legs_apart", f"must be true or false, got {self.legs_apart!r}")
        for name in ("torque_regularisation", "friction_smoothing", "torso_height_min",
                     "foot_half_width", "swing_clearance", "swing_clearance_ramp", "strike_speed_max",
                     "strike_deceleration_max", "joint_speed_max", "speed", "speed_max",
                     "twist_regularisation", "torque_smoothness", "leg_clearance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                bad(name, f"must be a number, got {value!r}")
            if value < 0:
                bad(name, f"must be >= 0, got {value}")


def check_effort_limits(scene: Scene, limits) -> tuple[tuple[str, float], ...]:
    """((revolute joint, N m), ...) of the option ``effort_limits: {joint: N m}``: hard
    bounds |tau| <= limit on that joint's torque at every node (a URDF's <limit effort>);
    SettingsError naming an unknown or spherical joint or a limit that is not positive."""
    if not isinstance(limits, Mapping):
        raise SettingsError(f"effort_limits: need a mapping joint -> N m, got {limits!r}")
    revolute = {j.name for j in scene.joints if j.axis is not None}
    out = []
    for name, value in limits.items():
        if name not in revolute:
            raise SettingsError(f"effort_limits.{name}: not a revolute joint of scene "
                                f"{scene.name!r} (its revolute joints: {sorted(revolute)})")
        if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise SettingsError(f"effort_limits.{name}: need a positive torque (N m), "
                                f"got {value!r}")
        out.append((str(name), float(value)))
    return tuple(out)


def check_joint_speed_limits(scene: Scene, limits) -> tuple[tuple[str, float], ...]:
    """((joint, deg/s), ...) of the option ``joint_speed_limits: {joint: deg/s}``: each joint
    named keeps its relative rotation over an interval below its own limit times h_n (a
    URDF's <limit velocity>); SettingsError naming an unknown joint or a limit that is not
    positive."""
    if not isinstance(limits, Mapping):
        raise SettingsError(f"joint_speed_limits: need a mapping joint -> deg/s, got {limits!r}")
    joints = {j.name for j in scene.joints}
    out = []
    for name, value in limits.items():
        if name not in joints:
            raise SettingsError(f"joint_speed_limits.{name}: not a joint of scene "
                                f"{scene.name!r} (its joints: {sorted(joints)})")
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value) or value <= 0:
            raise SettingsError(f"joint_speed_limits.{name}: need a positive speed (deg/s), "
                                f"got {value!r}")
        out.append((str(name), float(value)))
    return tuple(out)


def joint_speed_bounds(scene: Scene, s: GaitSettings) -> tuple[float, ...]:
    """deg/s per joint of `scene` (its order; 0 = unbounded): its joint_speed_limits entry,
    else joint_speed_max."""
    own = dict(s.joint_speed_limits)
    return tuple(float(own.get(j.name, s.joint_speed_max)) for j in scene.joints)


def widened_scaling_bounds(s: GaitSettings) -> tuple[float, float]:
    """sigma's bounds for the request `s`: its scaling_bounds widened by
    stairs_down_scaling_bounds on stairs down and by speed_scaling_bounds at a requested
    speed (`settings_for` applies it to the scene's bounds)."""
    lo, hi = s.scaling_bounds
    for applies, wider in ((s.step_height < 0, s.stairs_down_scaling_bounds),
                           (s.speed > 0, s.speed_scaling_bounds)):
        if applies and wider:
            lo, hi = min(lo, wider[0]), max(hi, wider[1])
    return lo, hi


def duration_range(s: GaitSettings) -> tuple[float, float]:
    """(shortest, longest) half cycle t_{N-1} - t_0 of `s`, s: its sum(intervals) - 1
    intervals (interval N-1 is the mirror image of interval 0) of base_time_step each at
    sigma = 1, every sigma at the lower or the upper scaling bound (walker2d/3d: 0.39 s
    times 0.5 or 1.5)."""
    nominal = (sum(s.intervals) - 1) * s.base_time_step
    lo, hi = s.scaling_bounds
    return lo * nominal, hi * nominal


def step_range(s: GaitSettings) -> tuple[float, float]:
    """(shortest, longest) step length (m) a free-step search may take: the scene's
    step_length_bounds, or 0.5 to 1.5 times s.step_length."""
    if s.step_length_bounds:
        return float(s.step_length_bounds[0]), float(s.step_length_bounds[1])
    return 0.5 * s.step_length, 1.5 * s.step_length


def speed_range(s: GaitSettings) -> tuple[float, float]:
    """(slowest, fastest) mean forward speed (m/s) of a half cycle of s.step_length within
    `duration_range` (walker2d/3d at their 0.6338 m step: 1.083 to 3.250 m/s); with
    step_length_free, of any step within `step_range` (walker2d/3d: 0.598 to 4.615 m/s);
    no faster than s.speed_max if the gait declares one."""
    shortest, longest = duration_range(s)
    low, high = step_range(s) if s.step_length_free else (s.step_length, s.step_length)
    fast = high / shortest
    return low / longest, min(fast, s.speed_max) if s.speed_max > 0 else fast


def free_step_range(s: GaitSettings) -> tuple[float, float]:
    """(shortest, longest) step length (m) within `step_range` whose half cycle reaches
    s.speed within `duration_range`."""
    shortest, longest = duration_range(s)
    low, high = step_range(s)
    return max(low, s.speed * shortest), min(high, s.speed * longest)


def check_speed(s: GaitSettings, scene_name: str) -> None:
    """SettingsError if s.speed > 0 lies outside `speed_range`, naming the field, the value
    and the reachable range."""
    if s.speed > 0:
        (slow, fast), (shortest, longest) = speed_range(s), duration_range(s)
        if not slow <= s.speed <= fast:
            low, high = step_range(s)
            at = (f"step lengths within [{low:g}, {high:g}] m (the step free)"
                  if s.step_length_free else f"step_length {s.step_length:g} m")
            why = (f"a half cycle of {shortest:.4g} to {longest:.4g} s: sigma within "
                   f"scaling_bounds [{s.scaling_bounds[0]:g}, {s.scaling_bounds[1]:g}]")
            if s.speed_max > 0 and fast == s.speed_max:
                why += (f"; no faster than the gait's speed_max {s.speed_max:g} m/s, the "
                        f"fastest it was planned at, with joint_speed_max "
                        f"{s.joint_speed_max:g} deg/s (the scene file says where)")
            raise SettingsError(
                f"speed = {s.speed} m/s is outside the range scene {scene_name!r} allows at "
                f"{at}: [{slow:.4f}, {fast:.4f}] m/s ({why})")


_SOLVE_NAMES = {f.name for f in dataclasses.fields(SolveOptions)}
_OPTION_NAMES = ({f.name for f in dataclasses.fields(GaitSettings)} - {
    "step_length", "base_time_step", "scaling_bounds", "friction_coefficient", "cost",
    "intervals", "solve",
}) | _SOLVE_NAMES


# The gait option listing the requests `gait-planner prepare` plans into the warm-start
# store besides the default (`ocp.prepare_requests.anchor_requests`)
ANCHORS_OPTION = "warm_start_anchors"
def settings_for(scene: Scene, *, step_length: float | None = None, cost: str | None = None,
                 friction_coefficient: float | None = None,
                 intervals_per_phase: int | None = None,
                 max_solve_time: float | None = None, **overrides) -> GaitSettings:
    """The scene's gait settings with the given overrides (None = the scene's value).

    intervals_per_phase refines or coarsens the grid of the same problem: the base time
    step scales so that the half cycle's nominal length (the sum over the phases of
    intervals * base_time_step, at sigma = 1) stays the scene's (walker2d/3d: 8 intervals
    per phase of 10 ms; 16 per phase: 5 ms). A fixed base step would instead ask for
    another gait (24 per phase: a half cycle three times as long, J 6.99 against 20.76 on
    walker3d).

    A speed > 0 outside `speed_range` of the resulting settings is refused (`check_speed`)
    before anything is built."""
    gait = scene.gait
    if gait is None:
        raise SettingsError(f"scene {scene.name!r} declares no gait: nothing to plan")
    options = dict(gait.options)
    options.pop(ANCHORS_OPTION, None)  # `anchor_requests`: not a setting of a plan
    unknown = (set(options) | set(overrides)) - _OPTION_NAMES
    if unknown:
        raise SettingsError(
            f"unknown gait option(s) {sorted(unknown)}; known: {sorted(_OPTION_NAMES)}"
        )
    options.update(overrides)
    try:
        if "joint_limits" in options:
            options["joint_limits"] = check_joint_limits(scene, options["joint_limits"])
        if "phase_joint_limits" in options:
            options["phase_joint_limits"] = check_phase_joint_limits(
                scene, options["phase_joint_limits"])
        if "effort_limits" in options:
            options["effort_limits"] = check_effort_limits(scene, options["effort_limits"])
        if "joint_speed_limits" in options:
            options["joint_speed_limits"] = check_joint_speed_limits(
                scene, options["joint_speed_limits"])
        check_posture(scene, {"posture": options.get("posture", "paper")})
    except PostureError as err:
        raise SettingsError(str(err)) from None
    if options.get("posture") == "human":  # declared phase limits come first
        declared = tuple(options.get("phase_joint_limits", ()))
        taken = {(phase, name) for phase, limits in declared for name, _, _ in limits}
        options["phase_joint_limits"] = declared + tuple(
            (phase, kept) for phase, limits in human_phase_limits(scene)
            if (kept := tuple(l for l in limits if (phase, l[0]) not in taken)))
    if max_solve_time is not None:
        options["max_solve_time"] = max_solve_time
    solve = SolveOptions(**{name: options.pop(name) for name in _SOLVE_NAMES if name in options})
    chosen = gait.cost if cost is None else cost
    twist = options.get("twist_regularisation")
    if isinstance(twist, Mapping):  # a weight per cost, in that cost's units
        unknown = set(twist) - set(COSTS)
        if unknown:
            raise SettingsError(f"twist_regularisation: unknown cost(s) {sorted(unknown)}; "
                                f"known: {', '.join(COSTS)}")
        options["twist_regularisation"] = twist.get(chosen, 0.0)
    intervals = tuple(p.intervals for p in gait.phases)
    base_time_step = gait.base_time_step
    if intervals_per_phase is not None:  # another grid on the same half cycle
        base_time_step *= sum(intervals) / (int(intervals_per_phase) * len(intervals))
        intervals = (int(intervals_per_phase),) * len(gait.phases)
    settings = GaitSettings(
        step_length=gait.step_length if step_length is None else float(step_length),
        base_time_step=base_time_step,
        scaling_bounds=tuple(gait.scaling_bounds),
        friction_coefficient=(gait.friction_coefficient if friction_coefficient is None
                              else float(friction_coefficient)),
        cost=chosen,
        intervals=intervals,
        solve=solve,
        **options,
    )
    settings = dataclasses.replace(settings, scaling_bounds=widened_scaling_bounds(settings))
    check_speed(settings, scene.name)
    check_ground(settings, scene)
    return settings


def ground_of(scene: Scene, s: GaitSettings) -> Ground:
    """The ground of `s` on `scene` (`gait_planner.model.ground`): a stair's first edge
    midway between the front of the foot that stands at the start of the half cycle (the
    largest heel-to-toe reach, along the body's d1, from the pinned contact point: the
    first contact of the first phase's first body, `ocp.transcription`) and the back of
    the landing foot (at x = step_length), moved s.stairs_shift along x."""
    gait = scene.gait
    held = [c for c in scene.contacts if c.name in gait.phases[0].contacts]
    pinned = held[0] if held else scene.contacts[0]
    body = scene.body(pinned.body)
    reach = max(body.points[c.point][0] - body.points[pinned.point][0]
                for c in scene.contacts if c.body == pinned.body)
    return Ground(slope=s.slope, step_height=s.step_height,
                  riser=0.5 * (reach + s.step_length) + s.stairs_shift,
                  tread=s.step_length,
                  segment_rows=s.stair_segment_rows)


def leg_length(scene: Scene, contact: str) -> float:
    """Length (m) of the chain of segments from the root body to a contact point: per body
    the distance between where it hangs from its parent and where the next body (or the
    point) hangs from it (walker3d: 0.908 m from the hip to the heel, 1.048 m to the
    forefoot)."""
    c = scene.contact(contact)
    body, point, total = c.body, np.asarray(scene.body(c.body).points[c.point]), 0.0
    by_child = {j.child: j for j in scene.joints}
    while body in by_child:
        joint = by_child[body]
        total += float(np.linalg.norm(np.asarray(scene.body(body).points[joint.child_point])
                                      - point))
        body, point = joint.parent, np.asarray(scene.body(joint.parent).points[joint.parent_point])
    return total


def check_ground(s: GaitSettings, scene: Scene) -> None:
    """SettingsError, before anything is built, for a ground the scene cannot plan on:
    a slope steeper than friction can hold (tan |slope| > friction_coefficient: a foot at
    rest on it would slide), or a stair whose next tread lies beyond the legs' reach (the
    two footholds (0, 0) and (step_length, step_height) farther apart than twice the
    longest `leg_length`); a Ground that cannot be built (`Ground.__post_init__`)."""
    try:
        ground = ground_of(scene, s)
    except GroundError as err:
        raise SettingsError(str(err)) from None
    mu = s.friction_coefficient
    steepest = math.degrees(math.atan(mu))
    if abs(s.slope) > steepest:
        raise SettingsError(
            f"slope = {s.slope:g} deg is steeper than friction can hold on scene "
            f"{scene.name!r}: tan |slope| = {math.tan(math.radians(abs(s.slope))):.4g} > "
            f"friction_coefficient {mu:g}; slopes within [-{steepest:.4g}, {steepest:.4g}] deg")
    if ground.stairs:
        reach = 2.0 * max(leg_length(scene, c.name) for c in scene.contacts)
        highest = math.sqrt(max(reach**2 - s.step_length**2, 0.0))
        if abs(s.step_height) > highest:
            raise SettingsError(
                f"step_height = {s.step_height:g} m is beyond the legs' reach on scene "
                f"{scene.name!r} at step_length {s.step_length:g} m: footholds "
                f"{math.hypot(s.step_length, s.step_height):.4g} m apart, the legs reach "
                f"{reach:.4g} m; step heights within [-{highest:.4g}, {highest:.4g}] m")
