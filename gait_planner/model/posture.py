"""Posture options of a gait, checked: the one place that says what a valid posture is.

A scene's ``gait.options`` may declare the posture a walker keeps (docs/user-guide.md,
"Gait options"); both angle options are in degrees:

* ``joint_limits: {angle name: [lower, upper]}``: any joint angle of the scene
  (`gait_planner.model.angles` convention, e.g. ``knee_r: [0, 75]``), each bound within
  [-180, 180], lower < upper, upper - lower < 180 (the margins of
  `gait_planner.ocp.posture` are exact only then), a roll range within [-90, 90];
* ``torso_lean_max``: the root body's d3 (a robot drafted from a URDF: its base link's z
  axis) within this angle of vertical, in [0, 90) (0 = off).

The scene loader checks them when a scene with a gait is loaded, and
`gait_planner.ocp.settings` when a request overrides them: both call the functions here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from gait_planner.model.scene import JointType, Scene

POSTURE_OPTIONS = ("joint_limits", "torso_lean_max")


class PostureError(ValueError):
    """A posture option that cannot be planned: `option` is its key path inside the gait
    options (e.g. "joint_limits.knee_r"), `reason` what is wrong."""

    def __init__(self, option: str, reason: str):
        self.option, self.reason = option, reason
        super().__init__(f"{option}: {reason}")


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def roll_angles(scene: Scene) -> frozenset[str]:
    """Names of the roll angles (the middle angle of each spherical joint)."""
    return frozenset(j.angle_names[1] for j in scene.joints if j.type is JointType.SPHERICAL)


def check_joint_limits(scene: Scene, limits) -> tuple[tuple[str, float, float], ...]:
    """Validated ((angle name, lo rad, hi rad), ...) from {name: (lo deg, hi deg)}."""
    if not isinstance(limits, Mapping):
        raise PostureError("joint_limits", f"need a mapping {{angle name: [lower, upper]}} "
                                           f"in degrees, got {type(limits).__name__}")
    names = [n for j in scene.joints for n in j.angle_names]
    rolls = roll_angles(scene)
    out = []
    for name, bounds in limits.items():
        key = f"joint_limits.{name}"
        if name not in names:
            raise PostureError("joint_limits", f"{name!r} is not a joint angle of scene "
                                               f"{scene.name!r}; known: {', '.join(names)}")
        if isinstance(bounds, (str, bytes, Mapping)) or not hasattr(bounds, "__len__") \
                or len(bounds) != 2 or not all(_is_number(v) for v in bounds):
            raise PostureError(key, f"need [lower, upper] in degrees, got {bounds!r}")
        lo, hi = (float(v) for v in bounds)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi and hi - lo < 180):
            raise PostureError(key, f"need finite lower < upper within 180 deg, got [{lo}, {hi}]")
        if not -180 <= lo < hi <= 180:
            raise PostureError(key, f"bounds must lie in [-180, 180] deg, got [{lo}, {hi}]")
        if name in rolls and not -90 <= lo < hi <= 90:
            raise PostureError(key, f"a roll range must lie in [-90, 90] deg, got [{lo}, {hi}]")
        out.append((name, math.radians(lo), math.radians(hi)))
    return tuple(out)


def check_phase_joint_limits(scene: Scene, value) -> tuple[tuple[str, tuple], ...]:
    """Validated ((phase name, ((angle, lo rad, hi rad), ...)), ...) from
    {phase name: {angle name: [lo deg, hi deg]}}: ranges that hold only at the nodes that
    start an interval of that phase (e.g. a straight stance knee in single support)."""
    if not isinstance(value, Mapping):
        raise PostureError("phase_joint_limits", "need a mapping {phase: {angle name: "
                                                 f"[lower, upper]}}, got {type(value).__name__}")
    phases = [p.name for p in scene.gait.phases] if scene.gait else []
    out = []
    for phase, limits in value.items():
        if phase not in phases:
            raise PostureError("phase_joint_limits", f"{phase!r} is not a phase of scene "
                                                     f"{scene.name!r}; known: {', '.join(phases)}")
        try:
            out.append((phase, check_joint_limits(scene, limits)))
        except PostureError as err:
            raise PostureError(f"phase_joint_limits.{phase}.{err.option}", err.reason) from None
    return tuple(out)


POSTURES = ("paper", "human")
# Normative human walking (Perry & Burnfield, Gait Analysis, 2nd ed., ch. 7; Winter, The
# Biomechanics and Motor Control of Human Gait): the stance knee flexes to about 15-20 deg
# after heel strike and extends to about 5 deg in mid and late stance.
HUMAN_STANCE_KNEE = (0.0, 20.0)  # deg


def human_phase_limits(scene: Scene) -> tuple[tuple[str, tuple], ...]:
    """`posture: human` as phase joint limits: in every single-support phase (the held
    contacts on one body), each revolute joint strictly inside the chain from that body to
    the root (not the one at the stance body, the ankle, nor the one at the root, the hip:
    the stance knee) within HUMAN_STANCE_KNEE. A scene whose chain has no such joint (the
    compass: stance leg and hip only) gets none."""
    parent_joint = {j.child: j for j in scene.joints}
    body_of = {c.name: c.body for c in scene.contacts}
    out = []
    for phase in scene.gait.phases:
        bodies = {body_of[c] for c in phase.contacts}
        if len(bodies) != 1:
            continue
        stance = body = bodies.pop()
        names = []
        while body in parent_joint:
            joint = parent_joint[body]
            inner = joint.child != stance and joint.parent in parent_joint
            if inner and joint.type is JointType.REVOLUTE:
                names.append(joint.angle_names[0])
            body = joint.parent
        if names:
            lo, hi = (math.radians(v) for v in HUMAN_STANCE_KNEE)
            out.append((phase.name, tuple((n, lo, hi) for n in names)))
    return tuple(out)


def check_torso_lean_max(value) -> float:
    """The validated torso_lean_max in degrees: a number in [0, 90) (0 = off)."""
    if not _is_number(value):
        raise PostureError("torso_lean_max", f"must be a number of degrees, got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and 0 <= value < 90):
        raise PostureError("torso_lean_max", f"must be in [0, 90) degrees, got {value}")
    return value


def check_posture(scene: Scene, options: Mapping[str, Any]) -> None:
    """Check the posture entries among a gait's `options` (others are left alone)."""
    if "joint_limits" in options:
        check_joint_limits(scene, options["joint_limits"])
    if "torso_lean_max" in options:
        check_torso_lean_max(options["torso_lean_max"])
    if "phase_joint_limits" in options:
        check_phase_joint_limits(scene, options["phase_joint_limits"])
    if options.get("posture", "paper") not in POSTURES:
        raise PostureError("posture", f"unknown posture {options['posture']!r}; known: "
                                      f"{', '.join(POSTURES)}")
