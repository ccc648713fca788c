"""PlanWorker's stop requests name the reservation they are meant for."""

from gait_planner.ros.worker import PlanWorker


def test_a_stop_for_an_earlier_reservation_does_not_stop_the_next_plan():
    worker = PlanWorker()
    assert worker.try_reserve()
    first = worker.ticket
    worker.run(lambda: None)  # the first plan ends, its reservation with it
    assert worker.try_reserve()
    assert not worker.request_stop(first)  # a late cancel of the first goal
    assert not worker.stopped()
    assert worker.request_stop(worker.ticket)
    assert worker.stopped()
