"""The ground a gait is planned on: level, a ramp, or stairs (docs/design.md section 13).

World x forward (walking direction), y left, z up, as in `gait_planner.model.scene`. The
half cycle's first held contact point is pinned at x = 0 (`ocp.transcription`), on the
ground there.

* Ramp: the plane z = x tan(slope) through the origin, slope in degrees, uphill positive.
  Its unit normal n = (-sin a, 0, cos a); a point's height above it is n . p (measured
  along the normal). The mirror image of a half cycle is shifted by the step length s
  along x and by s tan a up.
* Stairs: treads as deep as the step length s, each `step_height` h above the one behind
  (h < 0: stairs down); tread 0 (height 0) holds the foot that stands at the start of the
  half cycle, tread 1 (height h) the foot that lands. The edge between them, the
  `riser`, lies at x = (f + s) / 2, midway between the front of the standing foot (f its
  heel-to-toe reach from the pinned point) and the back of the landing foot (at x = s,
  the mirror image of the pinned point); the next edges are s apart. The mirror image is
  shifted by s along x and by h up. The normal is e_z.

Slope and stairs together are not a ground this planner builds (`Ground.__post_init__`).

A compiled problem reads its ground from the NLP's parameter vector (`Ground.parameters`,
`PARAMETERS`), not from constants folded into its code: `ParametricGround` is the same
ground as CasADi expressions of those entries, so one compiled problem serves every slope
and every stair height of one `Ground.form` (docs/design.md section 13).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

# A swing point must clear a stair edge's height this far (m) before the edge on stairs up.
# Where a node's point moves less than this along x per interval, the straight segment
# between two nodes cannot cut the edge's corner: its node on the lower tread's side lies
# within the margin, at the higher tread's height. Where it moves farther, the verifier's
# segment check finds the cut (a walker2d toe moved 8 cm in one 15 ms interval over a
# 0.15 m stair and passed 8 mm below the corner). A 10 cm margin left walker2d's 0.15 m
# stairs infeasible. Stairs down need no margin: their segment rows
# (`gait_planner.ocp.clearance.segment_heights`) keep every segment above the corners; the
# plan a cold plan on stairs down starts from keeps it (`Ground.segment_rows` False).
EDGE_MARGIN = 0.05
# Width (m) of the smooth step that stands for an edge in the clearance rows; its centre
# lies another 5 widths towards the lower tread, so at the margin from the edge the step
# is 99.3 % up (1 mm short on a 0.15 m stair, within the swing clearance).
EDGE_WIDTH = 0.005


class GroundError(ValueError):
    """A ground that cannot be planned on, with the reason."""


@dataclass(frozen=True)
class Ground:
    """slope deg (uphill positive); step_height m per step (stairs; 0: none); riser m,
    the x of the edge between tread 0 and tread 1; tread m, the depth of a tread (the
    step length); segment_rows: on stairs down, the segments between two nodes are kept
    above the edges' corners by the segment rows (True) or by `EDGE_MARGIN` as on stairs
    up (False: the start of a cold plan, `gait_planner.ocp.solve`)."""

    slope: float = 0.0
    step_height: float = 0.0
    riser: float = 0.0
    tread: float = 0.0
    segment_rows: bool = True

    def __post_init__(self):
        for name in ("slope", "step_height", "riser", "tread"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise GroundError(f"{name} must be a finite number, got {value!r}")
        if not -45.0 < self.slope < 45.0:
            raise GroundError(f"slope must lie within (-45, 45) degrees, got {self.slope:g}")
        if self.slope != 0.0 and self.step_height != 0.0:
            raise GroundError(f"a ramp with stairs is not a ground this planner builds: "
                              f"slope {self.slope:g} deg and step_height {self.step_height:g} m; "
                              f"give one of them")
        if self.stairs and self.tread <= 0:
            raise GroundError(f"stairs need a positive tread depth (the step length), got "
                              f"{self.tread:g} m")

    @property
    def level(self) -> bool:
        return self.slope == 0.0 and self.step_height == 0.0

    @property
    def stairs(self) -> bool:
        return self.step_height != 0.0

    @property
    def normal(self) -> np.ndarray:
        """(3,) unit normal of the ramp (e_z on level ground and on treads)."""
        a = math.radians(self.slope)
        return np.array([-math.sin(a), 0.0, math.cos(a)])

    @property
    def rise_per_step(self) -> float:
        """Rise (m) of the mirror image per metre of step length: tan(slope)."""
        return math.tan(math.radians(self.slope))

    def rise(self, step: float) -> float:
        """Height (m) the mirror image of a half cycle of step length `step` m is shifted
        up: step tan(slope) + step_height."""
        return parametric_rise(self.parameters, step)

    def tread_height(self, tread: int) -> float:
        """Height (m) of tread `tread` (0: the standing foot's, 1: the landing foot's)."""
        return tread * self.step_height

    def repeat_at(self, x: float) -> tuple[float, float]:
        """(dx, dz) m: the translation that maps this ground onto itself and takes its
        point at x (m) back to where the half cycle's pinned point stands (x = 0, tread 0):
        on stairs k treads back and k step heights down (k the tread that holds x), on a
        ramp (x, x tan(slope)) along it; on level ground none, (0, 0): every shift along x
        maps it onto itself, and a transition joins the gait where its start stands
        (`ocp.transition.stance_offset`)."""
        if self.stairs:
            k = math.floor((x - self.riser) / self.tread) + 1
            return k * self.tread, k * self.step_height
        return (x, x * self.rise_per_step) if self.slope else (0.0, 0.0)

    def height(self, x) -> np.ndarray:
        """Ground height z (m) at x (m, array): x tan(slope) on a ramp, the tread's height on
        stairs (an edge belongs to the tread ahead of it)."""
        x = np.asarray(x, dtype=float)
        if self.stairs:
            return self.step_height * (np.floor((x - self.riser) / self.tread) + 1.0)
        return x * self.rise_per_step

    @property
    def edge_margin(self) -> float:
        """How far (m) towards the lower tread a swing point must be at the higher tread's
        height: `EDGE_MARGIN` on stairs up and on stairs down without segment rows, 0 on
        stairs down with them and without stairs."""
        if self.step_height > 0 or (self.step_height < 0 and not self.segment_rows):
            return EDGE_MARGIN
        return 0.0

    def clearance_height(self, x, sigmoid):
        """Smooth ground height (m) at x that a swing point must clear (stairs only): the
        treads' heights with each edge a smooth step of width `EDGE_WIDTH`, moved
        `edge_margin` and 5 widths towards the lower tread, for the edges -1, 0 and 1 (the
        three a half cycle's swing foot passes over, from tread -1 to tread 1). sigmoid: the
        logistic function of the caller's algebra (CasADi or numpy)."""
        return parametric_clearance_height(self.parameters, x, sigmoid)

    @property
    def descending(self) -> bool:
        return self.step_height < 0

    @property
    def form(self) -> str:
        """What of the ground shapes the NLP (its rows and their Functions), as opposed to
        its values (`parameters`): "plane" (level ground and ramps), "stairs up", "stairs
        down" (with the segment rows) or "stairs down, edge margin" (without them)."""
        if not self.stairs:
            return "plane"
        if self.step_height > 0:
            return "stairs up"
        return "stairs down" if self.segment_rows else "stairs down, edge margin"

    @property
    def parameters(self) -> np.ndarray:
        """(len(PARAMETERS),) the values a compiled problem reads (`ParametricGround`): the
        normal's x and z, rise per metre of step, step height m, riser m, tread m, and the
        edge's shift towards the lower tread m (`clearance_height`: (edge margin + 5 edge
        widths) signed with the step height; 0 without stairs)."""
        n = self.normal
        ahead = ((self.edge_margin + 5 * EDGE_WIDTH) * (1.0 if self.step_height > 0 else -1.0)
                 if self.stairs else 0.0)
        return np.array([n[0], n[2], self.rise_per_step, self.step_height, self.riser,
                         self.tread, ahead])

    def metadata(self) -> dict[str, str]:
        """The recording's metadata entries that name this ground (`verify` reads them on
        its own; `from_metadata` is the inverse)."""
        return {key: repr(float(getattr(self, field))) for field, key in _METADATA.items()}

    @classmethod
    def from_metadata(cls, metadata) -> "Ground":
        """The ground a recording's metadata (str -> str) names, absent entries 0 (level
        ground); GroundError naming the entry that is not a number or not a ground."""
        values = {}
        for field, key in _METADATA.items():
            try:
                values[field] = float(metadata.get(key, 0.0))
            except ValueError:
                raise GroundError(f"metadata {key} = {metadata[key]!r} is not a number") from None
        return cls(**values)


_METADATA = {"slope": "slope", "step_height": "step_height", "riser": "stair_riser",
             "tread": "stair_tread"}  # Ground field -> metadata entry


LEVEL = Ground()

# the entries of `Ground.parameters`, in order
PARAMETERS = ("normal_x", "normal_z", "rise_per_step", "step_height", "riser", "tread",
              "edge_ahead")


def parametric_rise(parameters, step):
    """`Ground.rise` of the ground of `parameters` (`Ground.parameters`, any algebra)."""
    return step * parameters[2] + parameters[3]


def parametric_clearance_height(parameters, x, sigmoid):
    """`Ground.clearance_height` of the ground of `parameters` (`Ground.parameters`, any
    algebra): h (sum of the three edges' smooth steps - 1), each edge shifted by the
    parameters' edge shift towards the lower tread."""
    h, riser, tread, ahead = (parameters[i] for i in (3, 4, 5, 6))
    steps = sum(sigmoid((x - riser - j * tread + ahead) / EDGE_WIDTH) for j in (-1, 0, 1))
    return h * (steps - 1.0)


class ParametricGround:
    """A ground of one `Ground.form` as CasADi expressions of its `Ground.parameters`
    (values: a (len(PARAMETERS),) DM, SX or MX column), with `Ground`'s algebra: one
    compiled Function serves every slope and stair height of the form. `inputs` are the
    symbols a Function built from it takes after its own inputs (none for constants)."""

    def __init__(self, values, form: str, inputs: tuple = ()):
        self.values, self.form, self.inputs = values, form, inputs

    @classmethod
    def symbols(cls, ground: Ground) -> "ParametricGround":
        """Symbols (SX) for the parameters of grounds of `ground`'s form."""
        values = ca.SX.sym("ground", len(PARAMETERS))
        return cls(values, ground.form, (values,))

    @classmethod
    def of(cls, ground: "Ground | ParametricGround") -> "ParametricGround":
        """`ground` as CasADi expressions: a `Ground`'s parameters as constants."""
        return ground if isinstance(ground, ParametricGround) else \
            cls(ca.DM(ground.parameters), ground.form)

    def like(self, values) -> "ParametricGround":
        """The same form with other values (e.g. the parameter vector's MX entries)."""
        return ParametricGround(values, self.form)

    @property
    def stairs(self) -> bool:
        return self.form != "plane"

    @property
    def descending(self) -> bool:
        return self.form.startswith("stairs down")

    @property
    def segment_rows(self) -> bool:
        return self.form == "stairs down"

    @property
    def normal(self) -> list:
        """[n_x, 0, n_z]: the ramp's unit normal (`Ground.normal`)."""
        return [self.values[0], 0.0, self.values[1]]

    def rise(self, step):
        """`Ground.rise`: step tan(slope) + step_height."""
        return parametric_rise(self.values, step)

    def tread_height(self, tread: int):
        return tread * self.values[3]

    def along_normal(self, E: np.ndarray):
        """n . E (1, k) of rows E (3, k) (positions linear in q): their height above the
        ground's plane."""
        return sum(n * ca.DM(E[i : i + 1]) for i, n in enumerate(self.normal)
                   if not (isinstance(n, float) and n == 0.0))

    def clearance_height(self, x, sigmoid):
        """`Ground.clearance_height`."""
        return parametric_clearance_height(self.values, x, sigmoid)
