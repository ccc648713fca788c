"""One plan at a time, in a thread of its own that a stop request ends within an iteration.

The node's service and action callbacks reserve the worker (`try_reserve`: None = busy,
answered at once), then wait in `run` for the plan thread. A reservation that no `run` claims
within `RESERVATION_TIMEOUT` s lapses, and the next request takes it over: rclpy drops a
goal whose acceptance it failed to send with an RCLError (it logs "Failed to send goal
response"), and that goal must not keep the node busy for ever. (When Fast DDS has not yet
discovered the client's response reader 100 ms after the request, rclpy 9.1.2 only warns
"failed to send response (timeout)" and the goal runs; `gait_planner.ros.client.send_goal`
follows it by its feedback.) When the node shuts down (SIGINT, SIGTERM) `close` stops the
solve and lets every waiting callback return, so the executor never waits for a plan. The
build of a problem cannot be interrupted: the plan thread is a daemon, and
`gait_planner.ros.node.main` leaves without waiting for it (`wait_idle`).
"""

from __future__ import annotations

import threading
import time
from typing import Callable, TypeVar

from gait_planner.ocp.solve import STOPPED

T = TypeVar("T")
# phase, iteration, cost, violation (cost NaN: a phase change, iteration = the count so far)
Listener = Callable[[str, int, float, float], None]
# s from a reservation to its plan's start (`run`) after which the next request takes it over;
# a goal's plan starts milliseconds after its acceptance was sent
RESERVATION_TIMEOUT = 2.0
POLL = 0.1  # s, how often a caller waiting in `run` looks at the node's closing and ticks
# phases after the plan is found, in which a stop is refused: the plan is being recorded and
# published, or (node parameter walk_steps) the recorded plan is walked in MuJoCo
UNSTOPPABLE = ("recording", "walking")


class Stopped(Exception):
    """The plan was stopped (cancel or shutdown) before anything was recorded."""

    def __init__(self):
        super().__init__(STOPPED)


class Closed(Exception):
    """The node shut down while a caller waited for its plan."""


class Lapsed(Exception):
    """A reservation was claimed after it lapsed (`RESERVATION_TIMEOUT`) and another request
    had taken the worker over."""

    def __init__(self, ticket: int, current: int):
        super().__init__(
            f"busy: the plan's reservation (ticket {ticket}) lapsed before the plan could start "
            f"and request {current} holds the node now; try again later")


class PlanWorker:
    """Busy flag, stop flag, current phase and the plan thread of one node."""

    def __init__(self):
        self._busy = threading.Lock()  # held from reservation until the plan thread ends
        self._guard = threading.Lock()  # orders stop requests against entering "recording"
        self._stop = threading.Event()
        self._closed = threading.Event()
        self._listener: Listener | None = None
        self.phase, self.iterations = "", 0
        self.stopped_at: int | None = None  # the solver's iteration count when a stop was granted
        self.ticket = 0  # numbers the reservations: a stop names the plan it is meant for
        self._claimed, self._reserved_at = True, 0.0  # the current reservation's
        # on_lapse(ticket, age): told when a lapsed reservation is taken over (the node logs it)
        self.on_lapse: Callable[[int, float], None] | None = None

    def try_reserve(self) -> int | None:
        """Reserve the worker for one plan and return the reservation's ticket (it numbers
        the plans); None if a plan runs or is about to (or the node is closing). A reservation
        unclaimed (`run`) for `RESERVATION_TIMEOUT` s is taken over."""
        if self._closed.is_set():
            return None
        with self._guard:
            if not self._busy.acquire(blocking=False):
                age = time.monotonic() - self._reserved_at
                if self._claimed or age < RESERVATION_TIMEOUT:
                    return None
                if self.on_lapse is not None:  # the lock stays held: it is the new reservation's
                    self.on_lapse(self.ticket, age)
            self._stop.clear()
            self.phase, self.iterations, self.stopped_at = "", 0, None
            self.ticket += 1
            self._claimed, self._reserved_at = False, time.monotonic()
            return self.ticket

    def stopped(self) -> bool:
        """The planner's stop callback: True once a stop was requested."""
        return self._stop.is_set()

    def request_stop(self, ticket: int | None = None) -> bool:
        """Stop the running plan (with `ticket`: only the plan of that reservation, so that a
        late cancel never stops the next request); refused (False) once it is recording its
        result or walking it (`UNSTOPPABLE`) or when that plan is over."""
        with self._guard:
            if self.phase in UNSTOPPABLE or ticket not in (None, self.ticket):
                return False
            self._stop.set()
            self.stopped_at = self.iterations
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

    def detail(self, text: str) -> None:
        """Tell the current listener where the phase has got to, as the phase "<phase>
        (<text>)" (cost NaN); the phase itself, which decides whether a stop is refused,
        stays."""
        listener = self._listener
        if listener is not None:
            listener(f"{self.phase} ({text})", self.iterations, float("nan"), float("nan"))

    def progress(self, iteration: int, cost: float, violation: float) -> None:
        """Pass an IPOPT iteration on to the current listener."""
        self.iterations = iteration
        listener = self._listener
        if listener is not None:
            listener(self.phase, iteration, cost, violation)

    def run(self, ticket: int, work: Callable[[], T], listener: Listener | None = None,
            tick: Callable[[], None] | None = None) -> T:
        """Run `work` in the plan thread of the reservation `ticket` (`try_reserve`) and return
        its value (or raise its error); `listener` hears phases and iterations meanwhile, and
        `tick` is called in the caller's thread every `POLL` s while it waits.
        Raises `Lapsed` if another request took the reservation over, `Closed` if the node
        closes first. The reservation ends with the plan thread."""
        with self._guard:
            if ticket != self.ticket or self._claimed:
                raise Lapsed(ticket, self.ticket)
            self._claimed = True
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
        while not done.wait(POLL):
            if self._closed.is_set():
                raise Closed("the node is shutting down")
            if tick is not None:
                tick()
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
