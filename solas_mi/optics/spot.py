"""Spot diagrams: real rays through the entrance pupil to the image plane. Lengths in mm, spots in µm."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from . import pupil as P
from . import tracer as T
from .lens import Lens

PATTERNS = ("hexapolar", "grid")


@dataclass
class Spot:
    """Ray intersections with the image plane relative to the chief ray (µm)."""

    x_um: np.ndarray
    y_um: np.ndarray
    chief_ray_mm: tuple[float, float]
    launched: int  # rays launched
    vignetted: int  # rays blocked by an aperture or failing geometrically

    @property
    def centroid_um(self) -> tuple[float, float]:
        return float(self.x_um.mean()), float(self.y_um.mean())

    def rms_radius_um(self, reference: str = "centroid") -> float:
        """RMS radius about the centroid or the chief ray (µm)."""
        if reference not in ("centroid", "chief"):
            raise SolasError(f"spot reference {reference!r} must be 'centroid' or 'chief'")
        cx, cy = self.centroid_um if reference == "centroid" else (0.0, 0.0)
        return float(np.sqrt(np.mean((self.x_um - cx) ** 2 + (self.y_um - cy) ** 2)))


def pupil_pattern(pattern: str, density: int) -> np.ndarray:
    """Normalised pupil points (n, 2) within the unit disc.

    "hexapolar": `density` rings, ring i holding 6i rays (the usual spot-diagram pattern);
    "grid": a density×density square grid, uniform in area."""
    if not isinstance(density, (int, np.integer)) or density < 1:
        raise SolasError(f"pupil pattern density {density!r} must be a positive integer")
    if pattern == "hexapolar":
        rho = np.concatenate([[0.0]] + [np.full(6 * i, i / density) for i in range(1, density + 1)])
        phi = np.concatenate([[0.0]] + [np.arange(6 * i) * 2.0 * math.pi / (6 * i) for i in range(1, density + 1)])
        return np.stack([rho * np.cos(phi), rho * np.sin(phi)], axis=-1)
    if pattern == "grid":
        t = (np.arange(density) + 0.5) / density * 2.0 - 1.0
        x, y = np.meshgrid(t, t)
        keep = x * x + y * y <= 1.0
        return np.stack([x[keep], y[keep]], axis=-1)
    raise SolasError(f"pupil pattern {pattern!r} must be one of {', '.join(PATTERNS)}")


def spot(lens: Lens, field_deg, wavelength_nm: float, pattern: str = "hexapolar", density: int = 20) -> Spot:
    """Spot diagram at the image plane, every aperture clipping.

    Rays on `pattern` fill the real entrance pupil about the real chief ray (aimed through the stop
    centre): the disc reaching the nearest of the real rays aimed at the stop's rim."""
    wavelength_nm = lens.check_wavelength(wavelength_nm)
    field = np.array([lens.field_type.check(field_deg)])
    points = pupil_pattern(pattern, density)
    wl = np.array([wavelength_nm])
    chief = P.chief_rays(lens, field, wl)
    ex, ey, _, ok = P.stop_rim(P.Bundle(lens, field, wl, P.RIM_RAYS), chief)
    radius = float(np.hypot(ex - chief.entrance[0, 0], ey - chief.entrance[0, 1])[ok].min())
    b = P.Bundle(lens, field, wl, len(points))
    tr = b.trace(T.F(chief.entrance[0, 0] + radius * points[:, 0]), T.F(chief.entrance[0, 1] + radius * points[:, 1]))
    x, y, _ = T.to_plane(tr, lens.image_z)
    keep, x, y = T.to_numpy(tr.ok & (tr.clipped_by == 0), x, y)
    if not keep.any():
        raise SolasError(f"no ray of {wavelength_nm:g} nm through the pupil reaches the image for field "
                         f"({field[0, 0]:g}, {field[0, 1]:g}) deg: every one is blocked")
    x0, y0 = chief.image_xy[0]
    return Spot((x[keep] - x0) * 1e3, (y[keep] - y0) * 1e3, (float(x0), float(y0)),
                len(points), int((~keep).sum()))
