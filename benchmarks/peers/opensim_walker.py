"""The walker of a problem.json as an OpenSim Model (opensim peer env only), built with the
OpenSim API from the URDF (OpenSim reads no URDF: links' mass, centre of mass and inertia,
joints' origins and axes are parsed with xml.etree), the contact as Moco's walking examples
model it, and the conversion between OpenSim coordinates and the exchange format's
Pinocchio configurations.

* World z up: the model's gravity is problem["gravity"] (OpenSim's default is y up).
* Base: the root link hangs from ground by a PlanarJoint when every revolute axis is along y
  (walker2d, a planar walker; its frames turned so that its plane is world x-z:
  coordinates base_rz = -pitch, base_x, base_z), by a 6-coordinate CustomJoint otherwise
  (coordinates base_rx, base_ry, base_rz: body-fixed X-Y-Z Euler angles, then base_x,
  base_y, base_z; qdot = u, as Moco requires: it refuses a FreeJoint). The root link's
  origin is its centre of mass.
* Each URDF revolute/continuous joint is a PinJoint (about its frames' z) whose parent frame
  is the URDF origin turned so that z is the URDF axis and whose child frame is that turn on
  the child link: the coordinate is the URDF angle, same sign. A fixed joint to a link
  without <inertial> (a contact frame) is a PhysicalOffsetFrame on its parent body.
* Links' inertia: the URDF's, about the centre of mass in link axes, except for a link in
  problem["inertia_overrides"] (the scene's principal moments), which OpenSim takes as they
  are: Simbody does not insist on the triangle inequality.
* A CoordinateActuator (optimal force 1, so the control is the effort in N m) on every URDF
  joint, controls bounded to +-TORQUE_BOUND.
* Contact, as example2DWalking's 2D_gait.osim: a SmoothSphereHalfSpaceForce (Serrancoli's
  smoothed Hunt-Crossley with smoothed Coulomb and viscous friction; that model's stiffness,
  dissipation, transition velocity; friction problem["friction_coefficient"]) between a
  ContactSphere per contact frame (radius 0.035 m at a heel, 0.015 m elsewhere, its centre a
  radius above the contact point along the foot's z, so that the sphere touches the ground at
  the contact point when the foot is flat) and a ContactHalfSpace z <= 0 on ground. Unlike
  DMOCC's contact (perfectly plastic, points held still by a schedule, hard friction cones),
  this contact is compliant, everywhere active and the same for every foot point: the
  schedule, the placements and the impacts are the optimiser's to find, a point in
  contact penetrates and slides a little, and viscous friction may exceed mu f_n.
"""

from __future__ import annotations

import math
import os
import tempfile
import xml.etree.ElementTree as ET

import numpy as np
import opensim as osim

from benchmarks.peers import exchange

osim.Logger.removeFileSink()  # no opensim.log in the working directory (the repository)

TORQUE_BOUND = 1000.0  # N m, the actuators' control bounds (DMOCC bounds no effort)
# SmoothSphereHalfSpaceForce's parameters in Moco's example2DWalking model (2D_gait.osim)
CONTACT = {"stiffness": 3067776.0, "dissipation": 2.0, "viscous_friction": 0.5,
           "transition_velocity": 0.2, "hertz_smoothing": 300.0,
           "hunt_crossley_smoothing": 50.0}
RADIUS = {"heel": 0.035, "other": 0.015}  # m, heel / front spheres of 2D_gait.osim


# --- rotations --------------------------------------------------------------------------
# (numpy twins of gait_planner.model.rotations, which imports casadi: the opensim env has
# numpy and opensim only)
def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_matrix(rpy) -> np.ndarray:
    """URDF's rpy (fixed-axis roll, pitch, yaw): Rz(yaw) Ry(pitch) Rx(roll)."""
    return _rz(rpy[2]) @ _ry(rpy[1]) @ _rx(rpy[0])


def euler_xyz(R: np.ndarray) -> np.ndarray:
    """Body-fixed X-Y-Z Euler angles (a, b, c) of R = Rx(a) Ry(b) Rz(c) (OpenSim's
    orientation convention and its FreeJoint's rotation coordinates)."""
    b = math.asin(max(-1.0, min(1.0, R[0, 2])))
    return np.array([math.atan2(-R[1, 2], R[2, 2]), b, math.atan2(-R[0, 1], R[0, 0])])


def euler_matrix(angles) -> np.ndarray:
    """Rx(a) Ry(b) Rz(c)."""
    return _rx(angles[0]) @ _ry(angles[1]) @ _rz(angles[2])


def quat_matrix(quat) -> np.ndarray:
    """Rotation matrix of a quaternion (x, y, z, w) (normalised first)."""
    x, y, z, w = np.asarray(quat, float) / np.linalg.norm(quat)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def matrix_quat(R: np.ndarray) -> np.ndarray:
    """Quaternion (x, y, z, w), w >= 0, of a rotation matrix."""
    w = math.sqrt(max(0.0, 1.0 + R[0, 0] + R[1, 1] + R[2, 2])) / 2.0
    x = math.sqrt(max(0.0, 1.0 + R[0, 0] - R[1, 1] - R[2, 2])) / 2.0
    y = math.sqrt(max(0.0, 1.0 - R[0, 0] + R[1, 1] - R[2, 2])) / 2.0
    z = math.sqrt(max(0.0, 1.0 - R[0, 0] - R[1, 1] + R[2, 2])) / 2.0
    x = math.copysign(x, R[2, 1] - R[1, 2])
    y = math.copysign(y, R[0, 2] - R[2, 0])
    z = math.copysign(z, R[1, 0] - R[0, 1])
    q = np.array([x, y, z, w])
    return q / np.linalg.norm(q)


def _align_z(axis) -> np.ndarray:
    """A rotation taking z to the unit axis (the PinJoint frames' turn)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    z = np.array([0.0, 0.0, 1.0])
    v, c = np.cross(z, a), float(z @ a)
    if np.linalg.norm(v) < 1e-12:
        return np.eye(3) if c > 0 else _rx(math.pi)
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


def _free_to_custom(model: osim.Model) -> osim.Model:
    """The model with its FreeJoint "base" made a CustomJoint of the same coordinates
    (rotations about x, y, z, then translations along x, y, z: Moco refuses a FreeJoint,
    whose qdot is not u). Through the model's XML: this wheel's CustomJoint constructor
    crashes when called from Python."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "walker.osim")
        model.printToXML(path)
        tree = ET.parse(path)
        joint = next(j for j in tree.iter("FreeJoint") if j.get("name") == "base")
        joint.tag = "CustomJoint"
        names = [c.get("name") for c in joint.find("coordinates").findall("Coordinate")]
        transform = ET.SubElement(joint, "SpatialTransform")
        labels = ("rotation1", "rotation2", "rotation3",
                  "translation1", "translation2", "translation3")
        for k, (label, name) in enumerate(zip(labels, names)):
            axis = ET.SubElement(transform, "TransformAxis", name=label)
            ET.SubElement(axis, "coordinates").text = name
            ET.SubElement(axis, "axis").text = " ".join("1" if i == k % 3 else "0"
                                                        for i in range(3))
            function = ET.SubElement(axis, "LinearFunction", name="function")
            ET.SubElement(function, "coefficients").text = "1 0"
        tree.write(path)
        out = osim.Model(path)
    out.finalizeConnections()
    return out


def _vec3(v) -> osim.Vec3:
    return osim.Vec3(float(v[0]), float(v[1]), float(v[2]))


def _floats(text: str | None, default=(0.0, 0.0, 0.0)) -> np.ndarray:
    return np.array([float(t) for t in text.split()]) if text else np.array(default, float)


# --- the URDF -----------------------------------------------------------------------------
def parse_urdf(path: str) -> tuple[dict, list[dict]]:
    """({link: {mass, com (3,), inertia (3, 3) about the com in link axes} or None without
    <inertial>}, [joints {name, type, parent, child, xyz, R, axis}]) of a URDF file."""
    root = ET.parse(path).getroot()
    links = {}
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            links[link.get("name")] = None
            continue
        origin = inertial.find("origin")
        xyz = _floats(origin.get("xyz") if origin is not None else None)
        R = rpy_matrix(_floats(origin.get("rpy") if origin is not None else None))
        i = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
        inertia = np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]],
                            [i["ixz"], i["iyz"], i["izz"]]])
        links[link.get("name")] = {"mass": float(inertial.find("mass").get("value")),
                                   "com": xyz, "inertia": R @ inertia @ R.T}
    joints = []
    for joint in root.findall("joint"):
        origin = joint.find("origin")
        axis = joint.find("axis")
        joints.append({
            "name": joint.get("name"), "type": joint.get("type"),
            "parent": joint.find("parent").get("link"),
            "child": joint.find("child").get("link"),
            "xyz": _floats(origin.get("xyz") if origin is not None else None),
            "R": rpy_matrix(_floats(origin.get("rpy") if origin is not None else None)),
            "axis": _floats(axis.get("xyz") if axis is not None else None, (1.0, 0.0, 0.0))})
    return links, joints


class Walker:
    """problem["urdf"] as an OpenSim Model. Attributes: model (finalized, connected),
    planar, base_coordinates (names, in the order `to_exchange` reads them), joint_names
    (problem order), coordinate paths (`value_path`, `speed_path`), actuator paths
    (`actuator_path`), contact_forces {contact: SmoothSphereHalfSpaceForce name},
    spheres {contact: (body, centre in the body (3,), radius)}, frames {contact: (body,
    point in the body (3,))}."""

    def __init__(self, problem: dict, *, inertia_overrides: bool = True):
        links, joints = parse_urdf(problem["urdf"])
        self.problem = problem
        self.joint_names = list(problem["joint_names"])
        revolute = {j["name"]: j for j in joints if j["type"] in ("revolute", "continuous")}
        missing = [n for n in self.joint_names if n not in revolute]
        if missing:
            raise ValueError(f"joints {missing} are not revolute joints of the URDF")
        self.planar = all(abs(abs(revolute[n]["axis"][1]) - 1.0) < 1e-12
                          for n in self.joint_names)
        model = osim.Model()
        model.setName(f"{problem.get('scene', 'walker')}_opensim")
        model.setGravity(_vec3(problem.get("gravity", (0.0, 0.0, -9.81))))
        overrides = problem.get("inertia_overrides", {}) if inertia_overrides else {}
        bodies = {}
        for name, link in links.items():
            if link is None:
                continue
            inertia = np.diag(overrides[name]) if name in overrides else link["inertia"]
            # an override's principal moments are about the centre of mass in link axes
            bodies[name] = osim.Body(name, link["mass"], _vec3(link["com"]), osim.Inertia(
                float(inertia[0, 0]), float(inertia[1, 1]), float(inertia[2, 2]),
                float(inertia[0, 1]), float(inertia[0, 2]), float(inertia[1, 2])))
            model.addBody(bodies[name])
        root = problem["root_link"]
        if links.get(root) is None or np.linalg.norm(links[root]["com"]) > 1e-12:
            raise ValueError(f"root link {root} must carry its centre of mass at its origin")
        self.base_coordinates = self._add_base(model, bodies[root])
        self.frames: dict[str, tuple[str, np.ndarray]] = {}
        for j in joints:
            if j["type"] in ("revolute", "continuous"):
                A = _align_z(j["axis"])
                pin = osim.PinJoint(j["name"], bodies[j["parent"]], _vec3(j["xyz"]),
                                    _vec3(euler_xyz(j["R"] @ A)), bodies[j["child"]],
                                    osim.Vec3(0.0), _vec3(euler_xyz(A)))
                pin.updCoordinate().setName(j["name"])
                model.addJoint(pin)
            elif j["type"] == "fixed" and links.get(j["child"]) is None:
                self.frames[j["child"]] = (j["parent"], j["xyz"])
            else:
                raise ValueError(f"joint {j['name']} ({j['type']}) is not supported")
        for name in self.joint_names:
            actuator = osim.CoordinateActuator(name)
            actuator.setName(f"tau_{name}")
            actuator.setOptimalForce(1.0)
            actuator.setMinControl(-TORQUE_BOUND)
            actuator.setMaxControl(TORQUE_BOUND)
            model.addForce(actuator)
        self._add_contact(model, problem, links, joints)
        model.finalizeConnections()
        if not self.planar:
            model = _free_to_custom(model)
        self.model = model
        self.state = model.initSystem()

    # --- construction -------------------------------------------------------------------
    def _add_base(self, model: osim.Model, root: osim.Body) -> list[str]:
        """The root's joint to ground; its coordinates' names."""
        if self.planar:
            # PlanarJoint (rz, tx, ty in its frames' x-y plane) with both frames turned by
            # Rx(90 deg): frame x, y, z = world x, z, -y, so tx = x, ty = z, rz = -pitch
            turn = osim.Vec3(0.5 * math.pi, 0.0, 0.0)
            joint = osim.PlanarJoint("base", model.getGround(), osim.Vec3(0.0), turn,
                                     root, osim.Vec3(0.0), turn)
            names = ["base_rz", "base_x", "base_z"]
            for k, name in enumerate(names):
                joint.upd_coordinates(k).setName(name)
        else:
            joint = osim.FreeJoint("base", model.getGround(), osim.Vec3(0.0), osim.Vec3(0.0),
                                   root, osim.Vec3(0.0), osim.Vec3(0.0))
            names = ["base_rx", "base_ry", "base_rz", "base_x", "base_y", "base_z"]
            for k, name in enumerate(names):
                joint.upd_coordinates(k).setName(name)
        for k in range(joint.numCoordinates()):
            coordinate = joint.upd_coordinates(k)
            coordinate.setRangeMin(-100.0)
            coordinate.setRangeMax(100.0)
        model.addJoint(joint)
        return names

    def _add_contact(self, model: osim.Model, problem: dict, links: dict,
                     joints: list[dict]) -> None:
        """ContactHalfSpace z <= 0 on ground, a sphere and a SmoothSphereHalfSpaceForce per
        contact frame."""
        floor = osim.ContactHalfSpace(osim.Vec3(0.0), osim.Vec3(0.0, 0.5 * math.pi, 0.0),
                                      model.getGround(), "floor")
        model.addContactGeometry(floor)
        self.spheres, self.contact_forces = {}, {}
        mu = float(problem.get("friction_coefficient", 0.8))
        for contact in problem["contact_frames"]:
            body, point = self.frames[contact]
            radius = RADIUS["heel"] if "heel" in contact else RADIUS["other"]
            centre = point + np.array([0.0, 0.0, radius])
            sphere = osim.ContactSphere(radius, _vec3(centre), model.getBodySet().get(body),
                                        f"sphere_{contact}")
            model.addContactGeometry(sphere)
            force = osim.SmoothSphereHalfSpaceForce(f"contact_{contact}", sphere, floor)
            force.set_stiffness(CONTACT["stiffness"])
            force.set_dissipation(CONTACT["dissipation"])
            force.set_static_friction(mu)
            force.set_dynamic_friction(mu)
            force.set_viscous_friction(CONTACT["viscous_friction"])
            force.set_transition_velocity(CONTACT["transition_velocity"])
            force.set_hertz_smoothing(CONTACT["hertz_smoothing"])
            force.set_hunt_crossley_smoothing(CONTACT["hunt_crossley_smoothing"])
            model.addForce(force)
            self.spheres[contact] = (body, centre, radius)
            self.contact_forces[contact] = force.getName()

    # --- names --------------------------------------------------------------------------
    @property
    def coordinates(self) -> list[str]:
        """Every coordinate: the base's, then the URDF joints' in problem order."""
        return self.base_coordinates + self.joint_names

    def joint_of(self, coordinate: str) -> str:
        return "base" if coordinate in self.base_coordinates else coordinate

    def value_path(self, coordinate: str) -> str:
        return f"/jointset/{self.joint_of(coordinate)}/{coordinate}/value"

    def speed_path(self, coordinate: str) -> str:
        return f"/jointset/{self.joint_of(coordinate)}/{coordinate}/speed"

    def actuator_path(self, joint: str) -> str:
        return f"/forceset/tau_{joint}"

    # --- conversion ---------------------------------------------------------------------
    def from_exchange(self, q: np.ndarray) -> np.ndarray:
        """Coordinate values (len(coordinates),) of an exchange configuration (7 + nj,)."""
        q = np.asarray(q, float)
        R = quat_matrix(q[3:7])
        if self.planar:
            base = [-math.atan2(R[0, 2], R[0, 0]), q[0], q[2]]
        else:
            base = list(euler_xyz(R)) + list(q[:3])
        return np.concatenate([base, q[exchange.BASE_NQ:]])

    def to_exchange(self, values: np.ndarray) -> np.ndarray:
        """Exchange configuration (7 + nj,) of coordinate values."""
        values = np.asarray(values, float)
        nb = len(self.base_coordinates)
        if self.planar:
            rz, x, z = values[:3]
            position, R = np.array([x, 0.0, z]), _ry(-rz)
        else:
            position, R = values[3:6], euler_matrix(values[:3])
        return np.concatenate([position, matrix_quat(R), values[nb:]])

    def mirror_signs(self) -> dict[str, tuple[str, float]]:
        """Coordinate -> (the coordinate its mirror image holds at the next half cycle's
        start, sign): x keeps its sign (and is shifted by the step); planar, the pitch
        keeps it too; in 3D the reflection about y = 0 negates base y and the Euler angles
        about x and z (S Rx(a) Ry(b) Rz(c) S = Rx(-a) Ry(b) Rz(-c)); the joints follow
        problem["mirror"]["joint_map"]. Speeds (the coordinates' rates) follow the same map."""
        out = {}
        flip = {} if self.planar else {"base_rx": -1.0, "base_rz": -1.0, "base_y": -1.0}
        for name in self.base_coordinates:
            out[name] = (name, flip.get(name, 1.0))
        for i, j, sign in self.problem["mirror"]["joint_map"]:
            out[self.joint_names[int(i)]] = (self.joint_names[int(j)], float(sign))
        return out

    # --- kinematics ---------------------------------------------------------------------
    def set_coordinates(self, values: np.ndarray, speeds: np.ndarray | None = None):
        """The model's state at coordinate values (and speeds), realised to velocity."""
        coordinate_set = self.model.getCoordinateSet()
        for name, value in zip(self.coordinates, values):
            coordinate_set.get(name).setValue(self.state, float(value), False)
        if speeds is not None:
            for name, speed in zip(self.coordinates, speeds):
                coordinate_set.get(name).setSpeedValue(self.state, float(speed))
        self.model.realizeVelocity(self.state)
        return self.state

    def point(self, values: np.ndarray, contact: str) -> np.ndarray:
        """World position (3,) m of a contact frame's point at coordinate values."""
        self.set_coordinates(values)
        body, point = self.frames[contact]
        location = self.model.getBodySet().get(body).findStationLocationInGround(
            self.state, _vec3(point))
        return np.array([location.get(k) for k in range(3)])

    def total_mass(self) -> float:
        return float(self.model.getTotalMass(self.state))

    def contact_force(self, contact: str) -> np.ndarray:
        """The ground's force (3,) N on the body at the contact, world frame, at the
        current state (realised to velocity)."""
        force = self.model.getForceSet().get(self.contact_forces[contact])
        values = force.getRecordValues(self.state)
        return np.array([values.get(k) for k in range(3)])
