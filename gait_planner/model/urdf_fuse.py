"""Ball joints in a URDF (`gait_planner.model.urdf_import`): three revolute joints chained
by two massless links, the URDF's device for a spherical joint (as `gait-planner urdf`
writes the scene's hips and ankles), drafted as ONE spherical scene joint.

The fusion is exact, not an approximation: a massless link carries no mass and no
inertia, so the chain moves the child exactly as the spherical joint does when

* the links between the joints are massless: mass <= `MASSLESS_MASS` and principal
  moments <= `MASSLESS_INERTIA` (the exported walker3d's 1e-9 kg, 1e-12 kg m^2 links);
* the three axes meet in one point (within `POINT_TOLERANCE`): the joint point, on the
  parent and on the child;
* in the parent's directors the axes are, in chain order, (0, 1, 0), (1, 0, 0),
  (0, 0, 1) at the URDF's zero pose, and the child's directors there are the parent's
  (within `ROTATION_TOLERANCE`): then R_rel = Ry(q1) Rx(q2) Rz(q3), the scene's
  spherical convention (`gait_planner.model.angles`) with pitch, roll, yaw the three
  URDF angles, zero and sign as the URDF's.

The spherical joint's angle names are the three URDF joints' names (the JointTrajectory
keeps the URDF's names): ``X_pitch, X_roll, X_yaw`` make the joint ``X``, other names
are written as its ``angle_names``. A chain through massless links that does not map so
is refused, naming its links and what does not match. Links with real mass (G1's 1.35 kg
hip links) are never fused: that would change the dynamics.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gait_planner.model.urdf_errors import UrdfError

MASSLESS_MASS = 1e-6  # kg: a link at most this heavy ...
MASSLESS_INERTIA = 1e-8  # kg m^2: ... with principal moments at most this is massless
POINT_TOLERANCE = 1e-9  # m: the axes' distance from their common point
ROTATION_TOLERANCE = 1e-9  # axis and reference components
_SPHERICAL_AXES = np.eye(3)[[1, 0, 2]]  # pitch about d2, roll about d1, yaw about d3
_SUFFIXES = ("_pitch", "_roll", "_yaw")


@dataclass(frozen=True)
class Ball:
    """Three revolute joints (Pinocchio ids in the reduced model, pitch, roll, yaw) drafted
    as one spherical joint `name` whose angles are `angle_names` (the URDF joints')."""

    name: str
    joints: tuple[int, int, int]
    angle_names: tuple[str, str, str]
    links: tuple[str, str]  # the two massless links

    @property
    def default_names(self) -> bool:
        """True when the scene's own angle names (name_pitch, _roll, _yaw) are the URDF's."""
        return self.angle_names == tuple(self.name + s for s in _SUFFIXES)

    def entry(self, parent: str, child: str) -> dict:
        """Its scene joint entry; its point on both bodies is named as the joint."""
        names = {} if self.default_names else {"angle_names": list(self.angle_names)}
        return {"name": self.name, "type": "spherical", **names, "parent": parent,
                "parent_point": self.name, "child": child, "child_point": self.name}


def is_massless(inertia) -> bool:
    """A Pinocchio inertia (mass kg, inertia at the COM kg m^2) negligible as a body."""
    return (float(inertia.mass) <= MASSLESS_MASS
            and float(np.abs(np.linalg.eigvalsh(np.array(inertia.inertia))).max())
            <= MASSLESS_INERTIA)


def find_balls(model, legs: list[int], links: dict[int, str]) -> tuple[Ball, ...]:
    """The ball joints among the leg joints `legs` (reduced model ids) whose carried links
    (`links`: joint -> link name) are massless; UrdfError naming a massless link that is
    not one of the two inner links of three chained joints."""
    massless = [j for j in legs if is_massless(model.inertias[j])]
    balls = []
    for first in massless:
        if int(model.parents[first]) in massless:
            continue  # inside a chain: found from its first joint
        chain = [first]
        while chain[-1] in massless:
            below = [j for j in legs if int(model.parents[j]) == chain[-1]]
            if len(below) != 1:
                raise UrdfError(_refusal(model, links, chain[-1],
                                         f"it carries {len(below)} leg joints, not one"))
            chain.append(below[0])
        if len(chain) != 3:
            raise UrdfError(_refusal(model, links, first,
                                     f"{len(chain) - 1} massless link(s) in a row, not two"))
        names = tuple(str(model.names[j]) for j in chain)
        prefix = names[0][: -len(_SUFFIXES[0])] if names[0].endswith(_SUFFIXES[0]) else ""
        ball = Ball(prefix, tuple(chain), names, (links[chain[0]], links[chain[1]]))
        balls.append(ball if prefix and ball.default_names else
                     Ball(names[0], ball.joints, names, ball.links))
    return tuple(balls)


def _refusal(model, links, joint: int, why: str) -> str:
    inertia = model.inertias[joint]
    return (f"link {links[joint]!r} moves with the leg but is massless "
            f"({float(inertia.mass):g} kg): {why}. The importer reads massless links only as "
            f"the two inner links of three revolute joints whose axes meet in one point (a "
            f"ball joint); give the link an <inertial>, or merge it by making its joint fixed")


def ball_points(model, ball: Ball, axes: dict[str, np.ndarray], R_parent: np.ndarray,
                R_child: np.ndarray, parent: str, child: str) -> tuple[np.ndarray, np.ndarray]:
    """(the joint point in the parent's joint frame, in the child's joint frame) of `ball`,
    whose parent and child bodies have the principal axes R_parent, R_child (columns, their
    joint frames); `axes`: URDF joint name -> unit axis in its joint frame. UrdfError when
    the chain is not exactly the scene's spherical joint (module docstring)."""
    what = (f"joints {', '.join(map(repr, ball.angle_names))} (massless links "
            f"{ball.links[0]!r}, {ball.links[1]!r}) between {parent!r} and {child!r}")
    placement = model.jointPlacements[ball.joints[0]]
    origins, directions = [], []
    for k, joint in enumerate(ball.joints):
        if k:
            placement = placement * model.jointPlacements[joint]
        origins.append(np.array(placement.translation))
        directions.append(placement.rotation @ axes[ball.angle_names[k]])
    in_parent = R_parent.T @ np.array(directions).T  # columns: the axes in the directors
    if np.abs(in_parent - _SPHERICAL_AXES.T).max() > ROTATION_TOLERANCE:
        raise UrdfError(f"{what}: their axes in {parent!r}'s directors (its principal axes) "
                        f"are {np.round(in_parent.T, 6).tolist()}, not the scene's spherical "
                        f"joint's (0, 1, 0), (1, 0, 0), (0, 0, 1) (pitch, roll, yaw, in that "
                        f"order and sign): not fused, and a massless link cannot be a body")
    reference = R_parent.T @ placement.rotation @ R_child
    if np.abs(reference - np.eye(3)).max() > ROTATION_TOLERANCE:
        raise UrdfError(f"{what}: {child!r}'s directors (its principal axes) are not "
                        f"{parent!r}'s at the URDF's zero pose (relative rotation "
                        f"{np.round(reference, 6).tolist()}), and a spherical joint has no "
                        f"zero-angle reference: not fused, and a massless link cannot be a "
                        f"body")
    normal = [np.eye(3) - np.outer(d, d) for d in directions]
    point = np.linalg.solve(sum(normal), sum(n @ o for n, o in zip(normal, origins)))
    miss = max(float(np.linalg.norm(n @ (point - o))) for n, o in zip(normal, origins))
    if miss > POINT_TOLERANCE:
        raise UrdfError(f"{what}: their axes do not meet in one point ({miss:.3g} m from "
                        f"the nearest common point): not a ball joint, and a massless link "
                        f"cannot be a body")
    return point, placement.actInv(point)
