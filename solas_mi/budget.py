"""A job's memory, estimated before it starts and checked against the machine: a job that would not
fit in the memory that is free is refused (unless forced) instead of running the machine out of
memory halfway, and a large one says what it will take before it starts. Bytes throughout."""
from __future__ import annotations

import sys

from .errors import SolasError

LARGE = 1 << 30  # jobs above this announce their estimate on stderr


def available_memory() -> int | None:
    """Memory available to a new job (bytes), from /proc/meminfo; None where that cannot be read."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def size_text(n: float) -> str:
    return f"{n / 1e9:.1f} GB" if n >= 1e9 else f"{n / 1e6:.0f} MB"


def check_memory(job: str, need: float, force: bool = False, hint: str = "") -> None:
    """SolasError when `job` needs more than the free memory (unless `force`); a note on stderr for a
    large one."""
    free = available_memory()
    if free is not None and need > free and not force:
        raise SolasError(f"{job} needs about {size_text(need)} of memory and {size_text(free)} is free"
                         f"{'; ' + hint if hint else ''} (--force to try anyway)")
    if need > LARGE:
        print(f"{job}: about {size_text(need)} of memory", file=sys.stderr, flush=True)
