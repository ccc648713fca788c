"""The walking envelope of a drafted robot: an upright walk by default (issue #61, item 3).

The minimal-energy gait of a robot's legs alone walks where the draft lets it: Unitree
G1's first drafts walked with the pelvis pitched 26-30 deg and the knees at 71-89 deg, a
crouch no robot walks in (human walking keeps the stance knee within about 20 deg in
single support; humanoids walk with 20-40 deg). The draft therefore writes, from the
robot's own geometry at the URDF's zero pose (base level, legs straight):

* ``torso_lean_max: UPRIGHT_DEG``: the base link's z axis within 10 deg of vertical
  (`gait_planner.ocp.path_rows`: pitch and roll alike);
* the hip yaw joints (the first joint of a leg turning about the vertical) within
  +-HIP_YAW_DEG, so that the feet point where the robot walks;
* the knees (the second joint of a leg turning about the base's pitch axis, after the hip
  pitch, at least a quarter of the leg up from its last joint: not an ankle) flexed at most STANCE_KNEE_DEG in the single-support phases where their leg is
  the stance leg (``phase_joint_limits``), either way from the zero pose (and within the
  URDF's range), whatever the URDF's sign.

`leg_roles` names the joints by their world axes, not their names, so any axis convention
and naming works; a leg without such a joint gets no row for it. It also names the hip and
ankle pitch joints, whose speed limits set the draft's pace (`gait_planner.model.urdf_pace`).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["UPRIGHT_DEG", "HIP_YAW_DEG", "STANCE_KNEE_DEG", "leg_roles", "walking_envelope"]

UPRIGHT_DEG = 10.0  # base link z axis from vertical
HIP_YAW_DEG = 15.0  # hip yaw from the zero pose
STANCE_KNEE_DEG = 45.0  # stance knee flexion from the straight zero pose, single support
_ALONG = 0.9  # |component| of a joint's world axis along x, y or z: a roll, pitch, yaw joint
_MID_LEG = 0.25  # a knee is at least this share of the hip's height above the last joint


def leg_roles(model, data, chain: Sequence[int], axes: dict[str, np.ndarray],
              frame) -> dict:
    """{"hip_yaw": joint, "knee": joint, "sweep": [joints]} of one leg: `chain` its joint
    ids from the base (Pinocchio model, forward kinematics in `data` at the draft pose),
    `axes` the joints' unit axes in their own frames (`urdf_read.revolute_axis`), `frame`
    the walker's world in the URDF's (`gait_planner.model.urdf_frame.WalkFrame`: forward,
    left, up). "sweep": the leg's pitch joints but the knee (hip and ankle pitch: those
    that turn through the stride angle, `gait_planner.model.urdf_pace`)."""
    world = {j: frame.W.T @ data.oMi[j].rotation @ axes[model.names[j]] for j in chain}
    height = {j: float(frame.W[:, 2] @ (data.oMi[j].translation
                                         - data.oMi[chain[-1]].translation)) for j in chain}
    pitch = [j for j in chain if abs(world[j][1]) > _ALONG]
    if len(pitch) < 2 or height[pitch[1]] < _MID_LEG * height[chain[0]]:
        return {"sweep": [model.names[j] for j in pitch]}  # no knee: pitch[1] is an ankle
    knee = pitch[1]
    yaw = [j for j in chain[:chain.index(knee)] if abs(world[j][2]) > _ALONG]
    return {"knee": model.names[knee], **({"hip_yaw": model.names[yaw[0]]} if yaw else {}),
            "sweep": [model.names[j] for j in pitch if j != knee]}


def walking_envelope(roles: dict[str, dict[str, str]], limits: dict[str, list[float]],
                     stance: dict[str, Sequence[str]]) -> dict:
    """The gait options of the envelope: roles {"l"/"r": `leg_roles`}, limits {joint: [lo,
    hi] deg} (the draft's joint_limits, narrowed here in place for the hip yaws), stance
    {"l"/"r": the single-support phases whose stance leg it is}."""
    phases: dict[str, dict[str, list[float]]] = {}
    for side, role in roles.items():
        if "hip_yaw" in role and role["hip_yaw"] in limits:
            lo, hi = limits[role["hip_yaw"]]
            limits[role["hip_yaw"]] = [max(lo, -HIP_YAW_DEG), min(hi, HIP_YAW_DEG)]
        knee = role.get("knee")
        if knee in limits:
            lo, hi = limits[knee]
            bent = [max(lo, -STANCE_KNEE_DEG), min(hi, STANCE_KNEE_DEG)]
            if bent[0] < bent[1]:
                for phase in stance.get(side, ()):
                    phases.setdefault(phase, {})[knee] = bent
    return {"torso_lean_max": UPRIGHT_DEG, **({"phase_joint_limits": phases} if phases else {})}
