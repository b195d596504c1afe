"""Point spread functions on an image-plane grid of any pitch.

Fraunhofer: |matrix DFT of the pupil function|², the pupil sampled on the exit-pupil reference sphere
(see `pupil`). Geometric: histogram of real rays uniformly filling the entrance pupil.

Grid convention: `size`×`size` pixels of `pitch_um`; the chief ray's image point is at pixel
(size//2, size//2); row 0 is the top (largest y), column 0 the left (smallest x). Values are
irradiance per µm² as a fraction of the on-axis entrance-pupil power ("none"), or normalised to unit
sum ("sum", default) or unit peak ("peak").
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import pupil as P
from . import tracer as T
from .errors import SolasError
from .lens import Lens

METHODS = ("fraunhofer", "geometric")
NORMALIZATIONS = ("sum", "peak", "none")
DEFAULT_PUPIL_SAMPLES = 128
DEFAULT_GEOMETRIC_RAYS = 512
_BATCH_RAYS = 1 << 20  # rays traced at once


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


def grid_offsets(size: int, pitch_um: float) -> np.ndarray:
    """Pixel-centre offsets (µm) from the grid origin at index size//2, increasing."""
    return (np.arange(size) - size // 2) * pitch_um


def check_grid(pitch_um: float, size: int) -> None:
    if not isinstance(size, (int, np.integer)) or not 2 <= size <= 8192:
        raise SolasError(f"PSF size {size!r} must be an integer from 2 to 8192 pixels")
    if not isinstance(pitch_um, (int, float)) or not math.isfinite(pitch_um) or pitch_um <= 0:
        raise SolasError(f"PSF pitch {pitch_um!r} µm must be a positive number")


def normalize(data: np.ndarray, how: str) -> np.ndarray:
    """Normalise PSFs over the last two axes: "sum", "peak" or "none"."""
    if how not in NORMALIZATIONS:
        raise SolasError(f"normalization {how!r} must be one of {', '.join(NORMALIZATIONS)}")
    if how == "none":
        return data
    scale = data.sum(axis=(-2, -1), keepdims=True) if how == "sum" else data.max(axis=(-2, -1), keepdims=True)
    return data / np.where(scale > 0, scale, 1.0)


def fraunhofer(pf: P.PupilFunction, pitch_um: float, size: int, center_um: np.ndarray | None = None) -> np.ndarray:
    """Fraunhofer PSFs (n, size, size) in 1/µm² from pupil functions, by matrix DFT.

    `center_um` (n, 2) shifts each grid's origin from the chief ray (default: none)."""
    n = len(pf.alpha)
    offs = grid_offsets(size, pitch_um) * 1e-3  # mm
    u = np.broadcast_to(offs, (n, size)).copy()
    v = np.broadcast_to(-offs, (n, size)).copy()
    if center_um is not None:
        u += center_um[:, 0:1] * 1e-3
        v += center_um[:, 1:2] * 1e-3
    lam = pf.wavelength_nm * 1e-6 / pf.chief.n_image  # mm, in image space
    k = 2.0 * math.pi / lam
    phase = (2.0 * math.pi / (pf.wavelength_nm * 1e-6))[:, None, None] * pf.opd_mm
    pupil = (pf.amplitude * np.exp(1j * phase)).astype(np.complex64)
    # separable DFT kernels; phases in float64, products in complex64 (errors ~1e-7 of the peak)
    ex = np.exp(-1j * k[:, None, None] * pf.alpha[:, :, None] * u[:, None, :]).astype(np.complex64)  # (n, N, size)
    ey = np.exp(-1j * k[:, None, None] * v[:, :, None] * pf.beta[:, None, :]).astype(np.complex64)  # (n, size, N)
    field_ = np.empty((n, len(offs), len(offs)), dtype=np.complex64)
    for f in range(n):
        field_[f] = (ey[f] @ pupil[f]) @ ex[f]
    scale = (pf.cell_area / lam) ** 2 * 1e-6  # |U|² in 1/mm² → 1/µm²
    return (field_.real.astype(np.float64) ** 2 + field_.imag.astype(np.float64) ** 2) * scale[:, None, None]


def geometric(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, pitch_um: float, size: int,
              rays: int = DEFAULT_GEOMETRIC_RAYS, chief: P.ChiefRays | None = None,
              center_um: np.ndarray | None = None) -> tuple[np.ndarray, P.ChiefRays]:
    """Geometric PSFs (n, size, size) in 1/µm²: rays on a rays×rays grid over the entrance pupil,
    binned on the image-plane grid (each bin holds the power that lands in that pixel).

    `center_um` (n, 2) shifts each grid's origin from the chief ray (default: none)."""
    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    nf = len(field_deg)
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (nf,)).copy()
    chief = chief or P.chief_rays(lens, field_deg, wavelength_nm)
    hits = entrance_grid_hits(lens, field_deg, wavelength_nm, rays, chief)
    out = np.zeros((nf, size, size))
    edges = (np.arange(size + 1) - size // 2 - 0.5) * pitch_um
    shift = np.zeros((nf, 2)) if center_um is None else center_um
    for f, (dx, dy, w) in enumerate(hits):
        # rows run down from +y: the row coordinate is −(y offset), binned like the columns
        h, _, _ = np.histogram2d(shift[f, 1] - dy, dx - shift[f, 0], bins=(edges, edges), weights=w)
        out[f] = h / pitch_um ** 2
    return out, chief


def entrance_grid_hits(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, rays: int,
                       chief: P.ChiefRays) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per field: image-plane offsets (µm) from the chief ray of unvignetted rays on a regular
    rays×rays entrance grid covering the pupil, and each ray's power (fraction of the on-axis pupil)."""
    nf = len(field_deg)
    half = _entrance_half_width(lens, field_deg, wavelength_nm, chief)
    t = (np.arange(rays) + 0.5) / rays * 2.0 - 1.0
    per_batch = max(1, _BATCH_RAYS // (rays * rays))
    result = []
    for start in range(0, nf, per_batch):
        sl = slice(start, min(nf, start + per_batch))
        b = P.Bundle(lens, field_deg[sl], wavelength_nm[sl], rays * rays)
        cx, cy, hw = chief.entrance[sl, 0], chief.entrance[sl, 1], half[sl]
        ex = (cx[:, None, None] + hw[:, None, None] * t[None, None, :]).repeat(rays, axis=1)
        ey = (cy[:, None, None] + hw[:, None, None] * t[None, :, None]).repeat(rays, axis=2)
        tr = b.trace(T.F(ex.ravel()), T.F(ey.ravel()))
        x, y, _ = T.to_plane(tr, lens.image_z)
        keep = (np.asarray(tr.ok) & (np.asarray(tr.clipped_by) == 0)).reshape(-1, rays * rays)
        x, y = np.asarray(x).reshape(-1, rays * rays), np.asarray(y).reshape(-1, rays * rays)
        for j, f in enumerate(range(sl.start, sl.stop)):
            weight = (2.0 * hw[j] / rays) ** 2 * P._power_density(lens, float(wavelength_nm[f]))
            if not lens.at_infinity:
                pts = T.object_points(lens, field_deg[f:f + 1])[0]
                d2 = (ex[j] - pts[0]) ** 2 + (ey[j] - pts[1]) ** 2 + lens.object_distance ** 2
                weight = weight * (lens.object_distance ** 3 / d2 ** 1.5).ravel()[keep[j]]
            m = keep[j]
            result.append(((x[j, m] - chief.image_xy[f, 0]) * 1e3, (y[j, m] - chief.image_xy[f, 1]) * 1e3,
                           np.broadcast_to(weight, (int(m.sum()),)).astype(np.float64)))
    return result


def _entrance_half_width(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, chief: P.ChiefRays) -> np.ndarray:
    """Half-width (mm) of a square about the chief ray's entrance point that holds the whole pupil."""
    ex, ey, _, _ = P.stop_rim(P.Bundle(lens, field_deg, wavelength_nm, P.RIM_RAYS), chief)
    ex, ey = ex - chief.entrance[:, 0:1], ey - chief.entrance[:, 1:2]
    return np.maximum(np.abs(ex).max(axis=1), np.abs(ey).max(axis=1)) * 1.02


def check_method(method: str) -> None:
    if method not in METHODS:
        raise SolasError(f"PSF method {method!r} must be one of {', '.join(METHODS)}")


def compute(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, pitch_um: float, size: int,
            method: str, pupil_samples: int, rays: int, origin_mm: np.ndarray | None = None,
            ) -> tuple[np.ndarray, P.ChiefRays, np.ndarray, list]:
    """Unnormalised PSFs (n, size, size) in 1/µm² for field/wavelength pairs, each grid's origin on
    its chief ray or at `origin_mm` (n, 2); also the chief rays, the transmitted power fraction and
    the vignetting surfaces of each."""
    chief = P.chief_rays(lens, field_deg, wavelength_nm) if method == "geometric" else None
    if method == "fraunhofer":
        pf = P.pupil_function(lens, field_deg, wavelength_nm, pupil_samples)
        chief = pf.chief
    center = None if origin_mm is None else (origin_mm - chief.image_xy) * 1e3
    if method == "fraunhofer":
        return fraunhofer(pf, pitch_um, size, center), chief, pf.transmission, pf.vignetted_by
    data, _ = geometric(lens, field_deg, wavelength_nm, pitch_um, size, rays, chief, center)
    return data, chief, data.sum(axis=(1, 2)) * pitch_um ** 2, [[] for _ in range(len(field_deg))]


def check_field(field_deg) -> tuple[float, float]:
    try:
        fx, fy = (float(v) for v in field_deg)
    except (TypeError, ValueError):
        raise SolasError(f"field {field_deg!r} must be two angles (x, y) in degrees") from None
    if not (math.isfinite(fx) and math.isfinite(fy)) or abs(fx) >= 89 or abs(fy) >= 89:
        raise SolasError(f"field ({fx:g}, {fy:g}) deg must be finite and within ±89 deg")
    return fx, fy


def psf(lens: Lens, field_deg, wavelength_nm, *, weights=None, pitch_um: float = 0.5, size: int = 160,
        method: str = "fraunhofer", normalization: str = "sum", pupil_samples: int = DEFAULT_PUPIL_SAMPLES,
        rays: int = DEFAULT_GEOMETRIC_RAYS) -> PSF:
    """The PSF at `field_deg` (x, y degrees) for one wavelength (nm) or several with `weights`
    (polychromatic: the power-weighted sum of the monochromatic PSFs)."""
    field = check_field(field_deg)
    check_grid(pitch_um, size)
    check_method(method)
    wavelengths = tuple(float(w) for w in np.atleast_1d(wavelength_nm))
    for w in wavelengths:
        lens.check_wavelength(w)
    w8 = np.ones(len(wavelengths)) if weights is None else np.asarray(weights, dtype=np.float64)
    if w8.shape != (len(wavelengths),) or np.any(w8 < 0) or not np.isfinite(w8).all() or w8.sum() <= 0:
        raise SolasError(f"weights {weights!r} must be {len(wavelengths)} non-negative numbers, not all zero")
    w8 = w8 / w8.sum()
    fields = np.repeat(np.array([field]), len(wavelengths), axis=0)
    # all wavelengths share one origin, the first wavelength's chief ray, so lateral colour shows
    origin = P.chief_rays(lens, fields[:1], np.array(wavelengths[:1])).image_xy
    data, chief, transmission, vignetted = compute(lens, fields, np.array(wavelengths), pitch_um, size, method,
                                                   pupil_samples, rays, np.repeat(origin, len(wavelengths), axis=0))
    total = np.tensordot(w8, data, axes=1)
    meta = {
        "lens": lens.name, "lens_hash": lens.hash, "units": "1/um^2 of the on-axis entrance-pupil power" if normalization == "none" else normalization,
        "sampling": {"pupil_samples": pupil_samples} if method == "fraunhofer" else {"rays": rays},
        "chief_ray_mm": {f"{w:g}": chief.image_xy[i].tolist() for i, w in enumerate(wavelengths)},
        "transmission": float(np.dot(w8, transmission)),
        "energy_in_grid": float(total.sum() * pitch_um ** 2 / max(np.dot(w8, transmission), 1e-300)),
        "vignetted_by_surfaces": sorted({s for v in vignetted for s in v}),
        "origin_pixel": [size // 2, size // 2],
        "orientation": "row 0 = top (largest y), column 0 = left (smallest x)",
    }
    return PSF(normalize(total, normalization), float(pitch_um), field, wavelengths, tuple(w8.tolist()),
               tuple(chief.image_xy[0].tolist()), method, normalization, meta)
