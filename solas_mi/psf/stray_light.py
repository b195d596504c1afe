"""Stray light of a point source from the prescription: every two-reflection ghost path
(`optics.ghost_paths`) traced from a regular grid of rays that fills the first surface's clear aperture,
each ghost's energy relative to the direct image, its centroid, RMS size and best focus, and the sum of
the ghosts with the direct PSF as one high-dynamic-range stray-light PSF.

Ghost irradiance is geometric (rays binned per pixel): a ghost far from focus is wide against its
diffraction pattern. A ghost is called focused where its RMS radius on the image plane is within
`FOCUSED_AIRY` Airy radii of its beam (0.61 λ / NA, NA the sine of its widest ray's angle to its mean
direction): there diffraction shapes it, and the HDR PSF (`stray_psf`) blurs its rays by that Airy
pattern (geometric ⊗ diffraction, the usual estimate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import SolasError
from ..optics import ghost_paths, tracer
from ..optics.lens import Lens
from ..optics.paraxial import paraxial
from .registry import MAX_SAMPLING

FOCUSED_AIRY = 4.0  # a ghost within this many Airy radii (RMS) is focused: diffraction shapes it
MAX_FIELD_DEG = 89.0  # the widest polar angle ghosts take (light from the front of surface 1)


@dataclass(frozen=True)
class Ghost:
    """One ghost path at one field: the surfaces it reflects at (1-based, first j then i), its energy as a
    fraction of the direct image's, its centroid and RMS radius on the image plane (mm), the distance from
    the image plane to its best focus (mm, + toward the image side), whether it is focused and its beam's
    Airy radius (mm)."""

    surfaces: tuple[int, int]
    energy: float
    centroid_mm: tuple[float, float]
    rms_mm: float
    focus_mm: float
    focused: bool
    airy_mm: float  # the Airy radius 0.61 λ / NA of its beam (λ the longest wavelength; NA its widest ray)


@dataclass
class GhostReport:
    """The ghosts of one field and wavelengths, as `ghosts` computes them.

    Parameters
    ----------
    field_deg : (float, float)
        The field (x, y) in degrees.
    wavelengths_nm : tuple of float
        The wavelengths (nm), summed with equal weights.
    direct_power : float
        The direct image's power, a fraction of the light of the launch grid (a square on the plane of
        surface 1's vertex that holds its clear aperture).
    direct_centroid_mm : (float, float)
        The direct image's centroid on the image plane (mm).
    rays : int
        Rays per side of the launch grid, per path and wavelength.
    ghosts : list of Ghost
        One per two-reflection path: its surfaces, energy relative to the direct image, centroid, RMS
        radius, best focus and whether it is focused.
    hits : dict
        Per path (j, i), 0-based: its rays on the image plane, x and y (mm) and power (a fraction of the
        direct image's energy).
    """

    field_deg: tuple[float, float]
    wavelengths_nm: tuple[float, ...]
    direct_power: float
    direct_centroid_mm: tuple[float, float]
    rays: int
    ghosts: list[Ghost]
    hits: dict = field(default_factory=dict, repr=False)  # path → (x mm, y mm, power as a fraction of the direct
    # image's energy) of its rays on the image plane, all wavelengths

    @property
    def warnings(self) -> list[str]:
        """A line where no ray of the launch grid arrives by any path (the total 0 measures nothing)."""
        if not self.ghosts or any(g.energy for g in self.ghosts):
            return []
        return [
            f"no ray of the {self.rays} x {self.rays} grid arrives by any of the {len(self.ghosts)} ghost paths, "
            f"so their energies of 0 measure nothing: raise --rays (now {self.rays})"
        ]

    @property
    def total(self) -> float:
        """Every ghost's energy together, as a fraction of the direct image's."""
        return float(sum(g.energy for g in self.ghosts))

    def table(self) -> str:
        """The ghost table as text, brightest first.

        Returns
        -------
        str
            One line per ghost (its surfaces j, i, energy, centroid, RMS radius, best focus, focused),
            then their sum.
        """
        lines = [
            f"ghosts of {len(self.ghosts)} two-reflection paths, field ({self.field_deg[0]:g}, "
            f"{self.field_deg[1]:g}) deg, {', '.join(f'{w:g}' for w in self.wavelengths_nm)} nm; energy "
            f"relative to the direct image (which carries {self.direct_power:.4f} of the launch grid's light, a "
            "square over surface 1)",
            f"{'path j,i':>9} {'energy':>10} {'x mm':>10} {'y mm':>10} {'rms mm':>9} {'focus mm':>10} focused",
        ]
        for g in sorted(self.ghosts, key=lambda g: -g.energy):
            if g.energy == 0:
                lines.append(f"{g.surfaces[0]:>5},{g.surfaces[1]:<3} {0.0:10.3e}  (no ray of the grid arrives)")
                continue
            lines.append(
                f"{g.surfaces[0]:>5},{g.surfaces[1]:<3} {g.energy:10.3e} {g.centroid_mm[0]:10.4f} "
                f"{g.centroid_mm[1]:10.4f} {g.rms_mm:9.4f} {g.focus_mm:10.3f} {'yes' if g.focused else 'no'}"
            )
        lines.append(f"all ghosts: {self.total:.3e} of the direct image")
        return "\n".join(lines)


def check_rays(rays) -> None:
    """SolasError unless `rays` (rays per side of the launch grid) is an integer from 8 to MAX_SAMPLING."""
    if not isinstance(rays, int) or isinstance(rays, bool) or not 8 <= rays <= MAX_SAMPLING:
        raise SolasError(f"rays {rays!r} must be an integer from 8 to {MAX_SAMPLING} (rays per side of the grid)")


def launch(lens: Lens, field_deg: tuple[float, float], rays: int) -> ghost_paths.Rays:
    """rays × rays rays of the field through a regular grid on the plane of surface 1's vertex that holds its
    clear aperture, each with its power (a point source's, per grid cell; only ratios matter)."""
    first = lens.surfaces[0]
    reach = abs(float(first.sag(first.semi_diameter))) + 1.0  # how far the face stands off its vertex plane
    if lens.field_type.sideways:  # polar fields: the unit direction; from the front only
        d = lens.field_type.incoming(np.array(field_deg, dtype=np.float64))
        if d[2] < math.cos(math.radians(MAX_FIELD_DEG)):
            raise SolasError(
                f"field ({field_deg[0]:g}, {field_deg[1]:g}) deg: ghosts take light that meets surface 1 "
                f"from the front, a polar angle below {MAX_FIELD_DEG:g} deg"
            )
        tan = d[:2] / d[2]
    else:
        tan = tracer.field_tangents(np.array(field_deg, dtype=np.float64))
    half = first.semi_diameter * 1.001 + reach * float(np.hypot(*tan))
    t = (np.arange(rays) + 0.5) / rays * 2.0 - 1.0
    grid_x, grid_y = np.meshgrid(half * t, half * t)
    gx, gy = grid_x.ravel(), grid_y.ravel()
    z0 = tracer.launch_plane_z(lens)
    if lens.at_infinity:
        (dx, dy, dz), _, _ = tracer.beam_basis(tan[0], tan[1], math.sqrt)
        dx, dy, dz = np.full_like(gx, dx), np.full_like(gx, dy), np.full_like(gx, dz)
        power = np.ones_like(gx)
    else:
        points = tracer.object_points(lens, np.array([field_deg], dtype=np.float64))
        assert points is not None  # a finite object has its points
        ox, oy = points[0]
        vx, vy, vz = gx - ox, gy - oy, np.full_like(gx, lens.object_distance)
        dist = np.sqrt(vx * vx + vy * vy + vz * vz)
        sign = math.copysign(1.0, lens.object_distance)  # a virtual object: rays converge toward it
        dx, dy, dz = sign * vx / dist, sign * vy / dist, sign * vz / dist
        power = abs(lens.object_distance) / dist**3
    s = z0 / dz
    return ghost_paths.Rays(
        gx + s * dx, gy + s * dy, np.full_like(gx, z0), dx, dy, dz, power, np.ones(gx.shape, dtype=bool)
    )


def on_image(lens: Lens, r: ghost_paths.Rays) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rays that arrive, on the image plane: x, y (mm), their power, and their direction tangents."""
    keep = r.alive & (r.dz > 0) & (r.power > 0)
    t = (lens.image_z - r.z[keep]) / r.dz[keep]
    return (
        r.x[keep] + t * r.dx[keep],
        r.y[keep] + t * r.dy[keep],
        r.power[keep],
        r.dx[keep] / r.dz[keep],
        r.dy[keep] / r.dz[keep],
    )


def _best_focus(x, y, w, tx, ty) -> float:
    """The shift along z (mm) from the image plane that minimises the weighted RMS spot of straight rays."""
    cx, cy, ctx, cty = (np.average(a, weights=w) for a in (x, y, tx, ty))
    num = np.average((x - cx) * (tx - ctx) + (y - cy) * (ty - cty), weights=w)
    den = np.average((tx - ctx) ** 2 + (ty - cty) ** 2, weights=w)
    return float(-num / den) if den > 0 else 0.0


def ghosts(lens: Lens, field_deg, wavelengths_nm=None, rays: int = ghost_paths.DEFAULT_RAYS) -> GhostReport:
    """Every two-reflection ghost of a point source at `field_deg` (x, y degrees), summed over
    `wavelengths_nm` (default: the lens's) with equal weights.

    Parameters
    ----------
    lens : Lens
        The lens; its coatings weigh every reflection and crossing (bare surfaces: Fresnel's equations).
    field_deg : (float, float)
        The field (x, y) in degrees.
    wavelengths_nm : sequence of float, optional
        The wavelengths (nm); default: the lens's design wavelengths.
    rays : int, default 128
        Rays per side of the grid over the first surface's clear aperture.

    Returns
    -------
    GhostReport
        The ghost table and the rays on the image plane.

    Raises
    ------
    SolasError
        For a lens with an ideal thin lens, a bad ray count, or no direct light at that field.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> from solas_mi.psf import ghosts
    >>> report = ghosts(Lens.load("solas-doublet"), (0, 1), rays=64)
    >>> [g.surfaces for g in report.ghosts]  # reflect at j, then at i (the doublet's three glass surfaces)
    [(2, 1), (3, 1), (3, 2)]
    >>> report.ghosts[1].energy > report.ghosts[0].energy  # the two air faces: the brightest ghost
    True
    """
    check_rays(rays)
    field_deg = lens.field_type.check(field_deg)
    wavelengths = tuple(lens.check_wavelength(w) for w in (wavelengths_nm or lens.wavelengths_nm))
    start = launch(lens, field_deg, rays)
    hits = _path_hits(lens, start, wavelengths)
    direct = hits.pop(None)
    if direct[2].sum() <= 0:
        raise SolasError(f"no direct light reaches the image at field ({field_deg[0]:g}, {field_deg[1]:g}) deg")
    direct_power = float(direct[2].sum())
    table = [ghost_row(path, hit, direct_power, max(wavelengths)) for path, hit in hits.items()]
    centroid = (float(np.average(direct[0], weights=direct[2])), float(np.average(direct[1], weights=direct[2])))
    # each ghost ray's power as a fraction of the direct image's energy, for the HDR PSF
    return GhostReport(
        field_deg,
        wavelengths,
        direct_power / (len(wavelengths) * start.power.sum()),
        centroid,
        rays,
        table,
        {p: (h[0], h[1], h[2] / direct_power) for p, h in hits.items()},
    )


def _path_hits(lens: Lens, start: ghost_paths.Rays, wavelengths: tuple[float, ...]) -> dict:
    """Per path (None: the direct one), its rays on the image plane at every wavelength together: x, y (mm),
    power and direction tangents (`on_image`)."""
    traced = [ghost_paths.trace_all(lens, start, w) for w in wavelengths]
    return {
        path: tuple(np.concatenate(parts) for parts in zip(*(on_image(lens, t[path]) for t in traced)))
        for path in [None, *ghost_paths.paths(lens)]
    }


def working_f_number(lens: Lens) -> float:
    """The lens's working f-number; NaN for a lens that forms no image (a plate, an afocal system): no ghost is
    called focused there."""
    try:
        return abs(paraxial(lens).working_f_number)
    except SolasError:
        return math.nan


def ghost_row(path: tuple[int, int], hit, direct_power: float, wavelength_nm: float) -> Ghost:
    """One ghost's row of the table from its rays on the image plane (`_path_hits`, `psf.ghost_nodes`)."""
    x, y, w, tx, ty = hit
    surfaces = (path[0] + 1, path[1] + 1)
    if w.sum() <= 0:
        return Ghost(surfaces, 0.0, (math.nan, math.nan), math.nan, math.nan, False, math.nan)
    cx, cy = float(np.average(x, weights=w)), float(np.average(y, weights=w))
    rms = float(math.sqrt(np.average((x - cx) ** 2 + (y - cy) ** 2, weights=w)))
    # its beam's numerical aperture: the widest ray about the mean direction (sine of the angle)
    spread = np.hypot(tx - np.average(tx, weights=w), ty - np.average(ty, weights=w)).max()
    aperture = spread / math.sqrt(1.0 + spread * spread)
    airy = float(0.61 * wavelength_nm * 1e-6 / aperture) if aperture > 0 else math.inf
    return Ghost(
        surfaces,
        float(w.sum() / direct_power),
        (cx, cy),
        rms,
        _best_focus(x, y, w, tx, ty),
        bool(rms <= FOCUSED_AIRY * airy),
        airy,
    )
