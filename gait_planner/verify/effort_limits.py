"""Every published effort against the robot's own limits (issue #61).

A plan of a robot drafted from its URDF publishes an effort for every joint of the URDF:
the planned ones (their torques, bounded in the plan by the draft's ``effort_limits``)
and the locked ones (what holds them: `gait_planner.verify.robot`, bounded in the plan by
``robot.holds``, `gait_planner.ocp.held_efforts`). A controller feeds them forward, so
each must be within the URDF's ``<limit effort>``. The limits are read here from the
recording's /robot_description, the text the user published, not from the draft; an
effort above its limit by more than LIMIT_TOLERANCE fails, naming the joint, the node and
the effort it would need. The impulses of impacts are published apart
(MultibodyState.held_joint_impulses, N m s) and are not efforts.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LIMIT_TOLERANCE", "effort_limit_failures", "effort_shares"]

# relative: the plan bounds the locked joints' efforts by its own discretisation of what
# holds them; the published ones are Pinocchio's central differences on the URDF, which
# agreed with it to 0.004 N m (0.01 % of G1's 35 N m waist limit, 2026-12-06)
LIMIT_TOLERANCE = 1e-3


def effort_shares(urdf: str, names, effort: np.ndarray) -> dict[str, tuple[float, int, float]]:
    """{joint: (largest |effort| / limit, its node, limit N m)} of every published joint
    (`names`, efforts (N+1, n) N m) that the URDF text `urdf` gives a positive effort
    limit; {} for an empty URDF."""
    if not urdf:
        return {}
    import pinocchio as pin  # noqa: PLC0415 - the verifier's dependency

    model = pin.buildModelFromXML(urdf)
    out = {}
    for i, name in enumerate(names):
        if not model.existJointName(name):
            continue
        joint = model.joints[model.getJointId(name)]
        if joint.nv != 1:
            continue
        limit = float(model.effortLimit[joint.idx_v])
        if 0.0 < limit < 1e10 and effort.shape[0]:
            column = np.abs(np.asarray(effort[:, i], dtype=float))
            node = int(column.argmax())
            out[name] = (float(column[node]) / limit, node, limit)
    return out


def effort_limit_failures(shares: dict[str, tuple[float, int, float]]) -> list[str]:
    """One failure per joint whose share exceeds 1 + LIMIT_TOLERANCE."""
    return [f"joint {name} needs {share * limit:.4g} N m at node {node}, beyond its URDF "
            f"effort limit {limit:g} N m ({100 * share:.1f} %)"
            for name, (share, node, limit) in sorted(shares.items(), key=lambda kv: -kv[1][0])
            if share > 1.0 + LIMIT_TOLERANCE]
