"""A gait library's folder and its index (SQLite).

    <folder>/library.json     what the library is: scene, gait, grid (`Manifest`)
    <folder>/index.sqlite     one row per finished grid point (`PlanRow`)
    <folder>/plans/<name>.mcap        the point's recording (`gait_planner.io.mcap_writer`)
    <folder>/plans/<name>.start.npz   its optimum, to continue neighbours from (`save_start`)

A point is finished when its row is in the index; a row is written only after the point's
files are complete (each written atomically, `gait_planner.atomic`), so the index never
lists a plan whose file is missing. Workers write their own rows (SQLite serialises the
writers), so a driver killed mid-build loses no finished plan, and a build on an existing
folder (`gaitlib.build`) plans only the points without a row.
"""

from __future__ import annotations

import dataclasses
import json
import sqlite3
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gait_planner.atomic import atomic_target
from gait_planner.ocp.warm_starts import StoredPlan

MANIFEST = "library.json"
INDEX = "index.sqlite"
PLANS = "plans"


class LibraryError(ValueError):
    """A library folder that cannot be used as asked; the message says why."""


@dataclass(frozen=True)
class Manifest:
    """scene: a scene name or file; gait: the scene's gait ("" = walk); grid: `Grid.text`;
    request: fixed request fields of every point (e.g. intervals_per_phase)."""

    scene: str
    gait: str
    grid: str
    request: dict


@dataclass(frozen=True)
class PlanRow:
    """One finished grid point. status "ok" (converged; `checks` says whether the
    certificate and the verifier passed) or "failed" (reason)."""

    name: str
    request: dict  # the request fields of the point
    status: str
    reason: str
    cost: float | None  # J of the scene's cost
    duration: float | None  # s, the half cycle
    sigma: list  # phase scalings
    iterations: int
    solve_time: float  # s, this point's planning (its attempts included)
    certificate: str  # the continuous-dynamics certificate's summary
    checks: str  # "pass" or the failures
    start: str  # where the plan started: "cold" or the neighbour's name
    attempts: int
    mcap: str  # file name in plans/ ("" if failed)


_COLUMNS = [f.name for f in dataclasses.fields(PlanRow)]
_JSON = ("request", "sigma")


def write_manifest(folder: Path, manifest: Manifest) -> None:
    """Create `folder` with its manifest, or check that the one there is the same library
    (LibraryError naming what differs)."""
    path = folder / MANIFEST
    if path.exists():
        old = read_manifest(folder)
        if old != manifest:
            differ = [f.name for f in dataclasses.fields(Manifest)
                      if getattr(old, f.name) != getattr(manifest, f.name)]
            raise LibraryError(
                f"{folder} holds another library: "
                + "; ".join(f"{n} {getattr(old, n)!r} there, {getattr(manifest, n)!r} asked"
                            for n in differ)
                + "; resume it with the same arguments or use a new folder")
        return
    (folder / PLANS).mkdir(parents=True, exist_ok=True)
    with atomic_target(path) as tmp:
        tmp.write_text(json.dumps(dataclasses.asdict(manifest), indent=1) + "\n")


def read_manifest(folder: Path) -> Manifest:
    try:
        return Manifest(**json.loads((folder / MANIFEST).read_text()))
    except FileNotFoundError:
        raise LibraryError(f"{folder} is not a gait library (no {MANIFEST})") from None
    except (ValueError, TypeError) as err:
        raise LibraryError(f"{folder / MANIFEST} cannot be read: {err}") from None


class LibraryIndex:
    """The index of the library in `folder` (module docstring)."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        self._db = sqlite3.connect(self.folder / INDEX, timeout=60.0)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute(f"CREATE TABLE IF NOT EXISTS plans ({_COLUMNS[0]} TEXT PRIMARY KEY, "
                         + ", ".join(_COLUMNS[1:]) + ")")
        self._db.commit()

    def close(self) -> None:
        self._db.close()

    def add(self, row: PlanRow) -> bool:
        """Record a finished point; False (and nothing changed) if it was already."""
        values = [json.dumps(v) if k in _JSON else v for k, v in dataclasses.asdict(row).items()]
        with self._db:
            cursor = self._db.execute(
                f"INSERT OR IGNORE INTO plans VALUES ({', '.join('?' * len(_COLUMNS))})", values)
        return cursor.rowcount == 1

    def rows(self) -> list[PlanRow]:
        """Every finished point, by name."""
        out = []
        for values in self._db.execute(f"SELECT {', '.join(_COLUMNS)} FROM plans ORDER BY name"):
            fields = {k: (json.loads(v) if k in _JSON else v) for k, v in zip(_COLUMNS, values)}
            out.append(PlanRow(**fields))
        return out

    def names(self) -> set[str]:
        return {name for (name,) in self._db.execute("SELECT name FROM plans")}


def start_path(folder: Path, name: str) -> Path:
    return Path(folder) / PLANS / f"{name}.start.npz"


def save_start(path: Path, plan: StoredPlan) -> None:
    """Write an optimum (`StoredPlan`) atomically."""
    with atomic_target(path) as tmp, open(tmp, "wb") as out:
        np.savez(out, step=plan.step, mu=plan.mu, x=plan.x, lam_x=plan.lam_x,
                 lam_g=plan.lam_g, qref=plan.qref)


def load_start(path: Path) -> StoredPlan:
    with np.load(path) as data:
        return StoredPlan(float(data["step"]), float(data["mu"]), data["x"], data["lam_x"],
                          data["lam_g"], data["qref"], f"the gait library ({path.name})")
