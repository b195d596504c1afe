"""OpenBLAS on one thread where our own code runs many small matrix products: OpenBLAS's threads,
spinning while they wait, fight our thread pools — or another process — for the cores (measured: a
4K convolution 3 s → 28 s on 2 busy cores; the Fraunhofer step of a PSF grid 2 → 90 GFLOP/s)."""

from __future__ import annotations

import ctypes
from contextlib import contextmanager
from functools import lru_cache


@lru_cache(maxsize=1)
def _openblas_threads():
    """(get, set) of the number of threads of the OpenBLAS that NumPy loaded, or None (other BLAS,
    not Linux)."""
    try:
        with open("/proc/self/maps") as f:
            paths = {line.split()[-1] for line in f if "openblas" in line.rsplit("/", 1)[-1].lower()}
        for path in sorted(paths):
            lib = ctypes.CDLL(path)
            for prefix in ("scipy_openblas", "openblas"):
                for suffix in ("64_", ""):
                    get = getattr(lib, f"{prefix}_get_num_threads{suffix}", None)
                    set_ = getattr(lib, f"{prefix}_set_num_threads{suffix}", None)
                    if get is not None and set_ is not None:
                        set_.argtypes, get.restype = [ctypes.c_int], ctypes.c_int
                        return get, set_
    except OSError:
        pass
    return None


@contextmanager
def single_threaded_blas():
    """OpenBLAS on one thread inside the block (no effect with another BLAS)."""
    api = _openblas_threads()
    if api is None:
        yield
        return
    get, set_ = api
    before = get()
    set_(1)
    try:
        yield
    finally:
        set_(before)


def set_threads(n: int) -> None:
    """OpenBLAS on `n` threads from now on (no effect with another BLAS)."""
    api = _openblas_threads()
    if api is not None:
        api[1](n)
