"""Stray light of a point source from the prescription: every two-reflection ghost path
(`optics.ghost_paths`) traced from a regular grid of rays that fills the first surface's clear aperture,
each ghost's energy relative to the direct image, its centroid, RMS size and best focus, and the sum of
the ghosts with the direct PSF as one high-dynamic-range stray-light PSF.

Ghost irradiance is geometric (rays binned per pixel): a ghost far from focus is wide against its
diffraction pattern. A ghost is called focused where its RMS radius on the image plane is within
`FOCUSED_AIRY` Airy radii (1.22 λ N, N the lens's working f-number) of its centroid: there diffraction
shapes it and its binned image is only its geometric envelope (the table says which). The direct
image in the HDR PSF is the geometric PSF over the window with the Fraunhofer PSF as its core where that
is sound (`stray_light_psf`), normalised to the direct energy 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import SolasError
from ..optics import ghost_paths, tracer
from ..optics.lens import Lens
from ..optics.paraxial import paraxial
from .geometric import bin_hits
from .registry import MAX_SAMPLING

FOCUSED_AIRY = 4.0  # a ghost within this many Airy radii (RMS) is focused: diffraction shapes it
MAX_FIELD_DEG = 89.0  # the widest polar angle ghosts take (light from the front of surface 1)


@dataclass(frozen=True)
class Ghost:
    """One ghost path at one field: the surfaces it reflects at (1-based, first j then i), its energy as a
    fraction of the direct image's, its centroid and RMS radius on the image plane (mm), the distance from
    the image plane to its best focus (mm, + toward the image side), and whether it is focused."""

    surfaces: tuple[int, int]
    energy: float
    centroid_mm: tuple[float, float]
    rms_mm: float
    focus_mm: float
    focused: bool


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
    ghosts: list[Ghost]
    hits: dict = field(default_factory=dict, repr=False)  # path → (x mm, y mm, power as a fraction of the direct
    # image's energy) of its rays on the image plane, all wavelengths

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


def _on_image(lens: Lens, r: ghost_paths.Rays) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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
    if not isinstance(rays, int) or isinstance(rays, bool) or not 8 <= rays <= MAX_SAMPLING:
        raise SolasError(f"rays {rays!r} must be an integer from 8 to {MAX_SAMPLING} (rays per side of the grid)")
    field_deg = lens.field_type.check(field_deg)
    wavelengths = tuple(lens.check_wavelength(w) for w in (wavelengths_nm or lens.wavelengths_nm))
    start = launch(lens, field_deg, rays)
    hits = _path_hits(lens, start, wavelengths)
    direct = hits.pop(None)
    if direct[2].sum() <= 0:
        raise SolasError(f"no direct light reaches the image at field ({field_deg[0]:g}, {field_deg[1]:g}) deg")
    direct_power = float(direct[2].sum())
    airy = 1.22 * max(wavelengths) * 1e-6 * _working_f_number(lens)
    table = [_ghost(path, hit, direct_power, airy) for path, hit in hits.items()]
    centroid = (float(np.average(direct[0], weights=direct[2])), float(np.average(direct[1], weights=direct[2])))
    # each ghost ray's power as a fraction of the direct image's energy, for the HDR PSF
    return GhostReport(
        field_deg,
        wavelengths,
        direct_power / (len(wavelengths) * start.power.sum()),
        centroid,
        table,
        {p: (h[0], h[1], h[2] / direct_power) for p, h in hits.items()},
    )


def _path_hits(lens: Lens, start: ghost_paths.Rays, wavelengths: tuple[float, ...]) -> dict:
    """Per path (None: the direct one), its rays on the image plane at every wavelength together: x, y (mm),
    power and direction tangents (`_on_image`)."""
    traced = [ghost_paths.trace_all(lens, start, w) for w in wavelengths]
    return {
        path: tuple(np.concatenate(parts) for parts in zip(*(_on_image(lens, t[path]) for t in traced)))
        for path in [None, *ghost_paths.paths(lens)]
    }


def _working_f_number(lens: Lens) -> float:
    """The lens's working f-number; NaN for a lens that forms no image (a plate, an afocal system): no ghost is
    called focused there."""
    try:
        return abs(paraxial(lens).working_f_number)
    except SolasError:
        return math.nan


def _ghost(path: tuple[int, int], hit, direct_power: float, airy_mm: float) -> Ghost:
    x, y, w, tx, ty = hit
    surfaces = (path[0] + 1, path[1] + 1)
    if w.sum() <= 0:
        return Ghost(surfaces, 0.0, (math.nan, math.nan), math.nan, math.nan, False)
    cx, cy = float(np.average(x, weights=w)), float(np.average(y, weights=w))
    rms = float(math.sqrt(np.average((x - cx) ** 2 + (y - cy) ** 2, weights=w)))
    return Ghost(
        surfaces,
        float(w.sum() / direct_power),
        (cx, cy),
        rms,
        _best_focus(x, y, w, tx, ty),
        rms <= FOCUSED_AIRY * airy_mm,
    )


DIRECT_SIZES = (33, 17, 9)  # pixels per side of the direct image's Fraunhofer core, the widest sound one
MAX_FINE = 1024  # the finest direct PSF's pixels per side (its pitch resolves the diffraction pattern)
GEOMETRIC_RAYS = 512  # rays per side of the direct image's geometric PSF over the whole window
LOG_DECADES = 8  # the log-scale PNG shows 1e-8 of the peak to the peak


def stray_light_psf(
    lens: Lens, report: GhostReport, pitch_um: float, size: int, pupil_samples: int = 256
) -> tuple[np.ndarray, tuple[float, float], list[str]]:
    """The HDR stray-light PSF (size × size, row 0 the top) in fractions of the direct image's energy per
    pixel: the direct image (geometric over the window, its central pixels the Fraunhofer PSF's where that
    is sound, `_diffraction_core`) plus every ghost's rays binned and smoothed over their spacing (`smooth`),
    centred on the first wavelength's chief ray; also that centre (mm) and a note where the direct image's
    core stays geometric."""
    from .base import check_grid
    from .methods import psf

    check_grid(pitch_um, size)
    field, wavelengths = report.field_deg, list(report.wavelengths_nm)
    geometric = psf(
        lens,
        field,
        wavelengths,
        pitch_um=pitch_um,
        size=size,
        normalization="sum",
        method="geometric",
        rays=GEOMETRIC_RAYS,
    )
    cx, cy = geometric.chief_ray_mm
    total = geometric.data * float(geometric.meta["energy_in_grid"])
    core, notes = _diffraction_core(lens, field, wavelengths, pitch_um, size, pupil_samples)
    if core is not None:
        lo = size // 2 - len(core) // 2
        total[lo : lo + len(core), lo : lo + len(core)] = core
    for x, y, w in report.hits.values():
        if len(w) > 1:
            binned, _ = bin_hits([((x - cx) * 1e3, (y - cy) * 1e3, w)], pitch_um, size)
            total += smooth(binned[0] * pitch_um**2, ray_spacing_um(x, y, w) / pitch_um)
    return total, (cx, cy), notes


def _diffraction_core(lens: Lens, field, wavelengths: list, pitch_um: float, size: int, pupil_samples: int):
    """The direct image's core by diffraction: the Fraunhofer PSF at a pitch that resolves it (λ N / 2 at the
    shortest wavelength) summed into the pixels, on the widest of `DIRECT_SIZES` windows where it is sound
    (no warning); (core, []) or (None, [why the rays' core stays])."""
    from .methods import psf

    fine_pitch = 0.5 * min(wavelengths) * 1e-3 * _working_f_number(lens)
    for inner in [min(size, n) | 1 for n in DIRECT_SIZES]:  # odd: its centre pixel is the big grid's
        fine = max(1, min(math.ceil(pitch_um / fine_pitch), MAX_FINE // inner)) | 1
        direct = psf(
            lens,
            field,
            wavelengths,
            pitch_um=pitch_um / fine,
            size=inner * fine,
            normalization="sum",
            pupil_samples=pupil_samples,
        )
        if not direct.meta["warnings"]:
            core = direct.data.reshape(inner, fine, inner, fine).sum(axis=(1, 3))
            return core * float(direct.meta["energy_in_grid"]), []
    return None, [
        f"the direct image is geometric ({GEOMETRIC_RAYS} x {GEOMETRIC_RAYS} rays): its Fraunhofer core "
        f"is not sound here ({direct.meta['warnings'][0]})"
    ]


def ray_spacing_um(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> float:
    """The mean distance (µm) between a ghost's rays on the image plane: √(π (2 σ)² / rays), σ its RMS radius."""
    cx, cy = np.average(x, weights=w), np.average(y, weights=w)
    rms = math.sqrt(np.average((x - cx) ** 2 + (y - cy) ** 2, weights=w))
    return 1e3 * math.sqrt(math.pi * (2.0 * rms) ** 2 / len(w))


def smooth(image: np.ndarray, sigma_px: float) -> np.ndarray:
    """`image` blurred by a normalised Gaussian of `sigma_px` pixels (a ray stands for its neighbourhood;
    under half a pixel: unchanged), edges zero-padded (light blurred out of the window is lost, as it is)."""
    if sigma_px < 0.5:
        return image
    half = int(min(3.0 * sigma_px, (image.shape[0] - 1) // 2))  # "same" keeps the image's length
    kernel = np.exp(-0.5 * (np.arange(-half, half + 1) / sigma_px) ** 2)
    kernel /= kernel.sum()
    rows = np.apply_along_axis(np.convolve, 1, image, kernel, "same")
    return np.apply_along_axis(np.convolve, 0, rows, kernel, "same")


def write(report: GhostReport, data: np.ndarray, centre_mm: tuple[float, float], pitch_um: float, exr, png) -> None:
    """The HDR PSF as OpenEXR (channel Y, the ghost table in its metadata) and a log-scale PNG (black:
    `LOG_DECADES` decades below the peak), whole or not at all."""
    from ..imageio import write_exr, write_png
    from ..outputs import written_together

    meta = {
        "field_deg": list(report.field_deg),
        "wavelengths_nm": list(report.wavelengths_nm),
        "pitch_um": pitch_um,
        "size": len(data),
        "chief_ray_origin_mm": list(centre_mm),
        "unit": "fraction of the direct image's energy per pixel",
        "ghosts": [
            {
                "surfaces": list(g.surfaces),
                "energy": g.energy,
                "centroid_mm": list(g.centroid_mm),
                "rms_mm": g.rms_mm,
                "focus_mm": g.focus_mm,
                "focused": g.focused,
            }
            for g in report.ghosts
            if g.energy > 0
        ],
        "irradiance": "geometric for the ghosts (binned rays), Fraunhofer for the direct image",
    }
    shown = np.log10(np.maximum(data / max(float(data.max()), 1e-300), 10.0**-LOG_DECADES)) / LOG_DECADES + 1.0
    with written_together(exr, png) as (tmp_exr, tmp_png):
        write_exr(tmp_exr, {"Y": data.astype(np.float32)}, meta)
        write_png(tmp_png, shown, encoded=True)
