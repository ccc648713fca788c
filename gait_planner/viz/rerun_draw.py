"""Drawing a walker in rerun (rerun-sdk 0.41), shared by a plan's view
(`gait_planner.viz.rerun_view`) and a walk's (`gait_planner.viz.rerun_walk`).

* `log_ground`: ``world`` z up and a grid on the ground a plan was made for (``world/ground``:
  z = 0, the tilted plane of a ramp, the treads of stairs, with the treads' boxes at
  ``world/ground/treads``);
* `log_bodies` and `log_poses`: each body's drawing primitive (`gait_planner.io.urdf.body_shapes`,
  box or cylinder, in body coordinates, partly transparent) at ``<root>/<body>``, moved by a
  Transform3D per time (the COM phi and the directors [d1 d2 d3]);
* `skeleton`: line strips COM -> joint point -> COM along every joint, heel -> forefoot on
  every foot;
* `Columns`: per-time instances of one entity (strips, points, arrows: any number at each
  time) sent as one columnar chunk;
* `send_scalars` and `log_boundaries`: a time series, and grey vertical lines at given times
  (phase or half-cycle boundaries) spanning a plot's range.
"""

from __future__ import annotations

import numpy as np
import rerun as rr

from gait_planner.io.messages import quaternion_msg
from gait_planner.viz.rerun_series import BOUNDARY_COLOR, PlotGroup
from gait_planner.io.urdf import body_shapes, ground_boxes
from gait_planner.model.ground import LEVEL, Ground
from gait_planner.model.scene import Scene

__all__ = ["Columns", "log_boundaries", "log_bodies", "log_ground", "log_poses",
           "send_scalars", "skeleton"]

_GROUND_HALF_SIZE, _GROUND_STEP = 1.5, 0.25  # m
_BODY_ALPHA = 150  # the bodies let the arrows, trails and skeleton inside them show
_GROUND_COLOR, _TREAD_COLOR = (150, 150, 150), (190, 190, 180, 70)


def _rgb(color) -> tuple[int, int, int]:
    return tuple(int(round(255 * c)) for c in color[:3])  # type: ignore[return-value]


def log_ground(rec: rr.RecordingStream, x_end: float = _GROUND_HALF_SIZE,
               ground: Ground = LEVEL) -> None:
    """``world`` z up and its ground grid ``world/ground`` (x from -1.5 m to `x_end` m, y
    within +-1.5 m, 0.25 m squares) on `ground` (`gait_planner.model.ground`): on z = 0,
    on a ramp's plane, or on the treads of stairs, whose boxes (`ground_boxes`) are drawn
    at ``world/ground/treads``; static."""
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    h = _GROUND_HALF_SIZE
    xs = np.arange(-h, max(x_end, h) + _GROUND_STEP - 1e-9, _GROUND_STEP)
    ys = np.arange(-h, h + 1e-9, _GROUND_STEP)
    zs = ground.height(xs) + 0.0  # + 0.0: 0.0, not -0.0, on level ground
    profile = [(-h, zs[0]), (xs[-1], zs[-1])]  # the ground's section along x (x, z)
    if ground.stairs:
        boxes = ground_boxes(ground, -h, xs[-1])
        profile = [(float(np.clip(b.centre[0] + side * b.size[0] / 2, -h, xs[-1])),
                    b.centre[2] + b.size[2] / 2) for b in boxes for side in (-1, 1)]
        rec.log("world/ground/treads", rr.Boxes3D(
            centers=[b.centre for b in boxes], sizes=[b.size for b in boxes],
            colors=_TREAD_COLOR, fill_mode="solid"), static=True)
    lines = [[[x, -h, z], [x, h, z]] for x, z in zip(xs, zs)]
    lines += [[[x, y, z] for x, z in profile] for y in ys]
    rec.log("world/ground", rr.LineStrips3D(lines, radii=0.001, colors=_GROUND_COLOR),
            static=True)


def log_bodies(rec: rr.RecordingStream, scene: Scene, root: str,
               alpha: int = _BODY_ALPHA) -> None:
    """Each body's drawing primitive (`body_shapes`, body coordinates) at ``<root>/<body>``,
    static, with opacity `alpha` (0-255); `log_poses` moves them."""
    for name, shape in body_shapes(scene).items():
        color = (*_rgb(shape.color), alpha)
        if shape.kind == "box":
            geometry = rr.Boxes3D(sizes=[shape.size], centers=[shape.centre], colors=[color],
                                  fill_mode="solid")
        else:
            geometry = rr.Cylinders3D(lengths=[shape.size[2]], radii=[shape.size[0]],
                                      centers=[shape.centre], colors=[color], fill_mode="solid")
        rec.log(f"{root}/{name}", geometry, static=True)


def log_poses(rec: rr.RecordingStream, root: str, body_names, indexes: list, phi: np.ndarray,
              D: np.ndarray) -> None:
    """The bodies of `log_bodies` at COMs phi (n, nb, 3) m with directors D (n, nb, 3, 3), a
    Transform3D per row of `indexes` (rerun time columns), one columnar chunk per body."""
    for i, body in enumerate(body_names):
        quaternions = [[v["x"], v["y"], v["z"], v["w"]]
                       for v in (quaternion_msg(R) for R in D[:, i])]
        rec.send_columns(f"{root}/{body}", indexes=indexes,
                         columns=rr.Transform3D.columns(translation=phi[:, i],
                                                        quaternion=quaternions))


def skeleton(scene: Scene, phi: np.ndarray, D: np.ndarray) -> list[np.ndarray]:
    """Line strips COM -> joint point -> COM along every joint, heel -> forefoot on every
    foot, of one configuration: COMs phi (nb, 3), directors D (nb, 3, 3)."""
    index = {b.name: i for i, b in enumerate(scene.bodies)}
    strips = []
    for joint in scene.joints:
        p, c = index[joint.parent], index[joint.child]
        point = phi[p] + D[p] @ np.asarray(scene.body(joint.parent).points[joint.parent_point])
        strips.append(np.array([phi[p], point, phi[c]]))
    feet: dict[str, list[np.ndarray]] = {}
    for contact in scene.contacts:
        b = index[contact.body]
        feet.setdefault(contact.body, []).append(
            phi[b] + D[b] @ np.asarray(scene.body(contact.body).points[contact.point]))
    strips += [np.array(points) for points in feet.values() if len(points) > 1]
    return strips


class Columns:
    """The per-node instances of one entity, sent as one columnar chunk (`send`): a row per
    node, each with its own number of instances (strips, points or arrows)."""

    def __init__(self, indexes: list):
        self.indexes, self.values, self.lengths = indexes, {}, []

    def add(self, **fields) -> None:
        counts = {len(v) for v in fields.values()}
        assert len(counts) == 1, fields.keys()
        self.lengths.append(counts.pop())
        for key, value in fields.items():
            self.values.setdefault(key, []).extend(value)

    def send(self, rec: rr.RecordingStream, path: str, archetype, **style) -> None:
        """The rows as `archetype` columns, partitioned by node; `style` (radii, colors,
        show_labels: the same at every node) logged once, static."""
        rec.log(path, archetype.from_fields(**style), static=True)
        values = {k: (np.array(v, dtype=float).reshape(-1, 3) if k in
                      ("positions", "origins", "vectors") else v)
                  for k, v in self.values.items()}
        rec.send_columns(path, indexes=self.indexes,
                         columns=archetype.columns(**values).partition(self.lengths))


def send_scalars(rec: rr.RecordingStream, path: str, t: np.ndarray, values: np.ndarray) -> None:
    """One time series: `values` (n,) at times `t` (n,) s on timeline ``time``."""
    rec.send_columns(path, indexes=[rr.TimeColumn("time", duration=t)],
                     columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=float)))


def log_boundaries(rec: rr.RecordingStream, group: PlotGroup, data: np.ndarray,
                   boundaries: np.ndarray, name: str) -> None:
    """Grey vertical lines at times `boundaries` (s) spanning the range of `data` (the
    group's values), the series ``group.boundary_path``."""
    low, high = float(np.nanmin(data)), float(np.nanmax(data))
    if high - low < 1e-9:
        low, high = low - 1.0, high + 1.0
    # one polyline of vertical segments: (t_b, low) -> (t_b + 1 us, high), then a gap
    times = np.repeat(boundaries, 3) + np.tile([0.0, 1e-6, 2e-6], len(boundaries))
    heights = np.tile([low, high, np.nan], len(boundaries))
    rec.log(group.boundary_path, rr.SeriesLines(  # not averaged within a pixel
        colors=BOUNDARY_COLOR, widths=1.0, names=name, aggregation_policy="Off"), static=True)
    send_scalars(rec, group.boundary_path, times, heights)
