"""The legs' clearance of a recording: the smallest distance between the collision geometry
of one leg and that of another, at every node.

Which bodies: those the scene gives ``collision:`` spheres (a drafted scene's knee, shank,
ankle and foot links; walker3d's calves and feet), grouped into legs by the joint of the
root their chain hangs from. What is measured:

* a scene drafted from a URDF: the URDF's own collision geometry (Pinocchio's
  ``buildGeomFromUrdfString`` on the recording's /robot_description, meshes found in the
  recording's ``robot_package_dirs`` and the scene's ``robot:`` folders), every object on
  the joint that carries each body's link (links fixed to it included), placed by the
  recorded configuration as the continuous certificate places it
  (`gait_planner.verify.robot.urdf_configurations`), distances by coal
  (``pinocchio.computeDistances``: GJK/EPA on meshes and primitives); a Collada mesh whose
  <up_axis> is Y_UP placed as its authors' viewers place it, its y turned to z (coal
  keeps the file's axes: iCub's shanks would lie across its hips, touching each other
  standing);
* a hand-written scene (or meshes that cannot be found, said in `source`): the spheres
  themselves, |c_i - c_j| - r_i - r_j with c = phi + D p.

Judged: a distance <= 0 (the legs touch or overlap) fails the plan; one below the plan's
``leg_clearance`` (the metadata's, the distance the planner's rows kept between the
spheres, which contain the geometry) is noted. A plan that was not asked to keep its legs
apart (``legs_apart: false``, walker3d's paper problem: no leg_clearance in the metadata)
is measured, and touching legs noted, not failed. Written again here from the scene file: nothing
of `gait_planner.ocp.legs` is used.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

import numpy as np

from gait_planner.verify.continuous import effort_names
from gait_planner.verify.mechanics import SceneData

__all__ = ["LegClearance", "judge_legs", "leg_clearance", "legs_of", "legs_of_recording"]


@dataclass(frozen=True)
class LegClearance:
    """distance (N+1,) m: the smallest distance between two legs at each node; node: where
    it is smallest; pair: the two bodies there; source: what was measured; clearance: the
    plan's leg_clearance (m; nan if the metadata has none)."""

    distance: np.ndarray
    node: int
    pair: tuple[str, str]
    source: str
    clearance: float

    @property
    def smallest(self) -> float:
        return float(self.distance[self.node])


def legs_of(scene: SceneData) -> list[tuple[str, ...]]:
    """The bodies with collision spheres of each leg (the subtree of one joint of the root;
    legs without spheres left out); [] for a planar scene."""
    if scene.planar:
        return []
    children: dict[str, list[str]] = {}
    for j in scene.joints:
        children.setdefault(j.parent, []).append(j.child)
    legs = []
    for top in children.get(scene.root, []):
        subtree, stack = [], [top]
        while stack:
            body = stack.pop()
            subtree.append(body)
            stack += children.get(body, [])
        legs.append(tuple(b.name for b in scene.bodies
                          if b.name in subtree and len(b.collision)))
    return [leg for leg in legs if leg]


def leg_clearance(scene: SceneData, q: np.ndarray, metadata: dict, urdf: str = "",
                  angles: np.ndarray | None = None) -> LegClearance | None:
    """The legs' clearance (module docstring) of the configurations q (N+1, 12 nb), on the
    URDF text `urdf` with the planned joints' angles (N+1, na) (`effort_names` order) when
    the scene was drafted from one; None for a scene with fewer than two legs with spheres."""
    legs = legs_of(scene)
    if len(legs) < 2:
        return None
    clearance = float(metadata.get("leg_clearance", "nan"))
    q = np.asarray(q, dtype=float)
    source = "the collision spheres of the scene"
    if scene.robot_root is not None and urdf:
        dirs = [d for d in metadata.get("robot_package_dirs", "").split(os.pathsep) if d]
        try:
            distance, pairs = _on_urdf(scene, legs, q, urdf, angles, dirs)
            node = int(np.argmin(distance))
            return LegClearance(distance, node, pairs[node], "the URDF's collision geometry "
                                "(coal)", clearance)
        except (ValueError, RuntimeError) as error:
            source += f" (the URDF's collision geometry cannot be read: {error})"
    distance, pairs = _on_spheres(scene, legs, q)
    node = int(np.argmin(distance))
    return LegClearance(distance, node, pairs[node], source, clearance)


def legs_of_recording(rec, scene: SceneData) -> LegClearance | None:
    """`leg_clearance` of a decoded recording (`gait_planner.io.mcap_reader.RecordedPlan`):
    its configurations, metadata, URDF and the planned joints' recorded angles."""
    names = list(rec.joint_names)
    columns = [names.index(n) for n in effort_names(scene) if n in names]
    angles = np.asarray(rec.positions, dtype=float)[:, columns]
    return leg_clearance(scene, rec.q, rec.metadata, rec.urdf, angles)


def judge_legs(legs: LegClearance | None, failures: list[str], notes: list[str]) -> None:
    """A failure when the legs touch or overlap (distance <= 0), a note when they come
    closer than the plan's leg_clearance (module docstring); for a plan that was not
    asked to keep them apart (no leg_clearance in its metadata: walker3d's paper problem)
    touching is noted, not failed."""
    if legs is None:
        return
    a, b = legs.pair
    where = f"{a} and {b} at node {legs.node} ({legs.source})"
    if math.isnan(legs.clearance):
        if not legs.smallest > 0:
            notes.append(f"the legs touch, {legs.smallest:.4g} m apart: {where}; the plan was "
                         f"not asked to keep them apart (no leg_clearance in its metadata)")
    elif not legs.smallest > 0:
        failures.append(f"the legs touch: {where} are {legs.smallest:.4g} m apart")
    elif legs.smallest < legs.clearance:
        notes.append(f"the legs come {legs.smallest:.4g} m close, less than the plan's "
                     f"leg_clearance {legs.clearance:g} m: {where}")


def _on_spheres(scene: SceneData, legs, q: np.ndarray):
    """((N+1,) smallest distance, [(body, body)] per node) between the legs' spheres."""
    index = {b.name: i for i, b in enumerate(scene.bodies)}
    centres, radii, owners = [], [], []
    for leg in legs:
        c, r, o = [], [], []
        for name in leg:
            i = index[name]
            phi, D = q[:, 12 * i:12 * i + 3], q[:, 12 * i + 3:12 * i + 12].reshape(-1, 3, 3)
            for x, y, z, radius in scene.bodies[i].collision:
                # D = [d1 d2 d3]: q holds d1, d2, d3 one after the other
                c.append(phi + np.einsum("nji,j->ni", D, [x, y, z]))
                r.append(radius)
                o.append(name)
        centres.append(np.stack(c, axis=1))
        radii.append(np.array(r))
        owners.append(o)
    best = np.full(len(q), math.inf)
    pairs = [("", "")] * len(q)
    for a in range(len(legs)):
        for b in range(a + 1, len(legs)):
            gap = np.linalg.norm(centres[a][:, :, None] - centres[b][:, None], axis=3) \
                - radii[a][:, None] - radii[b][None]
            for n in range(len(q)):
                i, j = np.unravel_index(int(np.argmin(gap[n])), gap[n].shape)
                if gap[n, i, j] < best[n]:
                    best[n], pairs[n] = float(gap[n, i, j]), (owners[a][i], owners[b][j])
    return best, pairs


def _on_urdf(scene: SceneData, legs, q: np.ndarray, urdf: str, angles, dirs):
    """((N+1,) smallest distance, [(link, link)] per node) between the legs' links'
    collision objects on the URDF, by coal."""
    import pinocchio as pin  # noqa: PLC0415 - drafted scenes only

    from gait_planner.verify.robot import urdf_configurations  # noqa: PLC0415

    model = pin.buildModelFromXML(urdf, pin.JointModelFreeFlyer())
    full = pin.buildGeomFromUrdfString(model, urdf, pin.GeometryType.COLLISION,
                                       package_dirs=list(dirs))
    y_to_z = pin.SE3(pin.utils.rotate("x", math.pi / 2), np.zeros(3))
    for obj in full.geometryObjects:
        if _y_up_collada(obj.meshPath):
            obj.placement = obj.placement * y_to_z
    geometry, side = pin.GeometryModel(), []
    for k, leg in enumerate(legs):
        joints = {model.frames[model.getFrameId(name)].parentJoint: name for name in leg
                  if model.existFrame(name)}
        if len(joints) != len(leg):
            raise ValueError(f"the URDF lacks links {[n for n in leg if not model.existFrame(n)]}")
        for obj in full.geometryObjects:
            if obj.parentJoint in joints:
                geometry.addGeometryObject(obj)
                side.append((k, joints[obj.parentJoint]))
    for a in range(len(side)):
        for b in range(a + 1, len(side)):
            if side[a][0] != side[b][0]:
                geometry.addCollisionPair(pin.CollisionPair(a, b))
    if not geometry.collisionPairs:
        raise ValueError("the legs' links have no collision objects")
    data, gdata = model.createData(), pin.GeometryData(geometry)
    best, pairs = [], []
    for config in urdf_configurations(scene, model, q, angles):
        pin.computeDistances(model, data, geometry, gdata, config)
        d = [r.min_distance for r in gdata.distanceResults]
        k = int(np.argmin(d))
        pair = geometry.collisionPairs[k]
        best.append(float(d[k]))
        pairs.append((side[pair.first][1], side[pair.second][1]))
    return np.array(best), pairs


def _y_up_collada(path: str) -> bool:
    """Whether `path` is a Collada file that declares <up_axis>Y_UP</up_axis>."""
    if not path.lower().endswith(".dae") or not os.path.isfile(path):
        return False
    with open(path, encoding="utf-8", errors="replace") as file:
        return re.search(r"<up_axis>\s*Y_UP\s*<", file.read(20000)) is not None
