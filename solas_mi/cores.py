"""How many threads this process's own pools run: one per core it may use, or its share of the cores where
several processes run side by side (a batch's local workers, `use_share`). Two workers on 2 cores, each with a
convolution pool of 2 threads and OpenBLAS's 2, put up to 8 busy threads on 2 cores, and OpenBLAS's threads spin
while they wait (`blas`)."""

from __future__ import annotations

import os

_SHARE: int | None = None  # this process's share of the cores, once a batch gave it one


def cores() -> int:
    """The cores this process may run on (its CPU affinity; the machine's where that is unknown)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # no affinity on this platform
        return os.cpu_count() or 1


def threads() -> int:
    """The threads a pool of this process may run: its share of the cores (`use_share`), else its cores."""
    return _SHARE if _SHARE is not None else cores()


def share(processes: int) -> int:
    """Each of `processes` processes' share of this machine's cores (at least one thread)."""
    return max(1, cores() // processes)


def use_share(n: int) -> None:
    """From now on this process runs `n` threads at most in its pools (`threads`) and in OpenBLAS."""
    from .blas import set_threads

    global _SHARE
    if n != _SHARE:
        _SHARE = n
        set_threads(n)
