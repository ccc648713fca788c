"""Rerun recordings (.rrd) written by a helper process, after the plan has been answered.

The node answers a plan once its MCAP recording is written and its topics are published;
the plan's .rrd (`gait_planner.viz.rerun_view.save_rrd`, atomic) follows from a helper
process. So neither importing rerun (about 0.45 s, which a fresh node's first request
paid) nor writing the file (about 0.17 s for walker3d's half cycle; more for many joined
half cycles) holds up an answer or the next solve: the helper runs on another core, where
a thread would wait for the solver's hold on the interpreter (CasADi keeps Python's GIL
while IPOPT runs). The helper starts with the recorder and imports rerun meanwhile.

The helper is a plain ``python -c`` process of the same interpreter and the same
gait_planner, fed pickled (path, result) pairs on its stdin and answering (path, error)
on its stdout, one file after the other in the order submitted (a later plan with the same
output name replaces an earlier one's file, as its MCAP did). Not `multiprocessing`: its
spawned children run the parent's ``__main__`` script again, and a user's script that
builds a node at its top level would build one in the helper too. The helper ignores
SIGINT (a terminal's Ctrl-C reaches the whole process group; the node decides when to
stop) and ends when its stdin closes, after the files it was given. A helper that dies is
replaced at the next submission; what it had not written is reported failed. A killed
process leaves at most a temporary file, which `gait_planner.atomic` removes at the
next start.
"""

from __future__ import annotations

import collections
import copyreg
import io
import os
import pickle
import queue
import signal
import subprocess
import sys
import threading
from pathlib import Path
from types import MappingProxyType
from typing import Callable

import gait_planner
from gait_planner.result import PlanResult

# Told when a recording is done: its path, or None and the error.
Done = Callable[[Path | None, BaseException | None], None]

_ROOT = str(Path(gait_planner.__file__).resolve().parent.parent)  # the helper imports this copy
_HELPER = [sys.executable, "-c", f"import sys; sys.path.insert(0, {_ROOT!r}); "
           "from gait_planner.viz.rrd_recorder import helper_main; helper_main()"]


def _read_only(items: dict) -> MappingProxyType:
    return MappingProxyType(items)


def _dumps(item: object) -> bytes:
    """pickle, with the scenes' read-only mappings (not picklable) as copies wrapped again."""
    buffer = io.BytesIO()
    pickler = pickle.Pickler(buffer, pickle.HIGHEST_PROTOCOL)
    pickler.dispatch_table = {**copyreg.dispatch_table,
                              MappingProxyType: lambda m: (_read_only, (dict(m),))}
    pickler.dump(item)
    return buffer.getvalue()


def helper_main() -> None:
    """The helper: (path, result) pairs from stdin, (written path, None) or (None, error)
    to stdout, until stdin closes. Anything else printed goes to stderr."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    answers = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # rerun's or numpy's messages must not corrupt the answers
    from gait_planner.viz.rerun_view import save_rrd

    requests = sys.stdin.buffer
    while True:
        try:
            path, result = pickle.load(requests)
        except EOFError:
            return
        try:
            answer = (save_rrd(result, path), None)
        except Exception as err:  # noqa: BLE001  (reported to the node, which logs it)
            answer = (None, err)
        try:
            data = _dumps(answer)
        except Exception:  # noqa: BLE001  (an error that does not pickle: its words)
            data = _dumps((None, RuntimeError(f"{type(answer[1]).__name__}: {answer[1]}")))
        answers.write(data)
        answers.flush()


class _Helper:
    """One helper process, the files it was given and not yet answered, and the threads
    that feed it and read its answers."""

    def __init__(self, report: Callable[[Done, Path | None, BaseException | None], None]):
        self.process = subprocess.Popen(_HELPER, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self.waiting: collections.deque[tuple[Path, Done]] = collections.deque()
        self.outbox: queue.Queue = queue.Queue()
        self._report = report
        threading.Thread(target=self._feed, name="rrd_helper_feed", daemon=True).start()
        threading.Thread(target=self._read, name="rrd_helper_read", daemon=True).start()

    def _feed(self) -> None:
        """Pickle and send what `outbox` holds (here, so that a submission never waits for
        the helper), until None: then close the helper's stdin."""
        while (item := self.outbox.get()) is not None:
            try:
                self.process.stdin.write(_dumps(item))
                self.process.stdin.flush()
            except OSError:  # the helper died: `_read` reports what it held
                break
        try:
            self.process.stdin.close()
        except OSError:
            pass

    def _read(self) -> None:
        """Report each answer to the submission it belongs to; when the helper ends, report
        the rest as not written."""
        while True:
            try:
                written, error = pickle.load(self.process.stdout)
            except (EOFError, OSError, pickle.UnpicklingError):
                break
            _, done = self.waiting.popleft()
            self._report(done, written, error)
        code = self.process.wait()
        while self.waiting:
            path, done = self.waiting.popleft()
            self._report(done, None, RuntimeError(
                f"{path} not written: the .rrd helper process ended (exit code {code})"))


class RrdRecorder:
    """Writes .rrd files in a helper process (started now); `submit` returns at once."""

    def __init__(self):
        self._lock = threading.Lock()
        self._idle = threading.Condition(self._lock)  # notified when a recording is reported
        self._outstanding = 0  # submitted and not yet reported
        self._closed = False
        self._helper = _Helper(self._report)

    def submit(self, result: PlanResult, path: Path, done: Done) -> None:
        """Write `result` to `path` (atomically) in the helper; `done` is called from
        another thread when the file is complete, or with the error (at once if the
        recorder is closed)."""
        with self._lock:
            if not self._closed:
                if self._helper.process.poll() is not None:  # it died: a new one
                    self._helper.outbox.put(None)  # (ends its feeding thread)
                    self._helper = _Helper(self._report)
                self._outstanding += 1
                self._helper.waiting.append((path, done))
                self._helper.outbox.put((str(path), result))
                return
        done(None, RuntimeError(f"{path} not written: the recorder is closed (shutting down)"))

    def _report(self, done: Done, path: Path | None, error: BaseException | None) -> None:
        try:
            done(None if path is None else Path(path), error)
        finally:
            with self._lock:
                self._outstanding -= 1
                self._idle.notify_all()

    def close(self, timeout: float) -> bool:
        """Wait up to `timeout` s for the recordings submitted to be written and reported
        (`submit`'s done), then let the helper go (it finishes what it was given and ends).
        True if all were reported."""
        with self._lock:
            self._closed = True
            self._helper.outbox.put(None)
            return self._idle.wait_for(lambda: self._outstanding == 0, timeout)
