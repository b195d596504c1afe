"""PSF grids computed from a lens, cached on disk by the lens's hash and the grid's spec
(`psf.spec.GridSpec`, its canonical form: every option that makes the grid), so that a repeated
batch (or a second batch with the same lens and spec) reuses its grid.

The default folder is the user's cache directory (`platformdirs`), e.g. ~/.cache/solas-mi/psf-grids.
`hits` and `misses` count what this cache object served.
"""
from __future__ import annotations

import hashlib
import os
import time
from pathlib import Path

from ..errors import SolasError


def default_cache_dir() -> Path:
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("solas-mi")) / "psf-grids"


def file_hash(path: str | os.PathLike) -> str:
    """The first 16 hex digits of the file's SHA-256."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()[:16]


class GridCache:
    """PSF grids in `folder` (default: `default_cache_dir()`), one EXR per lens hash + spec."""

    def __init__(self, folder: str | os.PathLike | None = None):
        self.folder = (Path(folder) if folder is not None else default_cache_dir()).expanduser().resolve()
        if self.folder.exists() and not self.folder.is_dir():
            raise SolasError(f"cache {str(self.folder)!r} exists and is not a folder")
        self.hits = 0
        self.misses = 0

    def path(self, lens, spec) -> Path:
        """Where the grid of `lens` with `spec` (a `psf.spec.GridSpec`) is kept: named by the lens and
        the hash of the lens's hash and the spec's canonical form."""
        return self.folder / f"{lens.name}-{spec.key(lens.hash)}.exr"

    def get(self, lens, spec, progress=None) -> tuple[Path, bool, float]:
        """(path of the grid of `lens` with `spec`, whether it came from the cache, seconds spent computing it)."""
        from ..psf.depth import make_grid

        path = self.path(lens, spec)
        if path.is_file():
            self.hits += 1
            return path, True, 0.0
        self.misses += 1
        start = time.perf_counter()
        grid = make_grid(lens, spec, progress=progress)  # its metadata holds the spec (meta["grid_spec"])
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SolasError(f"cannot create cache folder {self.folder}: {exc.strerror or exc}") from None
        grid.write(str(path))  # atomic: a concurrent batch computing the same grid writes the same file
        return path, False, time.perf_counter() - start
