"""Synthetic recordings of plans on a ramp and on stairs, made from a level plan's recording.

* `on_ramp(rec, slope)`: the level plan rigidly rotated about the y axis so that its ground
  becomes the ramp z = x tan(slope): every position, director, force and moment turned by
  R (R e_x = (cos a, 0, sin a), R e_z = the ramp's normal), the metadata's step length the
  rotated step's x extent s cos a. Geometrically a plan on the ramp (held points on it,
  forces in its cones, the mirror image shifted by (s', 0, s' tan a)); its dynamics are
  wrong, as gravity is not turned. `forces=False` leaves the forces vertical-cone ones.
* `on_stairs(rec, step_height, left, right)`: the level plan (walker2d: bodies ending in _l
  and _r) with every body of a leg lifted by that leg's offset (m, piecewise linear in the
  node index through the knots (nodes, offsets) `left`/`right`) and the torso by
  step_height times the fraction of the half cycle; held points then sit on their treads
  and the mirror image is shifted by (s, 0, step_height) when the offsets pair up
  (right(N-1) = left(0) + h, left(N-1) = right(0) + h, the same for nodes N and 1). The
  hips come apart, so the joint checks fail.
* `schedule(rec)`: (the node where the right foot, held at the start, is released; the
  node where the left foot strikes).

Both keep the potential energy consistent with the new heights.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from gait_planner.verify.mechanics import Mechanics, parse_scene


def _rotation(slope: float) -> np.ndarray:
    a = math.radians(slope)
    return np.array([[math.cos(a), 0.0, -math.sin(a)], [0.0, 1.0, 0.0],
                     [math.sin(a), 0.0, math.cos(a)]])


def _turn(vectors: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Rows of 3-vectors (..., 3m) turned by R, each triple."""
    v = np.asarray(vectors, dtype=float)
    return (v.reshape(*v.shape[:-1], v.shape[-1] // 3, 3) @ R.T).reshape(v.shape)


def _potential(rec, q: np.ndarray) -> np.ndarray:
    mech = Mechanics(parse_scene(rec.scene_text))
    return np.array([mech.potential_energy(row) for row in q])


def on_ramp(rec, slope: float, forces: bool = True):
    """`rec` turned onto a ramp of `slope` deg (module docstring)."""
    R = _rotation(slope)
    q = _turn(rec.q, R)
    step = float(rec.metadata["step_length"]) * math.cos(math.radians(slope))
    metadata = dict(rec.metadata, slope=repr(float(slope)), step_height="0.0",
                    step_length=repr(step))
    return dataclasses.replace(
        rec, q=q, generalized_force=_turn(rec.generalized_force, R),
        potential_energy=_potential(rec, q),
        contact_points=tuple(_turn(p, R) for p in rec.contact_points),
        contact_force_vectors=tuple(_turn(f, R) if forces else f
                                    for f in rec.contact_force_vectors),
        wrench_points=tuple(_turn(p, R) for p in rec.wrench_points),
        wrenches=tuple(_turn(w, R) for w in rec.wrenches),
        centers_of_pressure=tuple(_turn(p, R) for p in rec.centers_of_pressure),
        metadata=metadata)


def schedule(rec) -> tuple[int, int]:
    """(release, strike) nodes of the right and the left foot (module docstring)."""
    release = next(n for n in range(1, rec.n_nodes)
                   if not any(c.startswith("foot_r") for c in rec.active_contacts[n]))
    strike = next(n for n in range(rec.n_nodes)
                  if any(c.startswith("foot_l") for c in rec.active_contacts[n]))
    return release, strike


def on_stairs(rec, step_height: float, left, right):
    """`rec` lifted onto stairs of `step_height` m (module docstring); left, right: knots
    (nodes, offsets m) of the legs' offsets."""
    scene = parse_scene(rec.scene_text)
    mech = Mechanics(scene)
    times = np.asarray(rec.times, dtype=float)
    N = rec.n_nodes - 1
    torso = step_height * (times - times[0]) / (times[N - 1] - times[0])

    def offset(body: str, n: int) -> float:
        if body.endswith("_l"):
            return float(np.interp(n, *left))
        return float(np.interp(n, *right)) if body.endswith("_r") else float(torso[n])

    q = np.array(rec.q, dtype=float)
    for n in range(rec.n_nodes):
        for b in scene.bodies:
            q[n, mech.start(b.name) + 2] += offset(b.name, n)

    def lifted(points, bodies, n):
        """points (m, 3) of `bodies` at node n, lifted with them."""
        lift = np.array([[0.0, 0.0, offset(b, n)] for b in bodies]).reshape(-1, 3)
        return np.array(points, dtype=float).reshape(-1, 3) + lift

    body_of = {c: body for c, (body, _) in scene.contacts.items()}
    return dataclasses.replace(
        rec, q=q, potential_energy=_potential(rec, q),
        contact_points=tuple(lifted(p, [body_of[c] for c in rec.contact_names[n]], n)
                             for n, p in enumerate(rec.contact_points)),
        wrench_points=tuple(lifted(p, rec.wrench_bodies[n], n)
                            for n, p in enumerate(rec.wrench_points)),
        centers_of_pressure=tuple(lifted(p, rec.wrench_bodies[n], n)
                                  for n, p in enumerate(rec.centers_of_pressure)),
        metadata=dict(rec.metadata, slope="0.0", step_height=repr(float(step_height))))
