"""PSF grids computed from a lens, cached on disk by the lens's hash and every sampling option, so
that a repeated batch (or a second batch with the same lens and options) reuses its grid.

The default folder is the user's cache directory (`platformdirs`), e.g. ~/.cache/solas-mi/psf-grids.
`hits` and `misses` count what this cache object served.
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path
from typing import Any

from ..errors import SolasError
from ..options import floats, parse_wxh

# the options of `psf_grid` a batch passes, with their defaults (those of `solas-mi psf-grid`)
GRID_OPTIONS = ("grid", "wavelengths", "field_range_deg", "field_sampling", "pitch_um", "size", "method",
                "normalize", "pupil_samples", "rays", "auto_window")


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


def canonical_options(options: dict[str, Any] | None) -> dict[str, Any]:
    """Every option of the grid, defaults filled in and values canonical (so equal grids share a key).
    SolasError for an unknown option or a malformed value."""
    from ..psf.base import DEFAULT_GEOMETRIC_RAYS, DEFAULT_PITCH_UM, DEFAULT_PUPIL_SAMPLES, DEFAULT_SIZE
    from ..psf.grid import FIELD_SAMPLINGS
    from ..psf.methods import DEFAULT_METHOD

    given = dict(options or {})
    unknown = sorted(set(given) - set(GRID_OPTIONS))
    if unknown:
        raise SolasError(f"grid options {', '.join(unknown)} are unknown; allowed: {', '.join(GRID_OPTIONS)}")
    out = {"grid": "8x8", "wavelengths": None, "field_range_deg": None, "field_sampling": FIELD_SAMPLINGS[0],
           "pitch_um": DEFAULT_PITCH_UM, "size": DEFAULT_SIZE, "method": DEFAULT_METHOD, "normalize": "sum",
           "pupil_samples": DEFAULT_PUPIL_SAMPLES, "rays": DEFAULT_GEOMETRIC_RAYS, "auto_window": False}
    out.update({k: v for k, v in given.items() if v is not None})
    rows, cols = parse_wxh(out["grid"], "--grid")
    out["grid"] = f"{cols}x{rows}"
    for name in ("wavelengths", "field_range_deg"):
        if isinstance(out[name], str):
            out[name] = floats(out[name], f"--{name.replace('_', '-')}")
        if out[name] is not None:
            out[name] = [float(v) for v in out[name]]
    if out["field_range_deg"] is not None and len(out["field_range_deg"]) not in (1, 2):
        raise SolasError(f"--field-range-deg {out['field_range_deg']} must be one value or X,Y")
    out["pitch_um"] = float(out["pitch_um"])
    return out


class GridCache:
    """PSF grids in `folder` (default: `default_cache_dir()`), one EXR per lens hash + options."""

    def __init__(self, folder: str | os.PathLike | None = None):
        self.folder = (Path(folder) if folder is not None else default_cache_dir()).expanduser().resolve()
        if self.folder.exists() and not self.folder.is_dir():
            raise SolasError(f"cache {str(self.folder)!r} exists and is not a folder")
        self.hits = 0
        self.misses = 0

    def path(self, lens, options: dict[str, Any]) -> Path:
        """Where the grid of `lens` with (canonical) `options` is kept."""
        key = json.dumps({"lens_hash": lens.hash, **options}, sort_keys=True)
        return self.folder / f"{lens.name}-{hashlib.sha256(key.encode()).hexdigest()[:16]}.exr"

    def get(self, lens, options: dict[str, Any] | None = None, progress=None) -> tuple[Path, bool, float]:
        """(path of the grid, whether it came from the cache, seconds spent computing it)."""
        from ..psf.grid import psf_grid

        canon = canonical_options(options)
        path = self.path(lens, canon)
        if path.is_file():
            self.hits += 1
            return path, True, 0.0
        self.misses += 1
        start = time.perf_counter()
        rng = canon["field_range_deg"]
        grid = psf_grid(lens, grid=parse_wxh(canon["grid"], "--grid"), wavelengths_nm=canon["wavelengths"],
                        field_range_deg=None if rng is None else (rng[0], rng[-1]), pitch_um=canon["pitch_um"],
                        size=canon["size"], method=canon["method"], normalization=canon["normalize"],
                        pupil_samples=canon["pupil_samples"], rays=canon["rays"],
                        field_sampling=canon["field_sampling"], progress=progress, auto_window=canon["auto_window"])
        grid.meta["cache_options"] = canon
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SolasError(f"cannot create cache folder {self.folder}: {exc.strerror or exc}") from None
        grid.write(str(path))  # atomic: a concurrent batch computing the same grid writes the same file
        return path, False, time.perf_counter() - start
