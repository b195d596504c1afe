"""NumPy's transparent huge pages off inside a block (`small_pages`).

NumPy asks the kernel for huge pages on every array of 4 MB or more (madvise). Where the kernel's THP
defrag setting is "madvise" (this project's 2-core machines), each first touch of such memory compacts
memory to find a 2 MB page: measured, 0.6 CPU-s to fill a fresh 315 MB array (a 32x32x3 grid of 160²
PSFs) against 0.13 s with 4 kB pages, and the PSF grid's many fresh working arrays paid it too (a
32x32x3 grid 25 % faster with 4 kB pages).
"""

from __future__ import annotations

from contextlib import contextmanager


@contextmanager
def small_pages():
    """NumPy's huge-page advice off inside the block (no effect where NumPy has no such setting)."""
    try:
        from numpy._core import multiarray

        get, set_ = multiarray._get_madvise_hugepage, multiarray._set_madvise_hugepage
    except (ImportError, AttributeError):
        yield
        return
    before = get()
    set_(False)
    try:
        yield
    finally:
        set_(before)
