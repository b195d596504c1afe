"""`psf`, the PSF at one field, and `compute`, the one dispatcher of the PSF methods of `registry`
(`METHODS`, a `solas_mi.registry.Registry`: name → function and its own options), which every caller
uses (`psf`, PSF grids, the cross-validation, the benchmarks).
"""

from __future__ import annotations

import numpy as np

from ..errors import SolasError
from ..optics.lens_checks import as_built
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
from .registry import DEFAULT_METHOD, MAX_SAMPLING, METHODS, check_method, method_options

__all__ = ["DEFAULT_METHOD", "MAX_SAMPLING", "METHODS", "check_method", "compute", "method_options", "psf"]


def compute(
    lens,
    field_deg: np.ndarray,
    wavelength_nm: np.ndarray,
    pitch_um: float,
    size: int,
    method: str,
    *,
    shared_origin: bool = False,
    **options,
) -> Computed:
    """Unnormalised PSFs (n, size, size) in 1/µm² for field/wavelength pairs by `method`, each grid's
    origin on its chief ray or, with `shared_origin`, all on the first one's. `options`: the methods'
    own (`registry.METHODS`: each method's options); those of other methods are ignored."""
    own = method_options(method, options)
    if as_built(lens):  # the symmetric paths do not take it: those of the lens as built (`as_built_methods`)
        from . import as_built_methods

        return as_built_methods.compute(
            lens, field_deg, wavelength_nm, pitch_um, size, method, shared_origin=shared_origin, **own
        )
    return METHODS[method].function(lens, field_deg, wavelength_nm, pitch_um, size, shared_origin=shared_origin, **own)


# long: the public API's numpydoc docstring is half of it
def psf(
    lens,
    field_deg,
    wavelength_nm,
    *,
    weights=None,
    pitch_um: float = DEFAULT_PITCH_UM,
    size: int = DEFAULT_SIZE,
    method: str = DEFAULT_METHOD,
    normalization: str = "sum",
    auto_window: bool = False,
    **options,
) -> PSF:
    """The PSF of one field, monochromatic or polychromatic.

    Several wavelengths give the power-weighted sum of their PSFs, all on the first one's chief ray, so
    lateral colour shows. The window is centred on the chief ray (where the chief ray is blocked, on the
    centroid of the light that arrives); [PSFs in depth](../details/convolution.md).

    Parameters
    ----------
    lens : Lens
        The lens.
    field_deg : float or (float, float)
        The field: (x, y) degrees, or one value y.
    wavelength_nm : float or sequence of float
        One wavelength (nm), or several.
    weights : sequence of float, optional
        Power weights of the wavelengths; default: equal.
    pitch_um : float, default 0.5
        The pixel pitch on the image plane (µm).
    size : int, default 160
        Pixels per side.
    method : str, default "fraunhofer"
        A name of `registry.METHODS`.
    normalization : str, default "sum"
        One of `base.NORMALIZATIONS`.
    auto_window : bool, default False
        Double `size` until the window holds `base.WINDOW_ENERGY_LIMIT` of the transmitted light.
    **options
        The methods' own options (`registry.METHODS`: ``pupil_samples``, ``rays``); each method takes its
        own and leaves the others.

    Returns
    -------
    PSF
        The PSF; ``meta["energy_in_grid"]`` is the window's share of the transmitted light and
        ``meta["warnings"]`` what looked doubtful.

    Raises
    ------
    SolasError
        For a bad field, wavelength, weight, grid or option, or a field whose every ray is blocked.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> from solas_mi.psf import psf
    >>> one = psf(Lens.load("solas-doublet"), (0, 2), 531.0, size=64)
    >>> one.data.shape, round(float(one.data.sum()), 6), one.method
    ((64, 64), 1.0, 'fraunhofer')
    """
    check_lens(lens)
    field = lens.field_type.check(field_deg)
    check_grid(pitch_um, size)
    own = method_options(method, options)
    check_normalization(normalization)
    wavelengths = check_wavelengths(lens, wavelength_nm)
    power_weights = _weights(weights, len(wavelengths))
    while True:
        result = _psf(lens, field, wavelengths, power_weights, pitch_um, size, method, normalization, own)
        if not (auto_window and result.meta["energy_in_grid"] < WINDOW_ENERGY_LIMIT and 2 * size <= MAX_SIZE):
            return result
        size *= 2


def _weights(weights, n: int) -> np.ndarray:
    """Power weights of n wavelengths (default: equal), summing to 1."""
    try:
        given = np.ones(n) if weights is None else np.asarray(weights, dtype=np.float64)
    except (TypeError, ValueError):
        given = np.zeros(0)
    if given.shape != (n,) or np.any(given < 0) or not np.isfinite(given).all() or given.sum() <= 0:
        raise SolasError(f"weights {weights!r} must be {n} non-negative numbers, not all zero")
    return given / given.sum()


def _psf(lens, field, wavelengths, power_weights, pitch_um, size, method, normalization, own) -> PSF:
    """One computation of `psf` at one window size."""
    fields = np.repeat(np.array([field]), len(wavelengths), axis=0)
    # all wavelengths share one origin, the first wavelength's chief ray, so lateral colour shows
    computed = compute(lens, fields, np.array(wavelengths), pitch_um, size, method, shared_origin=True, **own)
    centre_um = computed.centre_um if bool(computed.chief.vignetted[0]) else None  # the light's centroid, if needed
    light = centre_um is not None
    origin = computed.chief.image_xy[0] + (
        centre_um[0] * 1e-3 if centre_um is not None else 0.0
    )  # the window's centre, mm
    blocked = sorted({s for v in computed.vignetted_by for s in v})
    if not np.dot(power_weights, computed.transmission) > 0:
        raise SolasError(
            f"no light reaches the image at field ({field[0]:g}, {field[1]:g}) deg: every ray is blocked"
            + (f" (by surfaces {', '.join(map(str, blocked))})" if blocked else "")
        )
    total = np.tensordot(power_weights, computed.data, axes=1)
    energy = float(window_energy(total, pitch_um, np.dot(power_weights, computed.transmission)))
    meta = describe(lens, method, normalization, own, size)
    if as_built(lens):
        from .as_built_methods import PATHS

        meta["path"] = PATHS[method]
    meta.update(
        {
            "chief_ray_mm": {f"{w:g}": computed.chief.image_xy[i].tolist() for i, w in enumerate(wavelengths)},
            "centre": "centroid of the arriving light (the chief ray is blocked)" if light else "chief ray",
            "transmission": float(np.dot(power_weights, computed.transmission)),
            "energy_in_grid": energy,
            "vignetted_by_surfaces": blocked,
            "warnings": [*computed.warnings, *window_warnings(energy, np.array([field]), size, pitch_um)],
        }
    )
    return PSF(
        normalize(total, normalization),
        float(pitch_um),
        field,
        wavelengths,
        tuple(power_weights.tolist()),
        tuple(origin.tolist()),
        method,
        normalization,
        meta,
    )
