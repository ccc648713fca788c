"""Small synthetic bipeds as URDF texts, for the importer's and the outputs' tests."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from gait_planner.model.rotations import matrix_rpy, rpy_matrix

AXES = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1", "-y": "0 -1 0"}


def _inertial(mass: float, rpy: str, xyz: str,
              moments=(0.02, 0.03, 0.04)) -> str:
    return (f'<inertial><origin xyz="{xyz}" rpy="{rpy}"/><mass value="{mass}"/>'
            f'<inertia ixx="{moments[0]}" iyy="{moments[1]}" izz="{moments[2]}" ixy="0" '
            f'ixz="0" iyz="0"/></inertial>')


def biped(tilt: float = 0.2, knee_axis: str = "y", foot_geometry: str | None = None,
          knee_type: str = "revolute", knee_mass: float = 1.0, base_y: float = 0.0,
          right_knee_mass: float | None = None, waist_axis: str = "z",
          arm_com: str = "0 0 0.2", waist_effort: float = 10.0,
          velocities: dict[str, float] | None = None) -> str:
    """A three-joint-per-leg biped whose hip-roll frame is pitched by `tilt` (as G1's) and
    whose feet carry `foot_geometry` (default: four small spheres at the sole's corners);
    its waist (locked by a draft) turns about `waist_axis`, its arm's centre of mass at
    `arm_com` from it; every leg joint's velocity limit 20 rad/s but those `velocities`
    names (joint -> rad/s)."""
    speed = {f"{side}_{j}_joint": 20.0 for side in ("left", "right")
             for j in ("hip_roll", "hip_pitch", "knee", "ankle")} | dict(velocities or {})
    sphere = '<collision><origin xyz="{x} {y} -0.06"/><geometry><sphere radius="0.005"/>' \
             '</geometry></collision>'
    feet = foot_geometry if foot_geometry is not None else "".join(
        sphere.format(x=x, y=y) for x in (-0.05, 0.12) for y in (-0.03, 0.03))
    legs = []
    for side, sign in (("left", 1.0), ("right", -1.0)):
        mass = knee_mass if side == "left" or right_knee_mass is None else right_knee_mass
        legs.append(f"""
  <link name="{side}_hip_link">{_inertial(1.5, xyz=f"0 {0.02 * sign} -0.02", rpy=f"{0.1 * sign} -0.2 {0.3 * sign}")}</link>
  <link name="{side}_thigh_link">{_inertial(2.0, xyz="0 0 -0.15", rpy=f"{0.1 * sign} 0.1 0")}</link>
  <link name="{side}_shin_link">{_inertial(mass, xyz="0 0 -0.15", rpy=f"{0.1 * sign} -0.2 {0.3 * sign}")}</link>
  <link name="{side}_foot_link">{_inertial(0.5, xyz="0.03 0 -0.04", rpy=f"0 0.05 {0.2 * sign}")}{feet}</link>
  <joint name="{side}_hip_roll_joint" type="revolute">
    <parent link="base_link"/><child link="{side}_hip_link"/>
    <origin xyz="0 {0.1 * sign} -0.1" rpy="0 {-tilt} 0"/><axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.5" effort="80" velocity="{speed[f'{side}_hip_roll_joint']}"/></joint>
  <joint name="{side}_hip_pitch_joint" type="revolute">
    <parent link="{side}_hip_link"/><child link="{side}_thigh_link"/>
    <origin xyz="0 {0.05 * sign} -0.05" rpy="0 {tilt} 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="100" velocity="{speed[f'{side}_hip_pitch_joint']}"/></joint>
  <joint name="{side}_knee_joint" type="{knee_type}">
    <parent link="{side}_thigh_link"/><child link="{side}_shin_link"/>
    <origin xyz="0 0 -0.3"/><axis xyz="{AXES[knee_axis]}"/>
    <limit lower="-0.1" upper="2.5" effort="120" velocity="{speed[f'{side}_knee_joint']}"/></joint>
  <joint name="{side}_ankle_joint" type="revolute">
    <parent link="{side}_shin_link"/><child link="{side}_foot_link"/>
    <origin xyz="0 0 -0.3"/><axis xyz="0 1 0"/>
    <limit lower="-0.8" upper="0.6" effort="40" velocity="{speed[f'{side}_ankle_joint']}"/></joint>""")
    return f"""<?xml version="1.0"?>
<robot name="biped">
  <link name="base_link">{_inertial(10.0, xyz=f"0 {base_y} 0.1", rpy="0 0 0", moments=(0.3, 0.2, 0.15))}</link>
  <link name="arm_link">{_inertial(1.0, xyz=arm_com, rpy="0 0 0")}</link>
  <joint name="waist_joint" type="revolute"><parent link="base_link"/><child link="arm_link"/>
    <origin xyz="0 0 0.2"/><axis xyz="{AXES[waist_axis]}"/><limit lower="-1" upper="1" effort="{waist_effort}" velocity="5"/></joint>
  {"".join(legs)}
</robot>"""


def turn_link_frames(urdf: str, turns: dict[str, np.ndarray],
                     flipped: tuple[str, ...] = ()) -> str:
    """The same robot with the frames of the links named in `turns` turned: link L's new
    frame is its old one times turns[L] (3, 3), every joint origin, axis, inertial and
    geometry origin rewritten to match, so the links, joints and masses stay where they
    are (a turned base link turns the whole robot in the URDF's world: Rz(pi) makes its x
    point backwards, as iCub's). The joints named in `flipped` turn about the opposite
    axis (their ranges negated), as a right joint of iCub does against its left twin."""
    robot = ET.fromstring(urdf)
    eye = np.eye(3)
    for joint in robot.findall("joint"):
        Qp = turns.get(joint.find("parent").get("link"), eye)
        Qc = turns.get(joint.find("child").get("link"), eye)
        _set_origin(joint, lambda p, R: (Qp.T @ p, Qp.T @ R @ Qc))
        axis = joint.find("axis")
        if axis is not None:
            sign = -1.0 if joint.get("name") in flipped else 1.0
            axis.set("xyz", _text(sign * Qc.T @ _vector(axis.get("xyz"))))
        limit = joint.find("limit")
        if joint.get("name") in flipped and limit is not None:
            lower, upper = limit.get("lower"), limit.get("upper")
            limit.set("lower", repr(-float(upper)))
            limit.set("upper", repr(-float(lower)))
    for link in robot.findall("link"):
        Q = turns.get(link.get("name"))
        if Q is not None:
            for part in link.findall("inertial") + link.findall("collision") + \
                    link.findall("visual"):
                _set_origin(part, lambda p, R, Q=Q: (Q.T @ p, Q.T @ R))
    return ET.tostring(robot, encoding="unicode")


def _set_origin(element, change) -> None:
    origin = element.find("origin")
    if origin is None:
        origin = ET.SubElement(element, "origin")
    p, R = change(_vector(origin.get("xyz", "0 0 0")),
                  rpy_matrix(_vector(origin.get("rpy", "0 0 0"))))
    origin.set("xyz", _text(p))
    origin.set("rpy", _text(matrix_rpy(R)))


def _vector(text: str) -> np.ndarray:
    return np.array([float(v) for v in text.split()])


def _text(v) -> str:
    return " ".join(repr(float(x)) for x in v)
