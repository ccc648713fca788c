"""The grid of a gait library: request fields and the values each takes.

A grid is written as the command line takes it: comma-separated axes
``field=start:stop:step`` (stop included when the steps reach it, to within 1e-9) or
``field=v1/v2/v3``, e.g. ``step_length=0.4:0.9:0.05,friction_coefficient=0.4:1.0:0.2``.
The fields are request fields that take a number (`AXES`); every grid point is one plan
request, the product of the axes. Points are named by their indices along the axes
(`Grid.name`), and their neighbours are the points one index away along one axis: the
plans a point's plan is continued from (`gait_planner.gaitlib.build`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

# Request fields a grid may run over, and their units
AXES = {"step_length": "m", "friction_coefficient": "", "slope": "deg", "speed": "m/s",
        "step_height": "m"}
MAX_POINTS = 100_000


class GridError(ValueError):
    """A grid that cannot be read; the message names the axis and why."""


@dataclass(frozen=True)
class Grid:
    """axes: ((field, values), ...) in the order given; values ascending, distinct."""

    axes: tuple[tuple[str, tuple[float, ...]], ...]

    @property
    def fields(self) -> tuple[str, ...]:
        return tuple(field for field, _ in self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(values) for _, values in self.axes)

    def indices(self) -> list[tuple[int, ...]]:
        """Every point's indices, the last axis fastest."""
        return list(itertools.product(*(range(n) for n in self.shape)))

    def values(self, index: tuple[int, ...]) -> dict[str, float]:
        """The request fields of the point at `index`."""
        return {field: values[i] for (field, values), i in zip(self.axes, index)}

    def name(self, index: tuple[int, ...]) -> str:
        """The point's name: its indices, e.g. "p03-01" (a file name)."""
        return "p" + "-".join(f"{i:02d}" for i in index)

    def neighbours(self, index: tuple[int, ...]) -> list[tuple[int, ...]]:
        """The points one index away along one axis."""
        out = []
        for axis, n in enumerate(self.shape):
            for step in (-1, 1):
                i = index[axis] + step
                if 0 <= i < n:
                    out.append(index[:axis] + (i,) + index[axis + 1:])
        return out

    def text(self) -> str:
        """The grid in the command line's form, every value listed."""
        return ",".join(f"{field}=" + "/".join(f"{v:g}" for v in values)
                        for field, values in self.axes)


def _axis_values(field: str, text: str) -> tuple[float, ...]:
    def number(word: str) -> float:
        try:
            value = float(word)
        except ValueError:
            raise GridError(f"grid axis {field}: {word!r} is not a number") from None
        if not math.isfinite(value):
            raise GridError(f"grid axis {field}: {word!r} is not finite")
        return value

    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise GridError(f"grid axis {field}: {text!r} is not start:stop:step")
        start, stop, step = (number(p) for p in parts)
        if step <= 0 or stop < start:
            raise GridError(f"grid axis {field}: {text!r} needs step > 0 and stop >= start")
        count = math.floor((stop - start) / step + 1e-9) + 1
        if count > MAX_POINTS:
            raise GridError(f"grid axis {field}: {text!r} has {count} values")
        values = [round(start + i * step, 12) for i in range(count)]
    else:
        values = [number(word) for word in text.split("/")]
    if len(set(values)) != len(values):
        raise GridError(f"grid axis {field}: repeated values in {text!r}")
    return tuple(sorted(values))


def parse_grid(text: str) -> Grid:
    """The `Grid` of `text` (module docstring); GridError naming what is wrong."""
    axes: list[tuple[str, tuple[float, ...]]] = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        field, sep, values = part.partition("=")
        field = field.strip()
        if not sep:
            raise GridError(f"grid axis {part!r} is not field=values")
        if field not in AXES:
            raise GridError(f"grid axis {field!r} is not a request field a grid may run "
                            f"over; those are: {', '.join(AXES)}")
        if field in dict(axes):
            raise GridError(f"grid axis {field!r} is given twice")
        axes.append((field, _axis_values(field, values.strip())))
    if not axes:
        raise GridError("the grid has no axis (e.g. step_length=0.4:0.9:0.1)")
    grid = Grid(tuple(axes))
    if math.prod(grid.shape) > MAX_POINTS:
        raise GridError(f"the grid has {math.prod(grid.shape)} points, more than {MAX_POINTS}")
    return grid
