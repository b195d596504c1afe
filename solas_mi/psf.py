"""Point spread functions on an image-plane grid of any pitch.

Methods: "fraunhofer" (`fraunhofer`, from the pupil function of `pupil`) and "geometric"
(`geometric`, a histogram of real rays uniformly filling the entrance pupil).

Grid convention: `size`×`size` pixels of `pitch_um`; the chief ray's image point is at pixel
(size//2, size//2); row 0 is the top (largest y), column 0 the left (smallest x). Values are
irradiance per µm² as a fraction of the on-axis entrance-pupil power ("none"), or normalised to unit
sum ("sum", default) or unit peak ("peak").
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .errors import SolasError
from .lens import Lens

if TYPE_CHECKING:
    from .pupil import ChiefRays

METHODS = ("fraunhofer", "geometric")
NORMALIZATIONS = ("sum", "peak", "none")
VALUE_MEANING = {
    "sum": "unit sum over the grid",
    "peak": "unit peak",
    "none": "irradiance per um^2 as a fraction of the on-axis entrance-pupil power",
}
DEFAULT_PITCH_UM = 0.5
DEFAULT_SIZE = 160
DEFAULT_PUPIL_SAMPLES = 128
DEFAULT_GEOMETRIC_RAYS = 512


@dataclass
class PSF:
    """One PSF (2-D array, image orientation) and what it means."""

    data: np.ndarray
    pitch_um: float
    field_deg: tuple[float, float]
    wavelengths_nm: tuple[float, ...]
    weights: tuple[float, ...]
    chief_ray_mm: tuple[float, float]  # image-plane point at pixel (size//2, size//2), first wavelength
    method: str
    normalization: str
    meta: dict = field(default_factory=dict)

    @property
    def size(self) -> int:
        return self.data.shape[0]

    @property
    def x_um(self) -> np.ndarray:
        """Column centres relative to the chief ray (µm)."""
        return grid_offsets(self.size, self.pitch_um)

    @property
    def y_um(self) -> np.ndarray:
        """Row centres relative to the chief ray (µm), top row first."""
        return -grid_offsets(self.size, self.pitch_um)

    def write(self, path: str) -> None:
        """Write as OpenEXR (channel "Y") with all metadata in the header."""
        from .imageio import write_exr

        meta = dict(self.meta, field_deg=list(self.field_deg), wavelengths_nm=list(self.wavelengths_nm),
                    weights=list(self.weights), pitch_um=self.pitch_um, size=self.size,
                    chief_ray_origin_mm=list(self.chief_ray_mm))
        write_exr(path, {"Y": self.data}, meta)

    def write_png(self, path: str) -> None:
        """The PSF scaled to its peak, as an sRGB PNG for viewing."""
        from .imageio import write_png

        write_png(path, self.data / max(float(self.data.max()), 1e-300))


def grid_offsets(size: int, pitch_um: float) -> np.ndarray:
    """Pixel-centre offsets (µm) from the grid origin at index size//2, increasing."""
    return (np.arange(size) - size // 2) * pitch_um


def check_grid(pitch_um: float, size: int) -> None:
    if not isinstance(size, (int, np.integer)) or not 2 <= size <= 8192:
        raise SolasError(f"PSF size {size!r} must be an integer from 2 to 8192 pixels")
    if not isinstance(pitch_um, (int, float)) or not math.isfinite(pitch_um) or pitch_um <= 0:
        raise SolasError(f"PSF pitch {pitch_um!r} µm must be a positive number")


def check_normalization(how: str) -> None:
    if how not in NORMALIZATIONS:
        raise SolasError(f"normalization {how!r} must be one of {', '.join(NORMALIZATIONS)}")


def normalize(data: np.ndarray, how: str) -> np.ndarray:
    """Normalise PSFs over the last two axes: "sum", "peak" or "none"."""
    check_normalization(how)
    if how == "none":
        return data
    scale = data.sum(axis=(-2, -1), keepdims=True) if how == "sum" else data.max(axis=(-2, -1), keepdims=True)
    return data / np.where(scale > 0, scale, 1.0)


def check_method(method: str, pupil_samples: int, rays: int) -> None:
    """The method's name and its sampling: pupil samples N (N×N) or rays (rays×rays)."""
    if method not in METHODS:
        raise SolasError(f"PSF method {method!r} must be one of {', '.join(METHODS)}")
    if method == "fraunhofer" and (not isinstance(pupil_samples, (int, np.integer)) or pupil_samples < 8):
        raise SolasError(f"pupil samples {pupil_samples!r} must be an integer >= 8")
    if method == "geometric" and (not isinstance(rays, (int, np.integer)) or rays < 2):
        raise SolasError(f"rays {rays!r} must be an integer >= 2 (rays × rays per PSF)")


def compute(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, pitch_um: float, size: int,
            method: str, pupil_samples: int, rays: int, shared_origin: bool = False,
            ) -> tuple[np.ndarray, "ChiefRays", np.ndarray, list]:
    """Unnormalised PSFs (n, size, size) in 1/µm² for field/wavelength pairs, each grid's origin on
    its chief ray or, with `shared_origin`, all on the first one's; also the chief rays, the
    transmitted power fraction and the vignetting surfaces of each."""
    # the ray-tracing modules load Dr.Jit: imported here so that PSF constants and types stay light
    from .fraunhofer import fraunhofer
    from .geometric import geometric
    from .pupil import chief_rays, pupil_function

    if method == "fraunhofer":
        pf = pupil_function(lens, field_deg, wavelength_nm, pupil_samples)
        center = (pf.chief.image_xy[:1] - pf.chief.image_xy) * 1e3 if shared_origin else None
        return fraunhofer(pf, pitch_um, size, center), pf.chief, pf.transmission, pf.vignetted_by
    chief = chief_rays(lens, field_deg, wavelength_nm)
    center = (chief.image_xy[:1] - chief.image_xy) * 1e3 if shared_origin else None
    data, _, transmission = geometric(lens, field_deg, wavelength_nm, pitch_um, size, rays, chief, center)
    return data, chief, transmission, [[] for _ in range(len(field_deg))]


def describe(lens: Lens, method: str, normalization: str, pupil_samples: int, rays: int, size: int) -> dict:
    """The metadata every PSF output carries: lens, method, sampling and array conventions."""
    return {
        "lens": lens.name, "lens_hash": lens.hash, "lens_source": lens.source, "method": method,
        "normalization": normalization, "values": VALUE_MEANING[normalization],
        "sampling": {"pupil_samples": pupil_samples} if method == "fraunhofer" else {"rays": rays},
        "origin_pixel": [size // 2, size // 2],
        "orientation": "row 0 = top (largest y), column 0 = left (smallest x)",
    }


def check_field(field_deg) -> tuple[float, float]:
    try:
        fx, fy = (float(v) for v in field_deg)
    except (TypeError, ValueError):
        raise SolasError(f"field {field_deg!r} must be two angles (x, y) in degrees") from None
    if not (math.isfinite(fx) and math.isfinite(fy)) or abs(fx) >= 89 or abs(fy) >= 89:
        raise SolasError(f"field ({fx:g}, {fy:g}) deg must be finite and within ±89 deg")
    return fx, fy


def psf(lens: Lens, field_deg, wavelength_nm, *, weights=None, pitch_um: float = DEFAULT_PITCH_UM,
        size: int = DEFAULT_SIZE,
        method: str = "fraunhofer", normalization: str = "sum", pupil_samples: int = DEFAULT_PUPIL_SAMPLES,
        rays: int = DEFAULT_GEOMETRIC_RAYS) -> PSF:
    """The PSF at `field_deg` (x, y degrees) for one wavelength (nm) or several with `weights`
    (polychromatic: the power-weighted sum of the monochromatic PSFs)."""
    field = check_field(field_deg)
    check_grid(pitch_um, size)
    check_method(method, pupil_samples, rays)
    check_normalization(normalization)
    wavelengths = tuple(float(w) for w in np.atleast_1d(wavelength_nm))
    for w in wavelengths:
        lens.check_wavelength(w)
    w8 = np.ones(len(wavelengths)) if weights is None else np.asarray(weights, dtype=np.float64)
    if w8.shape != (len(wavelengths),) or np.any(w8 < 0) or not np.isfinite(w8).all() or w8.sum() <= 0:
        raise SolasError(f"weights {weights!r} must be {len(wavelengths)} non-negative numbers, not all zero")
    w8 = w8 / w8.sum()
    fields = np.repeat(np.array([field]), len(wavelengths), axis=0)
    # all wavelengths share one origin, the first wavelength's chief ray, so lateral colour shows
    data, chief, transmission, vignetted = compute(lens, fields, np.array(wavelengths), pitch_um, size, method,
                                                   pupil_samples, rays, shared_origin=True)
    total = np.tensordot(w8, data, axes=1)
    meta = describe(lens, method, normalization, pupil_samples, rays, size)
    meta.update({
        "chief_ray_mm": {f"{w:g}": chief.image_xy[i].tolist() for i, w in enumerate(wavelengths)},
        "transmission": float(np.dot(w8, transmission)),
        "energy_in_grid": float(total.sum() * pitch_um ** 2 / max(np.dot(w8, transmission), 1e-300)),
        "vignetted_by_surfaces": sorted({s for v in vignetted for s in v}),
    })
    return PSF(normalize(total, normalization), float(pitch_um), field, wavelengths, tuple(w8.tolist()),
               tuple(chief.image_xy[0].tolist()), method, normalization, meta)
