"""The process's thread pool, for work whose NumPy calls release the GIL (matrix products, random draws):
`in_threads` deals parts of a job to one thread per core this process may use."""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache


@lru_cache(maxsize=1)
def thread_pool() -> ThreadPoolExecutor:
    """One thread per core this process may use, kept for the process (the PSF's matrix products, the placing
    of a grid's nodes, the sensor's charges; starting threads each time took 3 ms a thread on a loaded
    machine)."""
    return ThreadPoolExecutor(len(os.sched_getaffinity(0)), thread_name_prefix="solas")


def in_threads(work, parts: list) -> None:
    """`work(part)` for each of `parts` on the pool's threads, the parts dealt out in turn; returns when all are done."""
    n = min(len(parts), len(os.sched_getaffinity(0)))
    if n <= 1:
        for part in parts:
            work(part)
        return
    list(thread_pool().map(lambda k: [work(p) for p in parts[k::n]], range(n)))
