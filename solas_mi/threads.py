"""How many threads this process's own pools run, and the pool: one thread per core it may use, or its share
of the cores where several processes run side by side (a batch's local workers, `use_share`). Two workers on
2 cores, each with a convolution pool of 2 threads and OpenBLAS's 2, put up to 8 busy threads on 2 cores, and
OpenBLAS's threads spin while they wait (`blas`). `in_threads` deals the parts of a job whose NumPy calls
release the GIL (matrix products, random draws) to the pool's threads."""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache

_SHARE: int | None = None  # this process's share of the cores, once a batch gave it one


def cores() -> int:
    """The cores this process may run on (its CPU affinity; the machine's where that is unknown)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # no affinity on this platform
        return os.cpu_count() or 1


def pool_threads() -> int:
    """The threads a pool of this process may run: its share of the cores (`use_share`), else its cores."""
    return _SHARE if _SHARE is not None else cores()


def share(processes: int) -> int:
    """Each of `processes` processes' share of this machine's cores (at least one thread)."""
    return max(1, cores() // processes)


def use_share(n: int) -> None:
    """From now on this process runs `n` threads at most in its pools (`pool_threads`) and in OpenBLAS."""
    from .blas import set_threads

    global _SHARE
    if n != _SHARE:
        _SHARE = n
        set_threads(n)


@lru_cache(maxsize=1)
def thread_pool() -> ThreadPoolExecutor:
    """One thread per core this process may use, kept for the process (the PSF's matrix products, the placing
    of a grid's nodes, the sensor's charges; starting threads each time took 3 ms a thread on a loaded
    machine)."""
    return ThreadPoolExecutor(cores(), thread_name_prefix="solas")


def in_threads(work, parts: list) -> None:
    """`work(part)` for each of `parts` on the pool's threads (at most `pool_threads`: a batch worker's share),
    the parts dealt out in turn; returns when all are done."""
    n = min(len(parts), pool_threads())
    if n <= 1:
        for part in parts:
            work(part)
        return
    list(thread_pool().map(lambda k: [work(p) for p in parts[k::n]], range(n)))
