"""Rerun recordings (.rrd) written by a helper process, after the plan has been answered.

The node answers a plan once its MCAP recording is written and its topics are published;
the plan's .rrd (`gait_planner.io.rerun_view.save_rrd`, atomic) follows from a helper
process. So neither importing rerun (about 0.45 s, which a fresh node's first request
paid) nor writing the file (about 0.17 s for walker3d's half cycle; more for many joined
half cycles) holds up an answer or the next solve: the helper runs on another core, where
a thread would wait for the solver's hold on the interpreter (CasADi keeps Python's GIL
while IPOPT runs). The helper starts with the recorder and imports rerun meanwhile.

Recordings are written one after the other, in the order submitted (a later plan with the
same output name replaces an earlier one's file, as its MCAP did). A helper that dies is
replaced at the next submission; the recording it was writing is reported failed. A killed
process leaves at most a temporary file, which `gait_planner.io.atomic` removes at the next
start.
"""

from __future__ import annotations

import multiprocessing
import threading
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from multiprocessing.reduction import ForkingPickler
from pathlib import Path
from types import MappingProxyType
from typing import Callable

from gait_planner.result import PlanResult



def _read_only(items: dict) -> MappingProxyType:
    return MappingProxyType(items)


# Scenes hold read-only mappings (not picklable): the helper gets copies, wrapped again.
ForkingPickler.register(MappingProxyType, lambda m: (_read_only, (dict(m),)))

# Told when a recording is done: its path, or None and the error.
Done = Callable[[Path | None, BaseException | None], None]


def _load() -> None:
    """The helper's start: rerun and the recording code, before the first plan arrives."""
    import gait_planner.io.rerun_view  # noqa: F401


def _ready() -> bool:
    return True


def _save(result: PlanResult, path: Path) -> Path:
    from gait_planner.io.rerun_view import save_rrd

    return save_rrd(result, path)


class RrdRecorder:
    """Writes .rrd files in a helper process (started now); `submit` returns at once."""

    def __init__(self):
        self._lock = threading.Lock()
        self._idle = threading.Condition(self._lock)  # notified when a recording is reported
        self._pending: set[Future] = set()
        self._closed = False
        self._pool = self._start()

    @staticmethod
    def _start() -> ProcessPoolExecutor:
        pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_load)
        pool.submit(_ready)  # the helper starts (and imports rerun) now, not at the first plan
        return pool

    def submit(self, result: PlanResult, path: Path, done: Done) -> None:
        """Write `result` to `path` (atomically) in the helper; `done` is called from
        another thread when the file is complete, or with the error (at once if the
        recorder is closed)."""
        with self._lock:
            future = None if self._closed else self._submit(result, path)
        if future is None:
            done(None, RuntimeError(f"{path} not written: the recorder is closed "
                                    "(shutting down)"))
            return

        def finished(f: Future) -> None:
            error = f.exception()
            try:
                done(None if error else f.result(), error)
            finally:
                with self._lock:
                    self._pending.discard(f)
                    self._idle.notify_all()

        future.add_done_callback(finished)

    def _submit(self, result: PlanResult, path: Path) -> Future:
        """The helper's Future of the file (under the lock); a dead helper is replaced."""
        try:
            future = self._pool.submit(_save, result, path)
        except BrokenProcessPool:
            self._pool.shutdown(wait=False)
            self._pool = self._start()
            future = self._pool.submit(_save, result, path)
        self._pending.add(future)
        return future

    def close(self, timeout: float) -> bool:
        """Wait up to `timeout` s for the recordings submitted to be written and reported
        (`submit`'s done), then let the helper go (it finishes what it was given and ends).
        True if all were reported."""
        with self._lock:
            self._closed = True
            reported = self._idle.wait_for(lambda: not self._pending, timeout)
        self._pool.shutdown(wait=False, cancel_futures=False)
        return reported
