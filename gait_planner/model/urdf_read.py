"""Reading a URDF for the importer (`gait_planner.model.urdf_import`): the description
parsed by Pinocchio on a free-flyer with its collision geometry (`read_urdf`; its visual
geometry on demand, `visual_geometry`; Collada ``Y_UP`` meshes turned to z up in both,
`urdf_contacts.turn_y_up`), the two feet (`find_feet`), a leg's joints
(`leg_path`) and a revolute joint's axis (`revolute_axis`). UrdfError names what is
refused: XML that is not well formed, a closed chain, a joint naming a missing link, a
mesh that cannot be read, fewer than two feet, feet sharing joints, a leg joint that is
not revolute.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Sequence

import numpy as np

from gait_planner.model.urdf_contacts import turn_y_up
from gait_planner.model.urdf_errors import UrdfError

__all__ = ["find_feet", "leg_path", "read_urdf", "revolute_axis", "visual_geometry"]


def _pin():
    import pinocchio as pin  # noqa: PLC0415 - only the importer needs it at import time

    return pin


def _check_tree(urdf_text: str) -> None:
    """UrdfError naming the link of a closed chain (a link that is the child of two joints:
    Pinocchio's own error then names neither) or a joint whose parent link is missing."""
    try:
        robot = ET.fromstring(urdf_text)
    except ET.ParseError as error:
        raise UrdfError(f"the URDF is not well-formed XML: {error}") from None
    parent_of: dict[str, str] = {}
    links = {link.get("name") for link in robot.findall("link")}
    for joint in robot.findall("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        name = joint.get("name")
        if parent is None or child is None:
            raise UrdfError(f"joint {name!r} lacks its <parent> or <child>")
        p, c = parent.get("link"), child.get("link")
        if c in parent_of:
            raise UrdfError(f"link {c!r} is the child of two joints ({parent_of[c]!r} and "
                            f"{name!r}): a closed chain, which the planner's tree of bodies "
                            f"cannot express")
        parent_of[c] = name
        for link in (p, c):
            if link not in links:
                raise UrdfError(f"joint {name!r} names the link {link!r}, which the URDF "
                                f"does not declare")


def read_urdf(urdf_text: str, package_dirs: Sequence[str]):
    pin = _pin()
    _check_tree(urdf_text)
    try:
        model = pin.buildModelFromXML(urdf_text, pin.JointModelFreeFlyer())
    except Exception as error:  # Pinocchio raises ValueError/RuntimeError with urdfdom's text
        raise UrdfError(f"the URDF cannot be read as a tree of links: {error}") from None
    try:
        geometry = pin.buildGeomFromUrdfString(model, urdf_text, pin.GeometryType.COLLISION,
                                               package_dirs=list(package_dirs))
    except Exception as error:
        raise UrdfError(f"the URDF's collision geometry cannot be read (a mesh file not "
                        f"found or not readable; give its folder with --package-dir): "
                        f"{error}") from None
    return model, turn_y_up(geometry)


def _joint_of_link(model, link: str) -> int:
    if not model.existFrame(link):
        raise UrdfError(f"no link {link!r} in the URDF")
    return int(model.frames[model.getFrameId(link)].parentJoint)


def leg_path(model, joint: int) -> list[int]:
    """The joint ids from the floating base (exclusive) to `joint`, hip first."""
    out = []
    while joint > 1:
        out.append(joint)
        joint = int(model.parents[joint])
    return out[::-1]


def visual_geometry(model, urdf_text: str, package_dirs: Sequence[str]):
    """The URDF's visual geometry (feet without collision geometry read it), or None when
    it cannot be read."""
    pin = _pin()
    try:
        visual = pin.buildGeomFromUrdfString(model, urdf_text, pin.GeometryType.VISUAL,
                                             package_dirs=list(package_dirs))
    except Exception:  # a visual mesh not found: the feet's frames remain
        return None
    return turn_y_up(visual)


def find_feet(model, feet: Sequence[str] | None) -> tuple[int, int]:
    """The feet's joint ids: the given links (LEFT, RIGHT), or the two lowest leaf joints
    (left and right told by `gait_planner.model.urdf_frame`)."""
    if feet:
        if len(feet) != 2:
            raise UrdfError(f"--feet takes two links LEFT,RIGHT, got {list(feet)}")
        ids = [_joint_of_link(model, f) for f in feet]
        for link, joint in zip(feet, ids):
            if joint <= 1:
                raise UrdfError(f"foot link {link!r} is fixed to the floating base, not at "
                                f"the end of a leg")
        return ids[0], ids[1]
    pin = _pin()
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    leaves = [j for j in range(2, model.njoints) if j not in set(model.parents[2:])]
    if len(leaves) < 2:
        raise UrdfError(f"no two feet found: the tree has {len(leaves)} leaf joint(s) below "
                        f"the base; name the feet with --feet LEFT_LINK,RIGHT_LINK")
    left, right = sorted(leaves, key=lambda j: data.oMi[j].translation[2])[:2]
    if set(leg_path(model, left)) & set(leg_path(model, right)):
        raise UrdfError(f"the two lowest leaves {model.names[left]!r} and "
                        f"{model.names[right]!r} share joints; name the feet with --feet")
    return left, right


def revolute_axis(model, joint: int) -> np.ndarray:
    """The unit axis (joint frame) of a 1-dof revolute joint; UrdfError otherwise."""
    joint_model = model.joints[joint]
    name = model.names[joint]
    data = joint_model.createData()
    if joint_model.nv != 1:
        raise UrdfError(f"joint {name!r} ({joint_model.shortname()}) has {joint_model.nv} "
                        f"degrees of freedom; a leg's joints must be revolute or continuous")
    q = np.zeros(joint_model.nq)
    q[0] = 1.0 if joint_model.nq == 2 else 0.0  # continuous joints: (cos, sin)
    joint_model.calc(data, q)
    motion = np.array(data.S).reshape(6, -1)[:, 0]  # (linear, angular)
    if np.linalg.norm(motion[3:]) < 0.5 or np.linalg.norm(motion[:3]) > 1e-12:
        raise UrdfError(f"joint {name!r} ({joint_model.shortname()}) is not revolute: a "
                        f"prismatic or helical joint inside a leg cannot be planned")
    return motion[3:] / np.linalg.norm(motion[3:])
