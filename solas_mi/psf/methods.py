"""`psf`, the PSF at one field, and `compute`, the one dispatcher of the PSF methods of `registry`
(`METHODS`, a `solas_mi.registry.Registry`: name → function and its own options), which every caller
uses (`psf`, PSF grids, the cross-validation, the benchmarks).
"""
from __future__ import annotations

import numpy as np

from ..errors import SolasError
from .base import (
    DEFAULT_PITCH_UM,
    DEFAULT_SIZE,
    MAX_SIZE,
    PSF,
    WINDOW_ENERGY_LIMIT,
    Computed,
    check_grid,
    check_lens,
    check_normalization,
    check_wavelengths,
    describe,
    normalize,
    window_energy,
    window_warnings,
)
from .registry import DEFAULT_METHOD, METHODS, MAX_SAMPLING, check_method, method_options

__all__ = ["DEFAULT_METHOD", "MAX_SAMPLING", "METHODS", "check_method", "compute", "method_options", "psf"]


def compute(lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, pitch_um: float, size: int, method: str, *,
            shared_origin: bool = False, **options) -> Computed:
    """Unnormalised PSFs (n, size, size) in 1/µm² for field/wavelength pairs by `method`, each grid's
    origin on its chief ray or, with `shared_origin`, all on the first one's. `options`: the methods'
    own (`registry.METHODS`: each method's options); those of other methods are ignored."""
    own = method_options(method, options)
    return METHODS[method].function(lens, field_deg, wavelength_nm, pitch_um, size, shared_origin=shared_origin, **own)


def psf(lens, field_deg, wavelength_nm, *, weights=None, pitch_um: float = DEFAULT_PITCH_UM,
        size: int = DEFAULT_SIZE, method: str = DEFAULT_METHOD, normalization: str = "sum", auto_window: bool = False,
        **options) -> PSF:
    """The PSF at `field_deg` (x, y degrees) for one wavelength (nm) or several with `weights`
    (polychromatic: the power-weighted sum of the monochromatic PSFs), by `method` with its own
    `options` (those of every method in `registry.METHODS`; each takes its own). meta["energy_in_grid"]
    is the fraction of the transmitted light inside the window and meta["warnings"] what looked
    doubtful; `auto_window` doubles `size` until the window holds `base.WINDOW_ENERGY_LIMIT` of the light."""
    check_lens(lens)
    field = lens.field_type.check(field_deg)
    check_grid(pitch_um, size)
    own = method_options(method, options)
    check_normalization(normalization)
    wavelengths = check_wavelengths(lens, wavelength_nm)
    w8 = _weights(weights, len(wavelengths))
    while True:
        result = _psf(lens, field, wavelengths, w8, pitch_um, size, method, normalization, own)
        if not (auto_window and result.meta["energy_in_grid"] < WINDOW_ENERGY_LIMIT and 2 * size <= MAX_SIZE):
            return result
        size *= 2


def _weights(weights, n: int) -> np.ndarray:
    """Power weights of n wavelengths (default: equal), summing to 1."""
    try:
        w8 = np.ones(n) if weights is None else np.asarray(weights, dtype=np.float64)
    except (TypeError, ValueError):
        w8 = np.zeros(0)
    if w8.shape != (n,) or np.any(w8 < 0) or not np.isfinite(w8).all() or w8.sum() <= 0:
        raise SolasError(f"weights {weights!r} must be {n} non-negative numbers, not all zero")
    return w8 / w8.sum()


def _psf(lens, field, wavelengths, w8, pitch_um, size, method, normalization, own) -> PSF:
    """One computation of `psf` at one window size."""
    fields = np.repeat(np.array([field]), len(wavelengths), axis=0)
    # all wavelengths share one origin, the first wavelength's chief ray, so lateral colour shows
    c = compute(lens, fields, np.array(wavelengths), pitch_um, size, method, shared_origin=True, **own)
    light = c.centre_um is not None and bool(c.chief.vignetted[0])
    origin = c.chief.image_xy[0] + (c.centre_um[0] * 1e-3 if light else 0.0)  # the window's centre, mm
    blocked = sorted({s for v in c.vignetted_by for s in v})
    if not np.dot(w8, c.transmission) > 0:
        raise SolasError(f"no light reaches the image at field ({field[0]:g}, {field[1]:g}) deg: every ray is blocked"
                         + (f" (by surfaces {', '.join(map(str, blocked))})" if blocked else ""))
    total = np.tensordot(w8, c.data, axes=1)
    energy = float(window_energy(total, pitch_um, np.dot(w8, c.transmission)))
    meta = describe(lens, method, normalization, own, size)
    meta.update({
        "chief_ray_mm": {f"{w:g}": c.chief.image_xy[i].tolist() for i, w in enumerate(wavelengths)},
        "centre": "centroid of the arriving light (the chief ray is blocked)" if light else "chief ray",
        "transmission": float(np.dot(w8, c.transmission)),
        "energy_in_grid": energy,
        "vignetted_by_surfaces": blocked,
        "warnings": [*c.warnings, *window_warnings(energy, np.array([field]), size, pitch_um)],
    })
    return PSF(normalize(total, normalization), float(pitch_um), field, wavelengths, tuple(w8.tolist()),
               tuple(origin.tolist()), method, normalization, meta)
