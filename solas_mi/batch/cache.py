"""PSF grids computed from a lens, cached on disk by the lens's hash and the grid's spec
(`psf.spec.GridSpec`, its canonical form: every option that makes the grid), so that a repeated
batch (or a second batch with the same lens and spec) reuses its grid. Each entry has a record beside
it (`NAME.exr.json`: its key — the lens's hash and the spec's canonical form — and its SHA-256); an
entry is reused only when its record matches the lens, the spec and the file's content, so a changed,
swapped or truncated entry is computed again, never passed off as the lens's grid.

The default folder is psf-grids in solas-mi's cache folder (`caches.cache_root`: $SOLAS_MI_CACHE_DIR, else the
user's cache directory), e.g. ~/.cache/solas-mi/psf-grids.
`hits` and `misses` count what this cache object served.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from .. import jsonio
from ..caches import cache_root, file_hash  # file_hash: imported from here too
from ..errors import SolasError
from ..outputs import inside, safe_name
from ..userfiles import read_text


def default_cache_dir() -> Path:
    """The grids' folder in solas-mi's cache folder (`caches.cache_root`)."""
    return cache_root() / "psf-grids"


class GridCache:
    """A folder of PSF grids, one EXR per lens and grid options, each checked before it is reused.

    Parameters
    ----------
    folder : str or PathLike, optional
        The folder; default: `default_cache_dir()`.

    Raises
    ------
    SolasError
        For a path that exists and is not a folder.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> from solas_mi.batch import GridCache
    >>> from solas_mi.psf import GridSpec
    >>> cache, lens, spec = GridCache("cache"), Lens.load("solas-doublet"), GridSpec(grid=(2, 2), size=32)
    >>> [cache.get(lens, spec)[1] for _ in range(2)]  # computed, then from the cache
    [False, True]
    """

    def __init__(self, folder: str | os.PathLike | None = None):
        self.folder = (Path(folder) if folder is not None else default_cache_dir()).expanduser().resolve()
        if self.folder.exists() and not self.folder.is_dir():
            raise SolasError(f"cache {str(self.folder)!r} exists and is not a folder")
        self.hits = 0
        self.misses = 0

    def path(self, lens, spec) -> Path:
        """Where the grid of a lens with some grid options is kept.

        Parameters
        ----------
        lens : Lens
            The lens.
        spec : GridSpec
            The grid's options.

        Returns
        -------
        Path
            In the folder, named by the lens (made a safe file name: a lens file's name is user data) and
            the hash of the lens's hash and the spec's canonical form.
        """
        return inside(self.folder, f"{safe_name(lens.name, 'lens')}-{spec.key(lens.hash)}.exr")

    @staticmethod
    def entry_key(lens, spec) -> dict:
        """What an entry is the grid of.

        Parameters
        ----------
        lens : Lens
            The lens.
        spec : GridSpec
            The grid's options.

        Returns
        -------
        dict
            The lens's hash and the spec's canonical form.
        """
        return {"lens_hash": lens.hash, "grid_spec": spec.canonical()}

    def check(self, path: Path, lens, spec) -> str | None:
        """Whether an entry is the grid of a lens with some options, whole.

        Parameters
        ----------
        path : Path
            The entry.
        lens : Lens
            The lens.
        spec : GridSpec
            The grid's options.

        Returns
        -------
        str or None
            None when its record beside it (``NAME.exr.json``) holds its key and its SHA-256, both
            matching; else why it is not reused.
        """
        try:
            record = jsonio.loads(read_text(f"{path}.json", "record"))
        except (OSError, ValueError):
            return "it has no readable record of its key and checksum"
        if not isinstance(record, dict) or record.get("key") != jsonio.loads(jsonio.dumps(self.entry_key(lens, spec))):
            return "its record names another lens or grid options"
        if record.get("sha256") != file_hash(path, full=True):
            return "its content does not match its checksum (changed or truncated)"
        return None

    def get(self, lens, spec, progress=None) -> tuple[Path, bool, float]:
        """The grid of a lens with some options: from the cache, or computed and kept.

        An entry that fails its check (`check`) is said so on stderr and computed again.

        Parameters
        ----------
        lens : Lens
            The lens.
        spec : GridSpec
            The grid's options.
        progress : callable, optional
            Told the PSFs done while the grid is computed (`psf.grid.psf_grid`).

        Returns
        -------
        tuple
            (the grid's path, whether it came from the cache, seconds spent computing it).

        Raises
        ------
        SolasError
            For a cache folder that cannot be created, or a grid that cannot be computed.
        """
        from ..imageio import write_text
        from ..psf.depth import make_grid

        path = self.path(lens, spec)
        if path.is_file():
            why = self.check(path, lens, spec)
            if why is None:
                self.hits += 1
                return path, True, 0.0
            print(f"cache entry {path} is not reused: {why}; computing the grid again", file=sys.stderr, flush=True)
        self.misses += 1
        start = time.perf_counter()
        grid = make_grid(lens, spec, progress=progress)  # its metadata holds the spec (meta["grid_spec"])
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SolasError(f"cannot create cache folder {self.folder}: {exc.strerror or exc}") from None
        grid.write(str(path))  # atomic: a concurrent batch computing the same grid writes the same file
        write_text(
            f"{path}.json",
            jsonio.dumps({"key": self.entry_key(lens, spec), "sha256": file_hash(path, full=True)}, indent=1) + "\n",
        )
        return path, False, time.perf_counter() - start
