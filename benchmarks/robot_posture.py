"""How a robot's plan walks, read from its recording as a user reads it (issue #61, item 3):
the base link's pitch and roll range (/tf's world -> base link: its z axis's lean forward
and sideways, positive forward and to the right), the knee's flexion in
stance and in swing (the JointTrajectory), the step width (the held contact points on
/gait_planner/contact_forces) and every published effort's share of the URDF's limit
(`gait_planner.verify.effort_limits`), the locked joints' apart.

A knee is the one the draft's walking envelope bounds (`urdf_envelope.leg_roles`: a leg's
second joint about the base's pitch axis at the URDF's zero pose, mid-leg); its flexion is
|angle| from that zero, where these robots' legs are straight. A leg is in stance at a node where
its foot alone is on the ground (single support), in swing where it is off the ground.

    .venv/bin/python benchmarks/robot_posture.py RUN.mcap [RUN.mcap ...]   # one JSON line each
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np

def _knees(urdf: str, names, scene_text: str) -> dict[str, str]:
    """{knee joint: "l" or "r"} of the planned joints `names`: the draft's envelope's knees
    (`gait_planner.model.urdf_envelope.leg_roles`) of the legs ending in a planned joint
    with no planned joint below it, the URDF's axes taken as the walker's; a knee's side
    is that of the draft's foot contacts (foot_l..., foot_r..., the walker's left and right,
    `scene_text` the recorded scene) on a link below it (iCub's left is its URDF's -y)."""
    import pinocchio as pin
    import yaml

    from gait_planner.model.urdf_envelope import leg_roles
    from gait_planner.model.urdf_frame import WalkFrame
    from gait_planner.model.urdf_read import leg_path, revolute_axis

    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    planned = [model.getJointId(n) for n in names if model.existJointName(n)]
    feet = [j for j in planned if not set(model.subtrees[j][1:]) & set(planned)]
    frame = WalkFrame(np.eye(3), np.zeros(3), "the URDF's axes")
    side = {model.frames[model.getFrameId(c["body"])].parentJoint: c["name"][len("foot_")]
            for c in yaml.safe_load(scene_text)["contacts"]}
    out = {}
    for foot in feet:
        chain = leg_path(model, foot)
        axes = {model.names[j]: revolute_axis(model, j) for j in chain}
        knee = leg_roles(model, data, chain, axes, frame).get("knee")
        if knee:
            below = set(model.subtrees[model.getJointId(knee)])
            out[knee] = next(s for j, s in side.items() if j in below)
    return out


def posture(path: str) -> dict:
    """The measures of one recording (module docstring)."""
    from gait_planner.io.mcap_reader import read_plan_mcap
    from gait_planner.verify.effort_limits import effort_shares

    rec = read_plan_mcap(path)
    N = len(rec.times) - 1
    base = [next(t for t in frames if t.parent == "world") for frames in rec.tf]
    R = np.array([t.matrix()[:3, :3] for t in base])
    # the lean of the base link's z axis (which the envelope bounds), forward and to the
    # left in the walker's world: the same as its x axis's pitch on robots whose base x is
    # forward, and not of the wrong sign on iCub's, whose base x points backwards
    pitch = np.degrees(np.arctan2(R[:, 0, 2], R[:, 2, 2]))
    roll = np.degrees(np.arctan2(-R[:, 1, 2], R[:, 2, 2]))
    names = list(rec.joint_names)
    knees = _knees(rec.urdf, [n for n in names if n not in rec.held_joint_names],
                   rec.scene_text)
    flexion = {"stance": 0.0, "swing": 0.0}
    width = []
    for n in range(N + 1):
        held = dict(zip(rec.contact_names[n], rec.contact_points[n]))
        down = {side for side in ("l", "r")
                if any(name.startswith(f"foot_{side}") for name in rec.active_contacts[n])}
        for knee, side in knees.items():
            angle = abs(math.degrees(rec.positions[n, names.index(knee)]))
            key = "swing" if side not in down else "stance" if len(down) == 1 else None
            if key:
                flexion[key] = max(flexion[key], angle)
        left = [p for name, p in held.items() if name.startswith("foot_l")]
        right = [p for name, p in held.items() if name.startswith("foot_r")]
        if left and right:
            width.append(float(np.mean(left, axis=0)[1] - np.mean(right, axis=0)[1]))
    shares = effort_shares(rec.urdf, names, np.asarray(rec.effort))
    locked = set(rec.held_joint_names)

    def worst(pick) -> tuple[str | None, float | None]:
        chosen = {n: s for n, s in shares.items() if pick(n)}
        if not chosen:
            return None, None
        name = max(chosen, key=lambda n: chosen[n][0])
        return name, chosen[name][0]

    planned_joint, planned_share = worst(lambda n: n not in locked)
    locked_joint, locked_share = worst(lambda n: n in locked)
    return {"pelvis_pitch_deg": [float(pitch.min()), float(pitch.max())],
            "pelvis_roll_deg": [float(roll.min()), float(roll.max())],
            "knees": sorted(knees), "stance_knee_max_deg": flexion["stance"],
            "swing_knee_max_deg": flexion["swing"],
            "step_width_m": float(np.mean(width)) if width else None,
            "effort_share_planned": planned_share, "effort_share_planned_joint": planned_joint,
            "effort_share_locked": locked_share, "effort_share_locked_joint": locked_joint,
            "impulse_max_Nms": float(np.abs(rec.held_joint_impulses).max())
            if rec.held_joint_impulses.size else 0.0}


if __name__ == "__main__":
    for argument in sys.argv[1:]:
        print(json.dumps({"mcap": argument, **posture(argument)}))
