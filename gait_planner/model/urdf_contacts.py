"""A drafted robot's contact points, from each foot's collision geometry at the URDF zero
pose (`gait_planner.model.urdf_import`): a sphere's lowest point, a box's lowest corners, a
capsule's or cylinder's lowest points at its two ends, a mesh's lowest vertices. With points
ahead and behind the foot's centre, the rear ones make the ``heel`` and the front ones the
``forefoot`` (each the centre of its group: two points per foot, as walker3d's foot, whose
full contact also holds the roll about the heel-forefoot line); a single point makes a
point foot (the compass's phases). A foot without collision geometry: the links fixed to it
without mass (`gait-planner urdf`'s contact frames) are its points.
"""

from __future__ import annotations

import itertools

import numpy as np

from gait_planner.model.urdf_errors import UrdfError

__all__ = ["foot_contacts"]


def foot_contacts(model, geometry, data, foot_ids, links) -> tuple[dict, dict[int, float]]:
    """(foot joint -> {"heel": p, "forefoot": p} or {"foot": p}, joint-frame points; foot
    joint -> the sole's half width (its points' lateral spread), flat feet with a width
    only). A foot without collision geometry: the links fixed to it without mass (contact
    frames, as `gait-planner urdf` writes them) are its points."""
    import pinocchio as pin  # noqa: PLC0415 - only the importer needs it at import time

    out, half_widths = {}, {}
    for foot in foot_ids:
        lowest: list[np.ndarray] = []  # joint-frame points
        for obj in geometry.geometryObjects:
            if obj.parentJoint != foot:
                continue
            lowest += _lowest_points(obj, data.oMi[foot])
        link = links[foot]
        lowest = lowest or [np.array(f.placement.translation) for f in model.frames
                            if f.parentJoint == foot and f.type == pin.FrameType.BODY
                            and f.name != link and f.inertia.mass == 0]
        if not lowest:
            raise UrdfError(f"foot link {link!r} has no collision geometry and no massless "
                            f"links fixed to it: its contact points come from its "
                            f"<collision> spheres, boxes or meshes, or else from such links")
        world = np.array([data.oMi[foot].act(p) for p in lowest])
        z0 = world[:, 2].min()
        on_sole = world[:, 2] <= z0 + 1e-3
        pts, wpts = np.array(lowest)[on_sole], world[on_sole]
        span = np.ptp(wpts[:, 0])
        if span < 0.02:  # a point foot
            out[foot] = {"foot": pts.mean(axis=0)}
            continue
        middle = 0.5 * (wpts[:, 0].min() + wpts[:, 0].max())
        out[foot] = {"heel": pts[wpts[:, 0] < middle].mean(axis=0),
                     "forefoot": pts[wpts[:, 0] >= middle].mean(axis=0)}
        if np.ptp(wpts[:, 1]) > 0:
            half_widths[foot] = 0.5 * float(np.ptp(wpts[:, 1]))
    return out, half_widths


def _lowest_points(obj, oMi) -> list[np.ndarray]:
    """The lowest points at the zero pose (joint frame) of one collision object."""
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
        corners = [np.array(v) for v in np.asarray(geom.vertices())]
    else:
        raise UrdfError(f"collision geometry {obj.name!r} is a {kind}, which the importer "
                        f"does not read (spheres, boxes, capsules, cylinders and meshes)")
    local = np.array([placement.act(c) for c in corners])
    height = (oMi.rotation @ local.T)[2]
    return list(local[height <= height.min() + 1e-3])
