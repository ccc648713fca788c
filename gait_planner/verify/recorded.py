"""A recording's certificate against the continuous dynamics: on its scene's own model
(`gait_planner.verify.continuous.certificate`), or on the robot's URDF when the scene was
drafted from one (`gait_planner.verify.robot.robot_certificate`)."""

from __future__ import annotations

import numpy as np

from gait_planner.verify.continuous import (ContinuousCertificate, certificate, effort_names,
                                            foot_wrenches_of_recording)
from gait_planner.verify.mechanics import parse_scene
from gait_planner.verify.robot import robot_certificate


def certificate_of_recording(rec) -> ContinuousCertificate:
    """The certificate of a decoded recording (`gait_planner.io.mcap_reader.RecordedPlan`)."""
    scene = parse_scene(rec.scene_text)
    names = list(rec.joint_names)
    missing = [n for n in effort_names(scene) if n not in names]
    if missing:
        raise ValueError(f"the JointTrajectory has no efforts {missing}")
    columns = [names.index(n) for n in effort_names(scene)]
    efforts = np.asarray(rec.effort, dtype=float)[:, columns]
    wrenches, source = foot_wrenches_of_recording(rec, scene)
    if scene.robot_root is not None:  # drafted from a URDF: certified on it
        return robot_certificate(scene, rec.urdf, rec.times, rec.q,
                                 np.asarray(rec.positions, dtype=float)[:, columns], efforts,
                                 wrenches, rec.active_contacts, source)[0]
    return certificate(scene, rec.times, rec.q, efforts, wrenches, rec.active_contacts, source)
