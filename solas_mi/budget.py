"""A job's memory, estimated before it starts and checked against the machine: a job that would not
fit in the memory that is free is refused (unless forced) instead of running the machine out of
memory halfway, and a large one says what it will take before it starts. Bytes throughout."""

from __future__ import annotations

import sys

from .errors import SolasError

LARGE = 1 << 30  # jobs above this announce their estimate on stderr


def available_memory() -> int | None:
    """Memory available to a new job (bytes): the machine's (MemAvailable, /proc/meminfo), and no more
    than this process may still map under its address-space limit (RLIMIT_AS, `ulimit -v`: the limit
    less its VmSize); None where neither can be read."""
    free = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    free = int(line.split()[1]) * 1024
                    break
    except OSError:
        pass
    room = _address_space_left()
    return room if free is None else free if room is None else min(free, room)


def _address_space_left() -> int | None:
    """Bytes this process may still map under RLIMIT_AS; None without a limit."""
    import resource

    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    if limit == resource.RLIM_INFINITY:
        return None
    try:
        with open("/proc/self/status") as f:
            used = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmSize:"))
    except (OSError, StopIteration):
        used = 0
    return max(0, limit - used)


def size_text(n: float) -> str:
    return f"{n / 1e9:.1f} GB" if n >= 1e9 else f"{n / 1e6:.0f} MB"


def check_memory(job: str, need: float, force: bool = False, hint: str = "") -> None:
    """SolasError when `job` needs more than the free memory (unless `force`); a note on stderr for a
    large one."""
    free = available_memory()
    if free is not None and need > free and not force:
        raise SolasError(
            f"{job} needs about {size_text(need)} of memory and {size_text(free)} is free"
            f"{'; ' + hint if hint else ''} (--force to try anyway)"
        )
    if need > LARGE:
        print(f"{job}: about {size_text(need)} of memory", file=sys.stderr, flush=True)
