"""This process's resident memory and the machine's available memory, read from Linux's
/proc (None where there is none), so that a problem too large for the machine is not built:
a refined grid (`strategies.plan_certified`) takes about twice its coarse problem's memory,
and a process the kernel's OOM killer ends (a node, with every request it serves) tells its
user nothing.

Measured 2026-12-07 (Unitree G1 drafted from its URDF, CasADi's derivatives, not compiled):
its problem on 40 intervals kept 3.64 GB after its build and IPOPT's instances (4.38 GB at
the build's peak), on 80 intervals 6.99 GB (8.45 GB at the peak): a refinement's peak is
`PEAK_PER_KEPT` times what it keeps, and what it keeps is the refinement's factor times what
the coarse problem kept. Refined again, to 160 intervals, its build would have needed about
17 GB beside the 10.8 GB the planner held: a CI run's test process grew to 24.3 GB of this
machine's 24 and was killed.
"""

from __future__ import annotations

import ctypes
import os

PEAK_PER_KEPT = 1.25  # a build's peak over what it keeps (G1 above: 1.20 and 1.21)
_PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096
# glibc's malloc_trim (None elsewhere), so that resident memory measures what is in use
_MALLOC_TRIM = getattr(ctypes.CDLL(None), "malloc_trim", None)


def release_free_heap() -> None:
    """Hand the heap's free pages back to the system (glibc; nothing elsewhere)."""
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)


def resident_bytes() -> int | None:
    """This process's resident memory (bytes), after the heap's free pages are handed back
    (`release_free_heap`); None where /proc/self/statm is missing."""
    release_free_heap()
    try:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * _PAGE
    except (OSError, IndexError, ValueError):
        return None


def available_bytes() -> int | None:
    """The memory the kernel can give without swapping (MemAvailable, bytes); None where
    /proc/meminfo is missing."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, IndexError, ValueError):
        return None
    return None


def gigabytes(count: int) -> str:
    """`count` bytes in GB for people, e.g. "17.4 GB"."""
    return f"{count / 1e9:.1f} GB"
