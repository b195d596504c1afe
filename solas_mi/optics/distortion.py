"""Distortion: the real chief ray's image height against the field angle, its departure from the
rectilinear f·tanθ, the projection it is closest to, and the relative illumination beside it.

Projections (image height h of a field angle θ for a focal length f, all mm): rectilinear f tanθ,
equidistant f θ, equisolid 2f sin(θ/2), stereographic 2f tan(θ/2). The closest is the one whose
least-squares fit h ≈ f·g(θ) over the sampled field leaves the smallest RMS residual (f free per
projection). Angles in degrees at the interfaces, heights in mm.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import SolasError
from .lens import Lens

PROJECTIONS = {
    "rectilinear": np.tan,
    "equidistant": lambda t: t,
    "equisolid": lambda t: 2.0 * np.sin(t / 2.0),
    "stereographic": lambda t: 2.0 * np.tan(t / 2.0),
}


def fit_projections(field_deg: np.ndarray, height_mm: np.ndarray) -> dict[str, tuple[float, float]]:
    """Per projection, (focal length mm, RMS residual mm) of the least-squares fit h ≈ f·g(θ). Field
    angles in [0, 180) degrees, one at least nonzero; rectilinear, undefined from 90°, is then
    (nan, inf)."""
    theta = np.radians(np.asarray(field_deg, dtype=np.float64))
    h = np.asarray(height_mm, dtype=np.float64)
    if theta.shape != h.shape or theta.ndim != 1 or not np.all((theta >= 0) & (theta < np.pi)) or not theta.any():
        raise SolasError(
            f"projection fit needs field angles in [0, 180) deg, one at least nonzero, and as many "
            f"image heights; got {np.degrees(theta).tolist()} deg and {h.size} heights"
        )
    fits = {}
    for name, g in PROJECTIONS.items():
        if name == "rectilinear" and theta.max() >= np.pi / 2:
            fits[name] = (float("nan"), float("inf"))
            continue
        gt = g(theta)
        f = float(np.dot(gt, h) / np.dot(gt, gt))
        fits[name] = (f, float(np.sqrt(np.mean((h - f * gt) ** 2))))
    return fits


def closest_projection(fits: dict[str, tuple[float, float]]) -> str:
    """The name of the projection with the smallest RMS residual among `fit_projections`' fits."""
    return min(fits, key=lambda name: fits[name][1])


@dataclass
class Distortion:
    """Image height vs field at one wavelength (lists, for JSON)."""

    wavelength_nm: float
    field_deg: list[float]
    image_height_mm: list[float]  # real chief ray
    rectilinear_height_mm: list[float | None]  # EFL · tanθ (None from 90°)
    distortion_percent: list[float | None]  # (h − EFL tanθ) / (EFL tanθ) · 100; 0 on the axis, None from 90°
    relative_illumination: list[float | None]  # E(θ)/E(0); None where undefined (illumination_note says why)
    projection: str  # the closest projection
    projection_fits: dict[str, list[float | None]]  # name → [focal length mm, RMS residual mm]; None: undefined
    illumination_note: str = ""  # why relative_illumination is None, if it is

    def as_dict(self) -> dict:
        return asdict(self)


def distortion(lens: Lens, field_deg=None, wavelength_nm: float | None = None, samples: int = 11) -> Distortion:
    """The distortion table of `lens` at `wavelength_nm` (default: its primary wavelength) over the
    field angles `field_deg` (degrees, y; default: `samples` angles from 0 to the lens's half field)."""
    from .illumination import relative_illumination
    from .paraxial import paraxial
    from .pupil import chief_rays  # loads Dr.Jit

    wl = lens.check_wavelength(wavelength_nm if wavelength_nm is not None else lens.primary_wavelength)
    if field_deg is None:
        if lens.field_deg <= 0:
            raise SolasError(f"lens {lens.name} states no field (field_deg = 0); give the field angles")
        field_deg = np.linspace(0.0, lens.field_deg, samples)
    angles = np.asarray(field_deg, dtype=np.float64)
    fields = np.stack([np.zeros_like(angles), angles], -1)
    h = np.abs(chief_rays(lens, fields, np.full(len(angles), wl)).image_xy[:, 1])
    efl = paraxial(lens, wl).efl_mm
    rect = [efl * math.tan(math.radians(abs(a))) if abs(a) < 90 else None for a in angles]
    percent = [None if r is None else (hi - r) / r * 100.0 if r > 0 else 0.0 for hi, r in zip(h, rect)]
    try:
        ri = relative_illumination(lens, fields, wl).tolist()
    except SolasError as exc:  # the table is still whole; the column says why it is empty
        ri, note = [None] * len(angles), str(exc)
    else:
        note = ""
    fits = fit_projections(np.abs(angles), h)
    return Distortion(
        wl,
        angles.tolist(),
        h.tolist(),
        rect,
        percent,
        ri,
        closest_projection(fits),
        {k: [x if math.isfinite(x) else None for x in v] for k, v in fits.items()},
        note,
    )
