"""PlanWorker's stop requests name the reservation they are meant for; a reservation that
never starts its plan lapses, one that did never does; a caller waiting for its plan ticks
(the action's feedback heartbeat) in its own thread."""

import threading
import time

import pytest

from gait_planner.ros import worker as worker_module
from gait_planner.ros.worker import Lapsed, PlanWorker


def test_a_stop_for_an_earlier_reservation_does_not_stop_the_next_plan():
    worker = PlanWorker()
    first = worker.try_reserve()
    assert first is not None
    worker.run(first, lambda: None)  # the first plan ends, its reservation with it
    second = worker.try_reserve()
    assert second is not None
    assert not worker.request_stop(first)  # a late cancel of the first goal
    assert not worker.stopped()
    assert worker.request_stop(second)
    assert worker.stopped()


def test_an_unclaimed_reservation_lapses_and_its_late_plan_is_refused(monkeypatch):
    monkeypatch.setattr(worker_module, "RESERVATION_TIMEOUT", 0.05)
    worker, lapses = PlanWorker(), []
    worker.on_lapse = lambda ticket, age: lapses.append((ticket, age))
    lost = worker.try_reserve()  # a goal whose acceptance never reached its client
    assert worker.try_reserve() is None  # busy at first
    time.sleep(0.06)
    taken = worker.try_reserve()
    assert taken == lost + 1 and lapses[0][0] == lost and lapses[0][1] >= 0.05
    with pytest.raises(Lapsed, match="busy"):
        worker.run(lost, lambda: None)  # the lost goal, executed late after all
    assert worker.run(taken, lambda: 42) == 42
    assert worker.try_reserve() is not None  # the plan ended: free again


def test_a_running_plan_never_lapses(monkeypatch):
    monkeypatch.setattr(worker_module, "RESERVATION_TIMEOUT", 0.05)
    worker, release = PlanWorker(), threading.Event()
    ticket = worker.try_reserve()
    runner = threading.Thread(target=worker.run, args=(ticket, lambda: release.wait(5)))
    runner.start()
    time.sleep(0.2)
    assert worker.try_reserve() is None
    release.set()
    runner.join(5)
    assert worker.try_reserve() == ticket + 1


def test_the_waiting_caller_ticks_in_its_own_thread_until_the_plan_ends():
    worker, release, ticks = PlanWorker(), threading.Event(), []
    ticket = worker.try_reserve()
    caller = threading.get_ident()

    def tick() -> None:
        ticks.append(threading.get_ident())
        if len(ticks) == 3:
            release.set()

    assert worker.run(ticket, lambda: release.wait(5) and "planned", tick=tick) == "planned"
    assert len(ticks) == 3 and set(ticks) == {caller}
