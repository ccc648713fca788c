"""Solved plans kept on disk, so that a fresh process re-plans warm instead of cold.

`Planner` keeps the optimum of every plan (primal and dual) to warm-start the next request of
the same problem. `WarmStartStore` keeps them beyond the process: in
`<cache folder>/plans/<key>.npz` (`gait_planner.ocp.compile.cache_folder`), one file per
problem, the key the SHA-256 of what the stored vectors mean: the scene file, the settings
that shape the problem (`ocp.transcription.shape_of`: the request's step length, friction,
slope, stair height and speed are parameters, kept with each plan), the NLP's size and the
source of the model, dynamics and transcription code. A stored plan is only a starting point: a
warm start is solved to the full tolerance and checked like any plan, so a stale or damaged
file costs iterations, never a wrong plan; one that cannot be read, or whose sizes do not
match, is ignored.

`gait-planner prepare` (run by `make setup`) plans each shipped scene's default request
into the library, and the node uses it: a fresh node's first walker3d request (the default)
re-plans from it in 1 IPOPT iteration instead of 64 cold, answered in 0.71 s instead of
2.91 s (benchmarks/node_latency.py, 2026-11-23); other requests as warm re-plans. A request
with cold_start = true ignores it, as it ignores the plans of the running process. A
problem's file keeps the MAX_PLANS newest plans of the processes that used it, and besides
them, pinned, the plans `prepare` made (the default, the scene's warm-start anchors, its
start from standing and its stop: a transition is kept like any plan, per problem shape),
so that a node answering many requests of one shape does not evict its anchors.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gait_planner.atomic import atomic_target
from gait_planner.ocp.compile import cache_folder

MAX_PLANS = 16  # per problem, besides its pinned plans; the oldest go first
_REQUEST = ("slope", "step_height", "speed")  # StoredPlan's request beyond step and mu
_FIELDS = ("step", "mu", "x", "lam_x", "lam_g", "qref", *_REQUEST, "pinned", "momentum")
_CODE = ("model", "dynamics", "ocp")  # packages whose source defines the stored vectors


@dataclass(frozen=True)
class StoredPlan:
    """An optimum to warm-start from: request (step length m, friction coefficient), the
    NLP's x (nx,) and multipliers lam_x (nx,), lam_g (ng,), the reference configurations
    qref (N-1, k) of its reparametrisation, where it came from ("this process" or the
    library file), and the rest of its request: slope deg, step height m, speed m/s (one
    problem serves every value of these, `ocp.transcription.shape_of`); pinned: planned by
    `gait-planner prepare` (the default and the warm-start anchors), never evicted by the
    plans a busy process keeps after it; momentum: a transition's start momentum (k,) N s
    (its node 0 is qref[0]), else empty."""

    step: float
    mu: float
    x: np.ndarray
    lam_x: np.ndarray
    lam_g: np.ndarray
    qref: np.ndarray
    source: str = "this process"
    slope: float = 0.0
    step_height: float = 0.0
    speed: float = 0.0
    pinned: bool = False
    momentum: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))

    @property
    def request(self) -> tuple[float, ...]:
        """(step, mu, slope, step_height, speed): what a later plan of it replaces."""
        return (self.step, self.mu, self.slope, self.step_height, self.speed)

    def on(self, settings) -> bool:
        """Whether it is a plan on the ground and at the speed of `settings`."""
        return (self.slope, self.step_height, self.speed) == (
            settings.slope, settings.step_height, settings.speed)


@functools.cache
def code_digest() -> str:
    """SHA-256 of the source of the model, dynamics and transcription code (what the stored
    vectors, and the preparation of a scene, depend on)."""
    root = Path(__file__).resolve().parent.parent
    digest = hashlib.sha256()
    for package in _CODE:
        for path in sorted((root / package).glob("*.py")):
            digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


class WarmStartStore:
    """The plans of earlier processes, by problem (module docstring)."""

    def __init__(self, folder: Path | None = None):
        self.folder = (cache_folder() if folder is None else Path(folder)) / "plans"

    @staticmethod
    def key(scene_source: str, fixed_settings: object, nx: int, ng: int) -> str:
        """The problem's key: SHA-256 of the scene text, repr of the settings that fix the
        problem, the NLP's size and the code that defines its vectors."""
        text = "\n".join([scene_source, repr(fixed_settings), f"{nx} {ng}", code_digest()])
        return hashlib.sha256(text.encode()).hexdigest()

    def path(self, key: str) -> Path:
        return self.folder / f"{key}.npz"

    def load(self, key: str, nx: int, ng: int) -> list[StoredPlan]:
        """The stored plans of problem `key` whose sizes match (nx, ng); [] if there is no
        readable file."""
        path = self.path(key)
        try:
            with np.load(path) as data:
                fields = {name: data[name] for name in _FIELDS}
        except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
            return []
        count = fields["step"].shape[0]
        shapes_ok = (fields["x"].shape == (count, nx) and fields["lam_x"].shape == (count, nx)
                     and fields["lam_g"].shape == (count, ng) and fields["qref"].ndim == 3
                     and fields["momentum"].ndim == 2 and fields["momentum"].shape[0] == count
                     and all(fields[name].shape == (count,)
                             for name in ("mu", *_REQUEST, "pinned")))
        finite = shapes_ok and all(np.all(np.isfinite(v)) for v in fields.values())
        if not finite:
            return []
        return [StoredPlan(float(fields["step"][i]), float(fields["mu"][i]), fields["x"][i],
                           fields["lam_x"][i], fields["lam_g"][i], fields["qref"][i],
                           f"the warm-start store ({path.name[:12]})",
                           *(float(fields[name][i]) for name in _REQUEST),
                           bool(fields["pinned"][i]), fields["momentum"][i])
                for i in range(count)]

    def save(self, key: str, plans: list[StoredPlan]) -> None:
        """Write the pinned plans and the newest MAX_PLANS others of `plans` (one per
        request: a later plan of the same `StoredPlan.request` replaces an earlier one, and
        stays pinned if that one was) as problem `key`'s file, atomically. An unwritable
        folder is not an error: nothing is kept."""
        kept: dict[tuple[float, ...], StoredPlan] = {}
        for plan in plans:
            earlier = kept.pop(plan.request, None)
            if earlier is not None and earlier.pinned and not plan.pinned:
                plan = dataclasses.replace(plan, pinned=True)
            kept[plan.request] = plan
        pinned = [p for p in kept.values() if p.pinned]
        newest = pinned + [p for p in kept.values() if not p.pinned][-MAX_PLANS:]
        if not newest:
            return
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            with atomic_target(self.path(key)) as tmp, open(tmp, "wb") as out:
                np.savez(out, **{name: np.array([getattr(p, name) for p in newest])
                                 for name in ("step", "mu", *_REQUEST, "pinned")},
                         x=np.stack([p.x for p in newest]),
                         lam_x=np.stack([p.lam_x for p in newest]),
                         lam_g=np.stack([p.lam_g for p in newest]),
                         qref=np.stack([p.qref for p in newest]),
                         momentum=np.stack([p.momentum for p in newest]))
        except OSError:
            return
