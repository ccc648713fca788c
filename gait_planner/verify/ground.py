"""The ground a recording was planned for, rebuilt from its metadata for the verifier.

Written again from docs/design.md section 13, without `gait_planner.model.ground`, so that an
error in the planner's ground cannot hide itself. World x forward, y left, z up; gravity
stays vertical on every ground. Metadata entries (strings; absent: level ground):

* ``slope`` (deg, uphill positive): a ramp, the plane z = x tan(a) through the origin with
  unit normal n = (-sin a, 0, cos a); a point's height above it is n . p.
* ``step_height`` h (m per step, < 0 down), ``stair_riser`` (m, the x of the edge between
  tread 0, height 0, and tread 1, height h) and ``stair_tread`` (m, the depth of every
  tread): stairs. Edge j lies at x = riser + j tread, between tread j (height j h) and
  tread j + 1; an edge belongs to the tread ahead of it. The normal is e_z and a point's
  height is z less the height of the tread under it.

The mirror image of a half cycle of step length s is shifted by (s, 0, s tan a + h).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

__all__ = ["RecordedGround"]

_KEYS = {"slope": "slope", "step_height": "step_height", "riser": "stair_riser",
         "tread": "stair_tread"}


@dataclass(frozen=True)
class RecordedGround:
    """slope deg; step_height m (0: no stairs); riser m, x of the edge between treads 0
    and 1; tread m, depth of a tread."""

    slope: float = 0.0
    step_height: float = 0.0
    riser: float = 0.0
    tread: float = 0.0

    @classmethod
    def of(cls, metadata: Mapping[str, str]) -> "RecordedGround":
        """The ground a recording's metadata names (absent entries: 0). ValueError naming
        the entry if one is not a finite number, if slope and stairs are both given, if the
        slope is not within (-90, 90) deg, or if stairs have no positive tread depth."""
        values = {}
        for field, key in _KEYS.items():
            try:
                values[field] = float(metadata.get(key, "0"))
            except ValueError:
                raise ValueError(f"metadata {key} = {metadata[key]!r} is not a number") from None
            if not math.isfinite(values[field]):
                raise ValueError(f"metadata {key} = {metadata[key]!r} is not finite")
        ground = cls(**values)
        if ground.slope and ground.stairs:
            raise ValueError(f"the metadata names a ramp (slope {ground.slope:g} deg) and stairs "
                             f"(step_height {ground.step_height:g} m) at once")
        if not -90.0 < ground.slope < 90.0:
            raise ValueError(f"metadata slope = {ground.slope:g} deg is not within (-90, 90)")
        if ground.stairs and ground.tread <= 0:
            raise ValueError(f"metadata stair_tread = {ground.tread:g} m: stairs need a "
                             f"positive tread depth")
        return ground

    @property
    def stairs(self) -> bool:
        return self.step_height != 0.0

    @property
    def normal(self) -> np.ndarray:
        """(3,) unit normal: (-sin a, 0, cos a), e_z on level ground and stairs."""
        a = math.radians(self.slope)
        return np.array([-math.sin(a), 0.0, math.cos(a)])

    def rise(self, step: float) -> float:
        """How far (m) the mirror image of a half cycle of step length `step` m is moved
        up: step tan a + step_height (it moves `step` along x)."""
        return step * math.tan(math.radians(self.slope)) + self.step_height

    def height(self, x) -> np.ndarray:
        """Ground height z (m) at x (m, any shape): x tan a on a ramp, the height of the
        tread under x on stairs."""
        x = np.asarray(x, dtype=float)
        if self.stairs:
            return self.step_height * (np.floor((x - self.riser) / self.tread) + 1.0)
        return x * math.tan(math.radians(self.slope))

    def above(self, p) -> np.ndarray:
        """Height (m) of points p (..., 3) above the ground: n . p on a ramp (along the
        normal), z less the height of the tread under the point on stairs, z on level
        ground."""
        p = np.asarray(p, dtype=float)
        if self.stairs:
            return p[..., 2] - self.height(p[..., 0])
        return p @ self.normal if self.slope else p[..., 2].copy()

    def edge_clearance(self, p0, p1) -> float:
        """Lowest height (m) of the straight segment from p0 to p1 (3,) above the higher of
        the two treads at each stair edge it crosses (inf: it crosses none, or no stairs).
        A segment whose ends are above the ground enters the stairs only at an edge: it
        passes through them exactly when this is negative."""
        lowest = math.inf
        p0, p1 = np.asarray(p0, dtype=float), np.asarray(p1, dtype=float)
        if not self.stairs or p0[0] == p1[0]:
            return lowest
        a, b = sorted((p0[0], p1[0]))
        for j in range(math.ceil((a - self.riser) / self.tread),
                       math.floor((b - self.riser) / self.tread) + 1):
            edge = self.riser + j * self.tread  # between tread j and tread j + 1
            if a < edge < b:
                z = p0[2] + (p1[2] - p0[2]) * (edge - p0[0]) / (p1[0] - p0[0])
                top = max(j * self.step_height, (j + 1) * self.step_height)
                lowest = min(lowest, z - top)
        return lowest

    def tangential(self, F) -> np.ndarray:
        """|F - (n . F) n| (N) of forces F (..., 3): the part along the ground."""
        F = np.asarray(F, dtype=float)
        n = self.normal
        return np.linalg.norm(F - (F @ n)[..., None] * n, axis=-1)

    def describe(self) -> str:
        """"level", "ramp 10 deg up", "stairs 0.15 m down (treads 0.63 m, first edge at
        x = 0.44 m)"."""
        if self.stairs:
            way = "up" if self.step_height > 0 else "down"
            return (f"stairs {abs(self.step_height):g} m {way} (treads {self.tread:.4g} m, "
                    f"first edge at x = {self.riser:.4g} m)")
        if self.slope:
            return f"ramp {abs(self.slope):g} deg {'up' if self.slope > 0 else 'down'}"
        return "level"
