"""A plan certified as its recording will be read: `certified` runs the continuous-dynamics
certificate (`gait_planner.verify.continuous`, or on the robot's own URDF:
`gait_planner.verify.robot`) on what the result's messages will publish; `grid_defects`
says what a finer grid can cure; `certificate_metadata` puts the certificate's maxima into
a recording's metadata. Used by the strategies (`gait_planner.strategies`: refinement
after a failed certificate), the pipeline and the benchmarks.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from gait_planner.result import PlanResult


def grid_defects(result: PlanResult, cert) -> list[str]:
    """What a finer grid can cure, in sentences: the continuous-dynamics certificate's
    failures (`cert`, of `result`) and efforts that zigzag from node to node away from
    contact switches (`gait_planner.verify.physical`; walker2d and walker3d on 6 intervals
    per phase: the swing knee's effort as it reaches its 75 deg limit)."""
    from gait_planner.io.messages import node_efforts
    from gait_planner.verify.physical import effort_zigzags

    zigzags = effort_zigzags(node_efforts(result), result.active_contacts,
                             result.joint_angle_names)
    return list(cert.failures) + ([f"efforts zigzag at (angle, node) {zigzags[:4]}"]
                                  if zigzags else [])


def continuous_certificate(result: PlanResult):
    """The certificate of `certified(result)`, the result left as it is."""
    return certified(result)[1]


def certified(result: PlanResult):
    """(result, certificate): `gait_planner.verify.continuous` on what the result's messages
    will publish: the efforts of `node_efforts` and the foot wrenches of `foot_wrenches`
    (moved to the world origin), so the certificate in the metadata is the one a reader of
    the recording gets. A scene drafted from a URDF is certified on that URDF
    (`gait_planner.verify.robot`), and the result returned carries its locked joints'
    `held_efforts` and, apart, the impacts' `held_impulses` (a new result; `result` is not
    changed)."""
    from gait_planner.io.messages import foot_wrenches, node_efforts
    from gait_planner.verify.continuous import certificate
    from gait_planner.verify.mechanics import parse_scene

    scene = parse_scene(result.scene.source)
    wrenches = {body: np.zeros((result.n_nodes, 6)) for body, _ in scene.contacts.values()}
    for n in range(result.n_nodes):
        for body, r, F, M, _ in foot_wrenches(result, n):
            wrenches[body][n] = np.concatenate([F, M + np.cross(r, F)])
    if result.scene.robot is not None:  # drafted from a URDF: certified on it
        from gait_planner.verify.robot import robot_certificate, split_impulses

        cert, held = robot_certificate(
            scene, result.scene.robot.urdf, result.times, result.q, result.joint_angles,
            node_efforts(result), wrenches, result.active_contacts)
        names = list(held)
        efforts, impulses = split_impulses(
            np.array([held[n] for n in names]).T.reshape(result.n_nodes, len(names)),
            result.times, result.active_contacts)
        return dataclasses.replace(
            result, held_efforts={**result.held_efforts, **dict(zip(names, efforts.T))},
            held_impulses={**result.held_impulses, **dict(zip(names, impulses.T))}), cert
    return result, certificate(scene, result.times, result.q, node_efforts(result), wrenches,
                               result.active_contacts)


def certificate_metadata(cert) -> dict[str, str]:
    """The certificate's maxima as metadata strings (MCAP record, service response): torque
    errors relative to the peak effort away from contact switches and at them, the floating
    base's residual force (N) and moment (N m) away from switches, and the summary line."""
    return {"continuous_torque_error": repr(cert.max_torque_calm),
            "continuous_torque_error_at_switches": repr(cert.max_torque_switch),
            "continuous_base_force": repr(cert.max_force_calm),
            "continuous_base_moment": repr(cert.max_moment_calm),
            "continuous_dynamics": cert.summary()}
