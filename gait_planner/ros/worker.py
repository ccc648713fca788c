"""One plan at a time, in a thread of its own that a stop request ends within an iteration.

The node's service and action callbacks reserve the worker (`try_reserve`: False = busy,
answered at once), then wait in `run` for the plan thread. When the node shuts down (SIGINT,
SIGTERM) `close` stops the solve and lets every waiting callback return, so the executor
never waits for a plan. The build of a problem cannot be interrupted: the plan thread is a
daemon, and `gait_planner.ros.node.main` leaves without waiting for it (`wait_idle`).
"""

from __future__ import annotations

import threading
from typing import Callable, TypeVar

from gait_planner.ocp.solve import STOPPED

T = TypeVar("T")
# phase, iteration, cost, violation (cost NaN: a phase change, iteration = the count so far)
Listener = Callable[[str, int, float, float], None]


class Stopped(Exception):
    """The plan was stopped (cancel or shutdown) before anything was recorded."""

    def __init__(self):
        super().__init__(STOPPED)


class Closed(Exception):
    """The node shut down while a caller waited for its plan."""


class PlanWorker:
    """Busy flag, stop flag, current phase and the plan thread of one node."""

    def __init__(self):
        self._busy = threading.Lock()  # held from reservation until the plan thread ends
        self._guard = threading.Lock()  # orders stop requests against entering "recording"
        self._stop = threading.Event()
        self._closed = threading.Event()
        self._listener: Listener | None = None
        self.phase, self.iterations = "", 0
        self.ticket = 0  # numbers the reservations: a stop names the plan it is meant for

    def try_reserve(self) -> bool:
        """Reserve the worker for one plan (`ticket` then numbers it); False if a plan runs
        (or the node is closing)."""
        if self._closed.is_set() or not self._busy.acquire(blocking=False):
            return False
        with self._guard:
            self._stop.clear()
            self.phase, self.iterations = "", 0
            self.ticket += 1
        return True

    def stopped(self) -> bool:
        """The planner's stop callback: True once a stop was requested."""
        return self._stop.is_set()

    def request_stop(self, ticket: int | None = None) -> bool:
        """Stop the running plan (with `ticket`: only the plan of that reservation, so that a
        late cancel never stops the next request); refused (False) once it is recording its
        result or when that plan is over."""
        with self._guard:
            if self.phase == "recording" or ticket not in (None, self.ticket):
                return False
            self._stop.set()
            return True

    def enter(self, phase: str) -> None:
        """The planner's stage callback; entering "recording" after a stop raises `Stopped`,
        so that a stopped plan writes and publishes nothing."""
        with self._guard:
            if phase == "recording" and self._stop.is_set():
                raise Stopped()
            self.phase = phase
        listener = self._listener
        if listener is not None:
            listener(phase, self.iterations, float("nan"), float("nan"))

    def progress(self, iteration: int, cost: float, violation: float) -> None:
        """Pass an IPOPT iteration on to the current listener."""
        self.iterations = iteration
        listener = self._listener
        if listener is not None:
            listener(self.phase, iteration, cost, violation)

    def run(self, work: Callable[[], T], listener: Listener | None = None) -> T:
        """Run `work` in the plan thread of a reservation (`try_reserve`) and return its value
        (or raise its error); `listener` hears phases and iterations meanwhile. Raises
        `Closed` if the node closes first. The reservation ends with the plan thread."""
        outcome: dict = {}
        done = threading.Event()
        self._listener = listener

        def target() -> None:
            try:
                outcome["value"] = work()
            except BaseException as err:  # noqa: BLE001  (handed to the waiting caller)
                outcome["error"] = err
            finally:
                self._listener = None
                done.set()
                self._busy.release()

        threading.Thread(target=target, name="gait_planner_plan", daemon=True).start()
        while not done.wait(0.1):
            if self._closed.is_set():
                raise Closed("the node is shutting down")
        if "error" in outcome:
            raise outcome["error"]
        return outcome["value"]

    def closing(self) -> bool:
        """True once `close` was called (the node is shutting down)."""
        return self._closed.is_set()

    def close(self) -> None:
        """Stop the running plan, silence its listener (the node is going away) and release
        every caller waiting in `run`."""
        self._listener = None
        self._closed.set()
        self._stop.set()

    def wait_idle(self, timeout: float) -> bool:
        """Wait up to `timeout` s for the plan thread to end; True if no plan runs."""
        if not self._busy.acquire(timeout=timeout):
            return False
        self._busy.release()
        return True
