"""`gait_planner.memory`: resident memory measured as the kernel counts it, and the memory
available, against which a refinement's build is weighed."""

from __future__ import annotations

import numpy as np

from gait_planner.memory import available_bytes, gigabytes, resident_bytes


def test_resident_memory_counts_an_array_while_it_lives():
    before = resident_bytes()
    block = np.ones(50_000_000)  # 400 MB, every page touched
    during = resident_bytes()
    del block
    after = resident_bytes()
    assert abs(during - before - 400e6) < 40e6
    assert abs(after - before) < 40e6  # handed back once freed


def test_available_memory_is_within_the_machine():
    with open("/proc/meminfo") as meminfo:
        total = int(next(line for line in meminfo if line.startswith("MemTotal:")).split()[1])
    assert 0 < available_bytes() <= total * 1024


def test_gigabytes_for_people():
    assert gigabytes(17_412_000_000) == "17.4 GB"
