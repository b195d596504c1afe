"""The PSF methods by name — the one list every caller uses (Python, CLI, PSF grids, the
cross-validation) — and `psf`, the PSF at one field.

Each method is a module of this package with one entry point,

    compute(lens, field_deg, wavelength_nm, pitch_um, size, sampling, shared_origin=False) -> Computed

for n field/wavelength pairs (`base.Computed`: unnormalised PSFs in 1/µm², chief rays, transmitted
power, vignetting surfaces). Method modules load Dr.Jit; the registry imports one only when it
computes, so the command line and the conventions of `base` stay light.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from .base import (
    DEFAULT_GEOMETRIC_RAYS,
    DEFAULT_PITCH_UM,
    DEFAULT_PUPIL_SAMPLES,
    DEFAULT_SIZE,
    MAX_SIZE,
    PSF,
    WINDOW_ENERGY_LIMIT,
    Computed,
    check_grid,
    check_normalization,
    describe,
    normalize,
    window_energy,
    window_warnings,
)


@dataclass(frozen=True)
class Method:
    """A PSF method: the module that computes it (relative to this package) and its one sampling
    parameter."""

    name: str
    module: str
    sampling: str  # the keyword that sets its sampling: "pupil_samples" (N×N) or "rays" (rays×rays)
    minimum: int  # smallest allowed sampling
    summary: str

    def compute(self, *args, **kwargs) -> Computed:
        return importlib.import_module(self.module, __package__).compute(*args, **kwargs)


METHODS: dict[str, Method] = {m.name: m for m in (
    Method("fraunhofer", ".fraunhofer", "pupil_samples", 8,
           "|matrix DFT of the pupil function|^2 (diffraction and aberrations)"),
    Method("geometric", ".geometric", "rays", 2, "real rays on a regular entrance grid, binned per pixel"),
    # recorded through the Mitsuba scene: the render stage computes it, imported only when used
    Method("render", "..render.psf", "rays", 2, "the entrance-grid rays traced through the Mitsuba scene's "
                                                 "lens meshes, binned per pixel"),
)}
DEFAULT_METHOD = "fraunhofer"
# largest sampling per side: 4096² = 16.8 M rays per PSF (about 1 GB of float64 working arrays);
# Dr.Jit refuses arrays beyond 2^32 entries long before memory would
MAX_SAMPLING = 4096


def check_method(method: str, pupil_samples: int, rays: int) -> int:
    """The sampling of `method` (pupil samples N or rays per side) after checking both."""
    if method not in METHODS:
        raise SolasError(f"PSF method {method!r} must be one of {', '.join(METHODS)}")
    m = METHODS[method]
    value = {"pupil_samples": pupil_samples, "rays": rays}[m.sampling]
    if (not isinstance(value, (int, np.integer)) or isinstance(value, bool)
            or not m.minimum <= value <= MAX_SAMPLING):
        what, per = ("pupil samples", "") if m.sampling == "pupil_samples" else ("rays", " (rays × rays per PSF)")
        raise SolasError(f"{what} {value!r} must be an integer from {m.minimum} to {MAX_SAMPLING}{per}")
    return int(value)


def compute(lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, pitch_um: float, size: int, method: str,
            pupil_samples: int, rays: int, shared_origin: bool = False) -> Computed:
    """Unnormalised PSFs (n, size, size) in 1/µm² for field/wavelength pairs by `method`, each grid's
    origin on its chief ray or, with `shared_origin`, all on the first one's."""
    sampling = check_method(method, pupil_samples, rays)
    return METHODS[method].compute(lens, field_deg, wavelength_nm, pitch_um, size, sampling, shared_origin)


def psf(lens, field_deg, wavelength_nm, *, weights=None, pitch_um: float = DEFAULT_PITCH_UM,
        size: int = DEFAULT_SIZE,
        method: str = DEFAULT_METHOD, normalization: str = "sum", pupil_samples: int = DEFAULT_PUPIL_SAMPLES,
        rays: int = DEFAULT_GEOMETRIC_RAYS, auto_window: bool = False) -> PSF:
    """The PSF at `field_deg` (x, y degrees) for one wavelength (nm) or several with `weights`
    (polychromatic: the power-weighted sum of the monochromatic PSFs). meta["energy_in_grid"] is the
    fraction of the transmitted light inside the window and meta["warnings"] what looked doubtful;
    `auto_window` doubles `size` until the window holds `base.WINDOW_ENERGY_LIMIT` of the light."""
    field = lens.field_type.check(field_deg)
    check_grid(pitch_um, size)
    sampling = check_method(method, pupil_samples, rays)
    check_normalization(normalization)
    wavelengths = tuple(lens.check_wavelength(w) for w in np.atleast_1d(wavelength_nm).tolist())
    if not wavelengths:
        raise SolasError("at least one wavelength (nm) is needed")
    w8 = np.ones(len(wavelengths)) if weights is None else np.asarray(weights, dtype=np.float64)
    if w8.shape != (len(wavelengths),) or np.any(w8 < 0) or not np.isfinite(w8).all() or w8.sum() <= 0:
        raise SolasError(f"weights {weights!r} must be {len(wavelengths)} non-negative numbers, not all zero")
    w8 = w8 / w8.sum()
    fields = np.repeat(np.array([field]), len(wavelengths), axis=0)
    # all wavelengths share one origin, the first wavelength's chief ray, so lateral colour shows
    data, chief, transmission, vignetted, doubts, centre_um = compute(lens, fields, np.array(wavelengths), pitch_um,
                                                                     size, method, pupil_samples, rays,
                                                                     shared_origin=True)
    light = centre_um is not None and bool(chief.vignetted[0])
    origin = chief.image_xy[0] + (centre_um[0] * 1e-3 if light else 0.0)  # the window's centre, mm
    if not np.dot(w8, transmission) > 0:
        raise SolasError(f"no light reaches the image at field ({field[0]:g}, {field[1]:g}) deg: every ray is blocked"
                         + (f" (by surfaces {', '.join(map(str, sorted({s for v in vignetted for s in v})))})"
                            if any(vignetted) else ""))
    total = np.tensordot(w8, data, axes=1)
    energy = float(window_energy(total, pitch_um, np.dot(w8, transmission)))
    meta = describe(lens, method, normalization, {METHODS[method].sampling: sampling}, size)
    meta.update({
        "chief_ray_mm": {f"{w:g}": chief.image_xy[i].tolist() for i, w in enumerate(wavelengths)},
        "centre": "centroid of the arriving light (the chief ray is blocked)" if light else "chief ray",
        "transmission": float(np.dot(w8, transmission)),
        "energy_in_grid": energy,
        "vignetted_by_surfaces": sorted({s for v in vignetted for s in v}),
        "warnings": [*doubts, *window_warnings(energy, np.array([field]), size, pitch_um)],
    })
    if auto_window and energy < WINDOW_ENERGY_LIMIT and 2 * size <= MAX_SIZE:
        return psf(lens, field_deg, wavelength_nm, weights=weights, pitch_um=pitch_um, size=2 * size, method=method,
                   normalization=normalization, pupil_samples=pupil_samples, rays=rays, auto_window=True)
    return PSF(normalize(total, normalization), float(pitch_um), field, wavelengths, tuple(w8.tolist()),
               tuple(origin.tolist()), method, normalization, meta)
