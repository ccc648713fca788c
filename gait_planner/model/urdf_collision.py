"""A drafted robot's lower legs as spheres fitted to their collision geometry
(`gait_planner.model.urdf_import`), for the rows that keep the legs apart
(`gait_planner.ocp.legs`; docs/design.md section 8).

Which bodies: every leg body whose joint lies in the lower LOWER_LEG of the leg at the URDF
zero pose (from the foot's joint to the hip's): the knee, shank, ankle and foot links; the
thighs, which meet at the crotch (Talos's are 12 mm apart standing), are left out.

The fit: the body's collision geometry, in its director components from the centre of
mass, is a set of convex pieces, each the convex hull of a few points grown by a radius rho
(a mesh's triangles, split until no edge is longer than PIECE_EDGE, rho = 0; a box's
corners; a sphere's centre, a capsule's or a cylinder's two end centres, rho = its radius).
The pieces are binned by their centroids into a grid of at most SPHERES cells (no narrower
than CELL where a coarser grid fits) across the leg's lateral direction (world y at the
zero pose): each cell spans the body's whole width, and its sphere, centred on the cell's
points' bounding box with radius max |c - p| + rho over them, contains each of its pieces
whole (a ball is convex): the spheres contain the collision geometry exactly, not only
sampled points of it. A sphere that spans the width bulges little towards the other leg:
Talos's standing shanks are 27.6 mm apart, their spheres 9.8 mm; a few spheres along the
body's axis or on its surface overlapped by 10 to 30 cm (benchmarks/HISTORY.md,
2026-12-06). A right body's spheres are its left partner's mirrored, fitted to the left
body's pieces and the right body's mirrored together (so they contain both).
"""

from __future__ import annotations

import numpy as np

from gait_planner.model.urdf_errors import UrdfError

__all__ = ["CELL", "LEG_CLEARANCE", "LOWER_LEG", "SPHERES", "collision_pieces", "fit_spheres",
           "leg_spheres"]

LEG_CLEARANCE = 0.01  # m: the draft's leg_clearance (`gait_planner.ocp.legs`)
LOWER_LEG = 0.65  # the lower part of the leg (foot joint to hip) whose bodies get spheres
SPHERES = 12  # at most, per body
CELL = 0.03  # m: no narrower cells where a coarser grid fits
PIECE_EDGE = 0.02  # m: a mesh's triangles are split until no edge is longer


def collision_pieces(geometry, joint: int) -> list[tuple[np.ndarray, float]]:
    """[(points (m, 3) in the joint frame, rho m)]: the convex pieces of the collision
    objects of a Pinocchio `GeometryModel` fixed to `joint` (module docstring); UrdfError
    for a shape the importer does not read."""
    out = []
    for obj in geometry.geometryObjects:
        if obj.parentJoint != joint:
            continue
        geom, placement = obj.geometry, obj.placement
        kind = type(geom).__name__
        if kind == "Sphere":
            out.append((np.array([placement.translation]), float(geom.radius)))
        elif kind in ("Capsule", "Cylinder"):  # a cylinder: the capsule around it
            ends = [placement.act(np.array([0.0, 0.0, s * geom.halfLength])) for s in (-1, 1)]
            out.append((np.array(ends), float(geom.radius)))
        elif kind == "Box":
            half = np.array(geom.halfSide)
            corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                                for sz in (-1, 1)]) * half
            out.append((np.array([placement.act(c) for c in corners]), 0.0))
        elif hasattr(geom, "tri_indices"):
            vertices = np.asarray(geom.vertices(), dtype=float)
            vertices = vertices @ placement.rotation.T + placement.translation
            triangles = np.array([[t[i] for i in range(3)] for t in
                                  (geom.tri_indices(k) for k in range(geom.num_tris))])
            out += [(t, 0.0) for t in _subdivided(vertices[triangles])]
        else:
            raise UrdfError(f"collision geometry {obj.name!r} is a {kind}, which the importer "
                            f"does not read (spheres, boxes, capsules, cylinders and meshes)")
    return out


def fit_spheres(pieces: list[tuple[np.ndarray, float]], lateral: np.ndarray,
                count: int = SPHERES, cell: float = CELL) -> np.ndarray:
    """(s, 4) spheres (centre m, radius m), s <= count, that contain every piece
    [(points (m, 3), rho)] (module docstring); ValueError without pieces."""
    if not pieces:
        raise ValueError("no collision pieces to fit spheres to")
    lateral = np.asarray(lateral, dtype=float) / np.linalg.norm(lateral)
    # the plane across `lateral`, spanned from the director least along it: a basis that
    # moves continuously with `lateral` (an SVD's basis of a repeated singular value does
    # not, and a round-off of a turned link frame reordered the cells)
    axis = np.eye(3)[int(np.argmin(np.abs(lateral)))]
    first = axis - (axis @ lateral) * lateral
    first /= np.linalg.norm(first)
    across = np.column_stack([first, np.cross(lateral, first)])  # (3, 2)
    centroids = np.array([p.mean(axis=0) for p, _ in pieces]) @ across  # (n, 2)
    low, high = centroids.min(axis=0), centroids.max(axis=0)
    cells = _grid(high - low, count, cell)
    index = np.minimum(((centroids - low) / np.maximum(high - low, 1e-12) * cells)
                       .astype(int), cells - 1)
    key = index[:, 0] * cells[1] + index[:, 1]
    out = []
    for k in np.unique(key):
        chosen = [pieces[i] for i in np.flatnonzero(key == k)]
        points = np.vstack([p for p, _ in chosen])
        centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
        out.append(np.r_[centre, _reach(centre, chosen)])
    return np.array(out)


def _grid(extent: np.ndarray, count: int, cell: float) -> np.ndarray:
    """(2,) cells along each of two extents (m): cells as square as the extents allow, at
    most `count` of them, none narrower than `cell` where a coarser grid fits."""
    wide = int(np.argmax(extent))
    ratio = max(float(extent[wide]) / max(float(extent[1 - wide]), 1e-12), 1.0)
    out = np.ones(2, dtype=int)
    out[1 - wide] = max(1, int(round(np.sqrt(count / ratio))))
    out[wide] = max(1, count // out[1 - wide])
    return np.maximum(np.minimum(out, np.ceil(extent / cell).astype(int)), 1)


def _subdivided(triangles: np.ndarray, edge: float = PIECE_EDGE) -> list[np.ndarray]:
    """The triangles (t, 3, 3) split at their edges' midpoints, four for one, until no
    edge is longer than `edge` m: the same surface in pieces a small ball can hold."""
    out = []
    while len(triangles):
        longest = np.linalg.norm(triangles - np.roll(triangles, 1, axis=1), axis=2).max(axis=1)
        out += list(triangles[longest <= edge])
        big = triangles[longest > edge]
        a, b, c = big[:, 0], big[:, 1], big[:, 2]
        ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
        triangles = np.concatenate([np.stack(t, axis=1) for t in
                                    ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    return out


def _reach(centre: np.ndarray, pieces) -> float:
    """max |centre - p| + rho over the pieces' points (the radius that contains them)."""
    return max(float(np.linalg.norm(p - centre, axis=1).max()) + rho for p, rho in pieces)


def leg_spheres(model, geometry, data, bodies, left_of: dict[int, int],
                foot_ids, frame) -> dict[int, np.ndarray]:
    """joint -> (s, 4) spheres (centre in the body's director components from its centre of
    mass, radius; m) of the lower legs' bodies (module docstring), from a reduced Pinocchio
    model's collision `geometry` at the zero pose (`data` after forward kinematics);
    `bodies`: joint -> the draft's body (R, com: its directors and centre of mass in the
    joint frame), `left_of`: right joint -> its left partner, `frame` the walker's world in
    the URDF's (`gait_planner.model.urdf_frame.WalkFrame`: its up and left). Bodies without
    collision geometry get none."""
    lower = []
    for foot in foot_ids:
        path, joint = [], foot
        while joint > 1:
            path.append(joint)
            joint = int(model.parents[joint])
        up = {j: float(frame.W[:, 2] @ data.oMi[j].translation) for j in path}
        hip, ankle = up[path[-1]], up[foot]
        lower += [j for j in path if j in bodies and up[j] - ankle <= LOWER_LEG * (hip - ankle)]
    mirror = np.array([1.0, -1.0, 1.0])

    def pieces(j: int) -> list[tuple[np.ndarray, float]]:
        body = bodies[j]
        return [((p - body.com) @ body.R, rho) for p, rho in collision_pieces(geometry, j)]

    out = {}
    for j in lower:
        if j in left_of:
            continue  # a right body: its left partner's spheres, mirrored
        right = [r for r, left in left_of.items() if left == j and r in lower]
        own = pieces(j) + [(p * mirror, rho) for r in right for p, rho in pieces(r)]
        if not own:
            continue
        lateral = bodies[j].R.T @ data.oMi[j].rotation.T @ frame.W[:, 1]
        out[j] = fit_spheres(own, lateral)
        for r in right:
            out[r] = out[j] * np.r_[mirror, 1.0]
    return out
