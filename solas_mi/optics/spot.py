"""Spot diagrams: real rays through the entrance pupil to the image plane. Lengths in mm, spots in µm."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from . import pupil, tracer
from .lens import Lens

PATTERNS = ("hexapolar", "grid")


@dataclass
class Spot:
    """Ray intersections with the image plane (µm) relative to `origin_mm`: the chief ray's image
    point, or where the chief ray is blocked but light passes, the centroid of that light."""

    x_um: np.ndarray
    y_um: np.ndarray
    chief_ray_mm: tuple[float, float]
    launched: int  # rays launched
    vignetted: int  # rays blocked by an aperture or failing geometrically
    origin_mm: tuple[float, float] | None = None  # None: the chief ray's image point

    @property
    def centre(self) -> str:
        return "chief ray" if self.origin_mm is None else "centroid of the arriving light (the chief ray is blocked)"

    @property
    def centroid_um(self) -> tuple[float, float]:
        return float(self.x_um.mean()), float(self.y_um.mean())

    def _chief_um(self) -> tuple[float, float]:
        """The chief ray's image point relative to the origin (µm)."""
        if self.origin_mm is None:
            return 0.0, 0.0
        return ((self.chief_ray_mm[0] - self.origin_mm[0]) * 1e3, (self.chief_ray_mm[1] - self.origin_mm[1]) * 1e3)

    def rms_radius_um(self, reference: str = "centroid") -> float:
        """RMS radius about the centroid or the chief ray (µm)."""
        if reference not in ("centroid", "chief"):
            raise SolasError(f"spot reference {reference!r} must be 'centroid' or 'chief'")
        cx, cy = self.centroid_um if reference == "centroid" else self._chief_um()
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
    """A spot diagram: real rays through the entrance pupil to the image plane, every aperture clipping.

    Rays on `pattern` fill the real entrance pupil about the real chief ray (aimed through the stop
    centre): the disc reaching the nearest of the real rays aimed at the stop's rim. Where an aperture
    blocks the chief ray itself, they fill the disc about the part of the pupil whose light arrives,
    and the spot is given about the centroid of that light.

    Parameters
    ----------
    lens : Lens
        The lens.
    field_deg : float or (float, float)
        The field: (x, y) degrees, or one value y.
    wavelength_nm : float
        The wavelength (nm).
    pattern : str, default "hexapolar"
        The pupil pattern, one of `PATTERNS`.
    density : int, default 20
        Rings of the hexapolar pattern, or points per side of the grid.

    Returns
    -------
    Spot
        The rays' image points (µm) about the chief ray's (or the light's centroid), with counts of
        rays launched and blocked; `Spot.rms_radius_um` its RMS radius.

    Raises
    ------
    SolasError
        For a bad field, wavelength or pattern, or a field whose every ray is blocked.

    Examples
    --------
    >>> from solas_mi import Lens, spot
    >>> result = spot(Lens.load("solas-doublet"), (0, 2), 531.0)
    >>> round(result.rms_radius_um(), 2), result.launched
    (8.04, 1261)
    """
    wavelength_nm = lens.check_wavelength(wavelength_nm)
    field = np.array([lens.field_type.check(field_deg)])
    points = pupil_pattern(pattern, density)
    wl = np.array([wavelength_nm])
    chief = pupil.chief_rays(lens, field, wl)
    ex, ey, _, ok = pupil.stop_rim(pupil.Bundle(lens, field, wl, pupil.RIM_RAYS), chief)
    reach = np.hypot(ex - chief.entrance[0, 0], ey - chief.entrance[0, 1])
    centre, radius = chief.entrance[0], float(reach[ok].min())
    if chief.vignetted[0]:
        centre, radius = _light_disc(lens, field, wl, chief.entrance[0], float(reach.max()))
    bundle = pupil.Bundle(lens, field, wl, len(points))
    x, y, keep = _image_hits(bundle, centre[0] + radius * points[:, 0], centre[1] + radius * points[:, 1],
                             lens.image_z)
    if not keep.any():
        raise SolasError(f"no ray of {wavelength_nm:g} nm through the pupil reaches the image for field "
                         f"({field[0, 0]:g}, {field[0, 1]:g}) deg: every one is blocked")
    chief_x, chief_y = chief.image_xy[0]
    origin = (float(x[keep].mean()), float(y[keep].mean())) if chief.vignetted[0] else None
    origin_x, origin_y = origin or (chief_x, chief_y)
    return Spot((x[keep] - origin_x) * 1e3, (y[keep] - origin_y) * 1e3, (float(chief_x), float(chief_y)), len(points),
                int((~keep).sum()), origin)


LIGHT_PROBE = 96  # points per side of the grid that finds the part of a blocked chief ray's pupil that passes


def _image_hits(bundle: pupil.Bundle, ex: np.ndarray, ey: np.ndarray, image_z: float):
    """Image-plane points (mm) of the bundle's rays at entrance coordinates ex, ey, and which arrive."""
    traced = bundle.trace(tracer.F(ex), tracer.F(ey))
    x, y, _ = tracer.to_plane(traced, image_z)
    keep, x_mm, y_mm = tracer.to_numpy(traced.ok & (traced.clipped_by == 0), x, y)
    return x_mm, y_mm, keep


def _light_disc(lens: Lens, field: np.ndarray, wl: np.ndarray, chief_entrance: np.ndarray, reach: float):
    """Centre (2,) and radius (mm) of the entrance disc holding the rays that arrive, from a
    LIGHT_PROBE² grid over the square ±`reach` about the chief ray's entrance point (the pupil's rim
    seen from it); the disc reaches half a probe cell past the outermost arriving probe."""
    g = (np.arange(LIGHT_PROBE) + 0.5) / LIGHT_PROBE * 2.0 - 1.0
    gx, gy = (chief_entrance[i] + reach * a.ravel() for i, a in enumerate(np.meshgrid(g, g)))
    _, _, keep = _image_hits(pupil.Bundle(lens, field, wl, len(gx)), gx, gy, lens.image_z)
    if not keep.any():
        return chief_entrance, reach
    centre = np.array([gx[keep].mean(), gy[keep].mean()])
    cell = 2.0 * reach / LIGHT_PROBE
    return centre, float(np.hypot(gx[keep] - centre[0], gy[keep] - centre[1]).max() + cell)
