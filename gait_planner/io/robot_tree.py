"""The frames of a robot's own URDF, for a scene drafted from it (`Scene.robot`).

`robot_tree(scene)` is the `KinematicTree` that /tf and /tf_static publish when the scene came
from a URDF (`gait_planner.model.urdf_import`): the URDF's own links and joints, read with
Pinocchio, so that robot_state_publisher, rviz, rerun and MuJoCo see the robot itself:

* ``world -> <base link>``: the root body's link frame (`RobotSource.links`: the base link
  in the root's COM-and-directors frame) moved with the root body.
* The planned joints, in the order of the plan's joint angles: the URDF joint's origin
  (parent link -> joint frame) and its axis, the angle as planned (the draft's angles are
  the URDF's).
* Every other joint of the URDF is fixed on /tf_static: its fixed joints as they are, its
  locked joints at their locked angle (`RobotSource.locked`; Pinocchio's placement of the
  joint at that value, so any joint type), and one frame per contact point (``<contact>``, fixed to its foot link) as
  the built-in walkers have.
"""

from __future__ import annotations

import numpy as np

from gait_planner.io.urdf import KinematicJoint, KinematicTree
from gait_planner.model.angles import angle_names
from gait_planner.model.rotations import matrix_rpy
from gait_planner.model.scene import Scene

__all__ = ["robot_tree"]


def _vec(v) -> tuple[float, float, float]:
    return tuple(float(x) for x in v)  # type: ignore[return-value]


def robot_tree(scene: Scene) -> KinematicTree:
    """The URDF frames of a drafted scene (module docstring); ValueError without its URDF."""
    import pinocchio as pin

    from gait_planner.model.urdf_import import revolute_axis

    robot = scene.robot
    if robot is None or not robot.urdf:
        raise ValueError(f"scene {scene.name!r} carries no URDF text (robot: section)")
    model = pin.buildModelFromXML(robot.urdf)  # fixed base: the base link is universe's
    index = {name: i for i, name in enumerate(angle_names(scene))}
    frames = model.frames
    q = pin.neutral(model)  # planned joints at zero, locked ones at their angle
    for name, angle in robot.locked.items():
        if not model.existJointName(name):
            raise ValueError(f"scene {scene.name!r}: the URDF has no locked joint {name!r}")
        joint = model.joints[model.getJointId(name)]
        q[joint.idx_q:joint.idx_q + joint.nq] = (np.cos(angle), np.sin(angle)) \
            if joint.nq == 2 else angle  # continuous joints: (cos, sin)
    data = model.createData()
    pin.forwardKinematics(model, data, q)  # data.liMi: each joint's placement at q

    def in_parent_link(f: int, joint_to_parent: pin.SE3) -> pin.SE3:
        return frames[frames[f].parentFrame].placement.inverse() * joint_to_parent

    moving, fixed = [], []
    for f, frame in enumerate(frames):
        if f == 0:  # "universe": the base link's parent in a fixed-base model, not a joint
            continue
        if frame.type == pin.FrameType.JOINT:
            j = frame.parentJoint
            name = model.names[j]
            origin = in_parent_link(f, data.liMi[j])
            if name in index:
                moving.append(KinematicJoint(name, frames[frame.parentFrame].name,
                                             _child_link(model, f), _vec(origin.translation),
                                             _vec(revolute_axis(model, j)), index[name],
                                             _vec(matrix_rpy(origin.rotation))))
                continue
            if name not in robot.locked:
                raise ValueError(f"scene {scene.name!r}: URDF joint {name!r} is neither "
                                 f"planned nor locked (robot.locked)")
        elif frame.type == pin.FrameType.FIXED_JOINT:
            origin = in_parent_link(f, frame.placement)
        else:
            continue
        fixed.append(KinematicJoint(frame.name, frames[frame.parentFrame].name,
                                    _child_link(model, f), _vec(origin.translation), None,
                                    None, _vec(matrix_rpy(origin.rotation))))
    moving.sort(key=lambda j: j.angle_index)
    missing = [n for n in index if n not in {j.name for j in moving}]
    if missing:
        raise ValueError(f"scene {scene.name!r}: the URDF has no joints {missing}")
    contacts = []
    for contact in scene.contacts:
        position, rotation = robot.link_pose(contact.body)
        point = np.asarray(scene.body(contact.body).points[contact.point], dtype=float)
        contacts.append(KinematicJoint(f"{contact.name}_fixed", contact.body, contact.name,
                                       _vec(rotation.T @ (point - position)), None, None))
    root = scene.root.body
    return KinematicTree(root, {root: np.zeros(3)}, tuple(moving + fixed + contacts),
                         tuple(c.name for c in scene.contacts), robot.link_pose(root))


def _child_link(model, joint_frame: int) -> str:
    """The link whose frame hangs from joint frame `joint_frame` (Pinocchio's BODY frame)."""
    return next(f.name for f in model.frames if f.parentFrame == joint_frame
                and f.name != model.frames[joint_frame].name)
