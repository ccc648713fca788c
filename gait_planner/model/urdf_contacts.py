"""A drafted robot's contact points, from each foot's geometry at the draft pose
(`gait_planner.model.urdf_import`).

`sole_points` takes a foot's lowest points: a sphere's lowest point, a box's lowest corners,
a capsule's or cylinder's lowest points at its two ends, a mesh's lowest vertices, of its
collision geometry; a foot without any reads its visual geometry (Alexander's feet have
only visual meshes); a foot without either takes the links fixed to it without mass
(`gait-planner urdf`'s contact frames) as its points. A Collada mesh (.dae) declared
``Y_UP`` is turned to z up as its authors' viewers turn it (coal, which reads the meshes
for Pinocchio, keeps the file's axes: iCub's feet would point sideways): `turn_y_up` turns
such a mesh's placement in a Pinocchio geometry model (the importer's, `urdf_read`), so
everything placed by the model (soles, the lower legs' spheres, `urdf_collision`) sees it
turned; `read_mesh` turns the vertices of a file read alone (MuJoCo's feet).

`foot_contacts` groups them in the walker's frame (`gait_planner.model.urdf_frame`): with
points ahead and behind the sole's middle, the rear ones make the ``heel`` and the front
ones the ``forefoot`` (each the centre of its group: two points per foot, as walker3d's
foot, whose full contact also holds the roll about the heel-forefoot line); a sole shorter
than 2 cm makes a point foot (the compass's phases).
"""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import numpy as np

from gait_planner.model.urdf_errors import UrdfError

__all__ = ["foot_contacts", "read_mesh", "sole_points", "turn_y_up"]

_SOLE = 1e-3  # m: vertices this close above the lowest one are on the sole
_POINT_FOOT = 0.02  # m: a sole shorter than this along forward is a point
_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # Collada Y_UP -> Z_UP


def sole_points(model, geometries, data, foot: int, link: str) -> tuple[np.ndarray, np.ndarray]:
    """(points in the foot's joint frame (n, 3), the same in the URDF world (n, 3)), m, of
    the sole of foot joint `foot` (carrying `link`) at the pose of `data`; `geometries`:
    Pinocchio geometry models in order of preference (collision, then visual)."""
    import pinocchio as pin  # noqa: PLC0415 - only the importer needs it at import time

    lowest: list[np.ndarray] = []
    for geometry in geometries:
        for obj in geometry.geometryObjects:
            if obj.parentJoint == foot:
                lowest += _lowest_points(obj, data.oMi[foot])
        if lowest:
            break
    lowest = lowest or [np.array(f.placement.translation) for f in model.frames
                        if f.parentJoint == foot and f.type == pin.FrameType.BODY
                        and f.name != link and f.inertia.mass == 0]
    if not lowest:
        raise UrdfError(f"foot link {link!r} has no collision or visual geometry and no "
                        f"massless links fixed to it: its contact points come from its "
                        f"spheres, boxes or meshes, or else from such links")
    world = np.array([data.oMi[foot].act(p) for p in lowest])
    on_sole = world[:, 2] <= world[:, 2].min() + _SOLE
    return np.array(lowest)[on_sole], world[on_sole]


def foot_contacts(soles: dict, frame) -> tuple[dict, dict[int, float]]:
    """(foot joint -> {"heel": p, "forefoot": p} or {"foot": p}, joint-frame points (3,) m;
    foot joint -> the sole's half width (its points' spread along left) m, flat feet with a
    width only) from `soles` (foot joint -> `sole_points`) in `frame`
    (`gait_planner.model.urdf_frame.WalkFrame`)."""
    out, half_widths = {}, {}
    for foot, (pts, world) in soles.items():
        walk = np.array([frame.point(p) for p in world])
        if np.ptp(walk[:, 0]) < _POINT_FOOT:
            out[foot] = {"foot": pts.mean(axis=0)}
            continue
        middle = 0.5 * (walk[:, 0].min() + walk[:, 0].max())
        out[foot] = {"heel": pts[walk[:, 0] < middle].mean(axis=0),
                     "forefoot": pts[walk[:, 0] >= middle].mean(axis=0)}
        if np.ptp(walk[:, 1]) > 0:
            half_widths[foot] = 0.5 * float(np.ptp(walk[:, 1]))
    return out, half_widths


def _lowest_points(obj, oMi) -> list[np.ndarray]:
    """The lowest points at the zero pose (joint frame) of one geometry object."""
    geom, placement = obj.geometry, obj.placement
    kind = type(geom).__name__
    down = placement.rotation.T @ oMi.rotation.T @ np.array([0.0, 0.0, -1.0])  # local
    if kind == "Sphere":
        return [placement.act(geom.radius * down)]
    if kind in ("Capsule", "Cylinder"):
        ends = [np.array([0.0, 0.0, s * geom.halfLength]) for s in (-1.0, 1.0)]
        r = geom.radius
        if kind == "Capsule":
            return [placement.act(e + r * down) for e in ends]
        radial = down - down[2] * np.array([0, 0, 1.0])
        n = np.linalg.norm(radial)
        return [placement.act(e + (r * radial / n if n > 1e-9 else 0)) for e in ends]
    if kind == "Box":
        half = np.array(geom.halfSide)
        corners = [np.array(s) * half for s in itertools.product((-1.0, 1.0), repeat=3)]
    elif hasattr(geom, "vertices"):
        corners = list(np.asarray(geom.vertices(), dtype=float))
    else:
        raise UrdfError(f"geometry {obj.name!r} is a {kind}, which the importer does not "
                        f"read (spheres, boxes, capsules, cylinders and meshes)")
    local = np.array([placement.act(c) for c in corners])
    height = (oMi.rotation @ local.T)[2]
    return list(local[height <= height.min() + _SOLE])


def turn_y_up(geometry):
    """The Pinocchio geometry model `geometry`, its Collada ``Y_UP`` meshes turned to z up
    in place (each one's placement followed by the turn; module docstring); call it once
    per model built."""
    import pinocchio as pin  # noqa: PLC0415 - only the importer needs it at import time

    turn = pin.SE3(_Y_UP, np.zeros(3))
    for obj in geometry.geometryObjects:
        if hasattr(obj.geometry, "vertices") and collada_y_up(obj.meshPath):
            obj.placement = obj.placement * turn
    return geometry


def read_mesh(path: str, scale) -> np.ndarray:
    """The vertices (n, 3) m of the mesh file `path` scaled by `scale` (3,), as coal reads
    it for Pinocchio, a Collada ``Y_UP`` turned to z up (module docstring)."""
    import coal  # noqa: PLC0415 - Pinocchio's geometry library, on demand

    vertices = np.asarray(coal.MeshLoader().load(path, np.asarray(scale, float)).vertices(),
                          dtype=float)
    return vertices @ _Y_UP.T if collada_y_up(path) else vertices


def collada_y_up(path: str) -> bool:
    """True for a Collada file (.dae) whose <up_axis> is Y_UP."""
    if not path.lower().endswith(".dae") or not Path(path).is_file():
        return False
    head = Path(path).read_text(errors="replace")[:20000]
    return re.search(r"<up_axis>\s*Y_UP\s*</up_axis>", head) is not None
