"""`gait_planner.ros.client.wait_until`, how the client looks for the node's service and
action server: it returns as soon as the check passes, and False once the timeout has
passed without it (rclpy's own waits sleep 0.25 s between checks)."""

from __future__ import annotations

import time

from gait_planner.ros import client


def test_returns_at_the_first_passing_check():
    checks = []

    def ready() -> bool:
        checks.append(time.monotonic())
        return len(checks) == 3

    assert client.wait_until(ready, timeout=10.0)
    assert len(checks) == 3
    gaps = [b - a for a, b in zip(checks, checks[1:])]
    assert all(client.POLL <= gap < 0.25 for gap in gaps), gaps


def test_false_after_the_timeout():
    checks = []
    start = time.monotonic()
    assert not client.wait_until(lambda: checks.append(1) or False, timeout=0.05)
    assert time.monotonic() - start >= 0.05
    assert len(checks) >= 2  # checked again before giving up


def test_a_passing_check_never_sleeps():
    assert client.wait_until(lambda: True, timeout=0.0)
