"""Chief rays and the pupil function on the exit-pupil reference sphere (the aim itself: `aiming`).

For each field, the chief ray is aimed through the stop centre (`aiming.chief_aim` says where a wide
field's aim starts, and where no ray reaches the centre, the passing ray nearest it); the reference sphere is centred on
the chief ray's image point P0 and passes through the chief ray's crossing of the paraxial exit-pupil
plane. The pupil is sampled on a regular grid of direction cosines (α, β) of the vector from P0 to the
sphere point, each ray found by Newton iteration on its entrance coordinates, so the Fraunhofer
integral is an exact matrix DFT in (α, β). Lengths in mm.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from . import tracer
from .lens import Lens
from .aiming import Bundle, chief_aim, continued_aim, nearest_passing, stop_target, aim
from .paraxial import paraxial, pupil_distance

__all__ = ["Bundle", "aim", "ChiefRays", "chief_rays", "widest_field", "stop_rim", "stop_aim", "PupilFunction",
           "pupil_function", "entrance_power", "nearest_passing"]
dr = tracer.dr
RIM_RAYS = 32
RIM_BISECTIONS = 30  # a rim ray moved inside the stop's rim: its radius to 1e-9 of the rim's
RIM_STEPS = 8  # lenses of polar fields: steps of the rim aim from the stop centre out to the rim


@dataclass
class ChiefRays:
    """Chief rays of a batch of fields (mm)."""

    entrance: np.ndarray  # (n, 2) entrance coordinates
    image_xy: np.ndarray  # (n, 2) image-plane point P0
    sphere_radius: np.ndarray  # (n,) reference-sphere radius
    opl: np.ndarray  # (n,) optical path to the reference sphere
    sphere_point: np.ndarray  # (n, 2) (α, β) of the chief ray's sphere point: (Q0 − P0) / R
    n_image: np.ndarray  # (n,)
    vignetted: np.ndarray  # (n,) bool: an aperture blocks the chief ray itself, or none reaches the stop centre
    off_centre: np.ndarray  # (n,) bool: no ray reaches the stop centre; the ray is the passing one nearest it


def chief_rays(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray) -> ChiefRays:
    """Real chief rays aimed through the stop centre; SolasError for a field no ray can reach."""
    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),))
    b = Bundle(lens, field_deg, wavelength_nm, 1)
    e0, goal = chief_aim(lens, b)
    ex, ey, tr, conv = aim(b, stop_target, tracer.F(e0[:, 0]), tracer.F(e0[:, 1]),
                           tracer.F(goal[:, 0]), tracer.F(goal[:, 1]))
    missed = np.flatnonzero(~tracer.to_numpy(conv)[0])
    if len(missed):  # the aim at the stop centre can miss at the very edge of the fields it reaches (the Cooke
        for f in missed:  # triplet at 31.842°): the passing ray nearest it, as where none reaches it; refused
            found = nearest_passing(lens, field_deg[f], wavelength_nm[f])  # only where no ray passes the stop
            if found is not None:
                e0[f], goal[f] = found
        ex, ey, tr, conv = aim(b, stop_target, tracer.F(e0[:, 0]), tracer.F(e0[:, 1]),
                               tracer.F(goal[:, 0]), tracer.F(goal[:, 1]))
    px, py, _ = tracer.to_plane(tr, lens.image_z)
    xp_z = np.array([paraxial(lens, w).exit_pupil_z_mm for w in wavelength_nm])
    qx, qy, qopl = tracer.to_plane(tr, b.per_ray(xp_z))
    radius = dr.sqrt((qx - px) ** 2 + (qy - py) ** 2 + (b.per_ray(xp_z) - lens.image_z) ** 2)
    ex, ey, px, py, radius, qopl, sa, sb, n_image, conv, clipped = tracer.to_numpy(
        ex, ey, px, py, radius, qopl, (qx - px) / radius, (qy - py) / radius, tr.n_image, conv, tr.clipped_by)
    if not conv.all():
        bad = field_deg[~conv][0]
        raise SolasError(f"no real ray of {wavelength_nm[~conv][0]:g} nm passes the stop for field "
                         f"({bad[0]:g}, {bad[1]:g}) deg; the lens does not image that field")
    return ChiefRays(
        entrance=np.stack([ex, ey], axis=-1),
        image_xy=np.stack([px, py], axis=-1),
        sphere_radius=radius,
        opl=qopl,
        sphere_point=np.stack([sa, sb], axis=-1),
        n_image=np.broadcast_to(n_image, (b.n_fields,)).copy(),
        vignetted=(clipped != 0) | (np.hypot(*goal.T) > 0),
        off_centre=np.hypot(*goal.T) > 0,
    )


def widest_field(lens: Lens, wavelength_nm: float, samples: int = 45) -> float:
    """The widest field (degrees, on the y axis, up to what the lens's field type allows) whose chief ray
    reaches the stop centre and passes every aperture: for lenses whose file states no field."""
    top = lens.field_type.largest_deg
    reached = float(continued_aim(lens, np.array([[0.0, top]]), np.array([wavelength_nm]))[1][0])
    fields = np.linspace(0.0, reached * top, samples)
    chief = chief_rays(lens, np.stack([np.zeros(samples), fields], axis=-1), np.full(samples, wavelength_nm))
    clear = np.flatnonzero(np.cumprod(~chief.vignetted))
    return float(fields[clear[-1]])


def stop_rim(rim: Bundle, chief: ChiefRays, accept=None, vignetting: np.ndarray | None = None,
             ) -> tuple[np.ndarray, np.ndarray, tracer.Traced, np.ndarray]:
    """Rays aimed at RIM_RAYS points of the stop's rim for each field of the `rim` bundle: entrance
    coordinates (n, RIM_RAYS) each, the trace, and which passed. Where the ray to the rim fails (total
    internal reflection, a surface missed, or `accept(traced)` false) the pupil's edge lies inside the
    rim: that ray is moved in, by bisection of its radius at the stop, to the outermost one that passes.
    `vignetting` (n, 4): per field the fractions (+x, −x, +y, −y) of the stop's radius cut off, as a lens
    file's vignetting factors give them (the rim squeezed to an ellipse of those four half-axes)."""
    lens = rim.lens
    r_stop = lens.surfaces[lens.stop_index].semi_diameter
    phi = np.tile(np.linspace(0.0, 2.0 * math.pi, RIM_RAYS, endpoint=False), rim.n_fields)
    cos, sin = np.cos(phi), np.sin(phi)
    if vignetting is not None:  # the rim's ellipse: its points scaled per side
        v = np.repeat(np.asarray(vignetting, dtype=np.float64), RIM_RAYS, axis=0)
        cos, sin = cos * (1.0 - np.where(cos >= 0, v[:, 0], v[:, 1])), sin * (1.0 - np.where(sin >= 0, v[:, 2], v[:, 3]))

    def at(scale: np.ndarray):
        ex, ey, tr, ok = stop_aim(rim, chief, tracer.F(r_stop * scale * cos), tracer.F(r_stop * scale * sin))
        return ex, ey, tr, tracer.to_numpy(ok & accept(tr) if accept is not None else ok)[0]

    ex, ey, tr, ok = at(np.ones(len(phi)))
    if not ok.all():
        lo, hi = np.where(ok, 1.0, 0.0), np.ones(len(phi))
        for _ in range(RIM_BISECTIONS):
            mid = 0.5 * (lo + hi)
            passed = at(mid)[3]
            lo, hi = np.where(passed, mid, lo), np.where(passed, hi, mid)
        ex, ey, tr, ok = at(lo)
    shape = (rim.n_fields, RIM_RAYS)
    ex, ey = tracer.to_numpy(ex, ey)
    return ex.reshape(shape), ey.reshape(shape), tr, ok.reshape(shape)


def stop_aim(b: Bundle, chief: ChiefRays, gx: tracer.F, gy: tracer.F):
    """The rays of bundle `b` aimed at the stop points (gx, gy) (mm in the stop's plane, per ray): each
    starts from its field's chief ray, shifted by the paraxial entrance-pupil/stop size ratio (wide
    fields, whose pupil is squeezed and tilted, grow the aim out from the chief ray in RIM_STEPS);
    entrance coordinates, the trace and whether the aim converged (Dr.Jit)."""
    lens = b.lens
    ex, ey = b.per_ray(chief.entrance[:, 0]), b.per_ray(chief.entrance[:, 1])
    if lens.field_type.sideways:
        for k in range(1, RIM_STEPS):
            ex, ey, _, _ = aim(b, stop_target, ex, ey, gx * (k / RIM_STEPS), gy * (k / RIM_STEPS))
    else:
        ratio = entrance_pupil_footprint(lens) / lens.surfaces[lens.stop_index].semi_diameter
        ex, ey = ex + gx * ratio, ey + gy * ratio
    return aim(b, stop_target, ex, ey, gx, gy)


def entrance_pupil_footprint(lens: Lens) -> float:
    """Radius (mm) of the paraxial on-axis beam in entrance coordinates: the entrance pupil's for an
    object at infinity; for a finite object, the cone from the object point to the entrance pupil's rim
    where it crosses the plane z = 0 that entrance coordinates lie in (the pupil far behind that plane,
    or virtual, gives a footprint much smaller than the pupil)."""
    p = paraxial(lens)
    r_ep = 0.5 * p.entrance_pupil_diameter_mm
    if lens.at_infinity:
        return r_ep
    return r_ep * abs(lens.object_distance / pupil_distance(lens, p.entrance_pupil_z_mm))


@dataclass
class PupilFunction:
    """Pupil functions of a batch of fields on regular (α, β) grids (relative to the chief ray)."""

    alpha: np.ndarray  # (n, N) direction cosines of grid columns
    beta: np.ndarray  # (n, N) direction cosines of grid rows
    opd_mm: np.ndarray  # (n, N, N) optical path difference to the chief ray, [field, β, α]
    power: np.ndarray  # (n, N, N) power per dα dβ, as a fraction of the on-axis entrance-pupil power
    coverage: np.ndarray  # (n, N, N) fraction of each grid cell inside the apertures
    chief: ChiefRays
    wavelength_nm: np.ndarray  # (n,)
    vignetted_by: list[list[int]]  # per field: 1-based surfaces that block part of the pupil

    @property
    def cell_area(self) -> np.ndarray:
        """dα dβ of one grid cell, per field."""
        return (self.alpha[:, 1] - self.alpha[:, 0]) * (self.beta[:, 1] - self.beta[:, 0])

    @property
    def amplitude(self) -> np.ndarray:
        """Field amplitude per grid cell: √power × covered fraction."""
        return np.sqrt(self.power) * self.coverage

    @property
    def transmission(self) -> np.ndarray:
        """Fraction of the on-axis entrance-pupil power that reaches the image, per field."""
        return np.sum(self.power * self.coverage, axis=(1, 2)) * self.cell_area


def entrance_power(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, ex: np.ndarray,
                   ey: np.ndarray) -> np.ndarray:
    """Power per unit entrance area (1/mm²) of rays at entrance coordinates ex, ey (n, ...) for
    fields (n, 2): the on-axis entrance pupil carries 1. Finite objects add cos³ of the ray's angle
    to the axis (a point source's power per area of the aim plane)."""
    density = np.array([_power_density(lens, float(w)) for w in wavelength_nm])
    density = density.reshape((-1,) + (1,) * (np.ndim(ex) - 1))
    if lens.at_infinity:
        return np.broadcast_to(density, np.shape(ex))
    pts = tracer.object_points(lens, field_deg).reshape((-1, 2) + (1,) * (np.ndim(ex) - 1))
    dist2 = (ex - pts[:, 0]) ** 2 + (ey - pts[:, 1]) ** 2 + lens.object_distance ** 2
    return density * abs(lens.object_distance) ** 3 / dist2 ** 1.5  # a virtual object's converging cone alike


def _power_density(lens: Lens, wavelength_nm: float) -> float:
    """Power per unit entrance area (1/mm²) on axis, such that the on-axis entrance pupil carries 1."""
    p = paraxial(lens, wavelength_nm)
    r_ep = 0.5 * p.entrance_pupil_diameter_mm
    if lens.at_infinity:
        return 1.0 / (math.pi * r_ep ** 2)
    half = math.atan(r_ep / pupil_distance(lens, p.entrance_pupil_z_mm))
    solid = 4.0 * math.pi * math.sin(0.5 * half) ** 2  # = 2π(1 − cos θ), without its cancellation
    return 1.0 / (lens.object_distance ** 2 * solid)


def pupil_function(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, samples: int) -> PupilFunction:
    """Pupil function on an N×N (α, β) grid (N = `samples`, checked by `psf.methods.check_method`) for each
    field/wavelength pair."""
    return pupil_functions(lens, field_deg, wavelength_nm, (samples,))[0]


def pupil_functions(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, samples) -> list[PupilFunction]:
    """`pupil_function` at each of several grid sizes `samples`, sharing the chief rays and the rim."""
    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),)).copy()
    chief = chief_rays(lens, field_deg, wavelength_nm)
    rim = _sphere_rim(lens, field_deg, wavelength_nm, chief)
    return [_sampled_pupil(lens, field_deg, wavelength_nm, chief, _pupil_grid(chief, rim, n)) for n in samples]


def _sampled_pupil(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, chief: ChiefRays, grid
                   ) -> PupilFunction:
    """The pupil function on the (α, β) grid (alpha, beta, affine) of `_pupil_grid`."""
    nf = len(field_deg)
    alpha, beta, affine = grid
    opd, ok, clipped, sx, sy, ex, ey = _grid_rays(lens, field_deg, wavelength_nm, chief, alpha, beta, affine)

    # Amplitude: power density × |∂e/∂(α,β)|, stop edge anti-aliased by the covered cell fraction.
    r_stop = lens.surfaces[lens.stop_index].semi_diameter
    da = (alpha[:, 1] - alpha[:, 0])[:, None, None]
    db = (beta[:, 1] - beta[:, 0])[:, None, None]

    def jacobian(u: np.ndarray, w: np.ndarray) -> np.ndarray:
        """|∂(u, w)/∂(α, β)| on the grid of each field."""
        du_db, du_da = np.gradient(u, axis=(1, 2))
        dw_db, dw_da = np.gradient(w, axis=(1, 2))
        return np.abs(du_da * dw_db - du_db * dw_da) / (da * db)

    power = entrance_power(lens, field_deg, wavelength_nm, ex, ey) * jacobian(ex, ey)
    cell = np.sqrt(jacobian(sx, sy) * da * db)  # grid cell size at the stop (mm)
    margin = r_stop - np.hypot(sx, sy)
    coverages = np.clip(0.5 + margin / np.maximum(cell, 1e-300), 0.0, 1.0)
    stop_code = lens.stop_index + 1
    other = (clipped != 0) & (clipped != stop_code)
    coverages = np.where(other | ~ok | ~np.isfinite(power), 0.0, coverages)
    powers = np.where(coverages > 0, power, 0.0)
    vignetted = [sorted({int(c) for c in np.unique(clipped[f][ok[f] & (margin[f] > 0)]) if c != 0})
                 for f in range(nf)]
    opd = np.where(coverages > 0, opd, 0.0)
    return PupilFunction(alpha, beta, opd, powers, coverages, chief, wavelength_nm, vignetted)


def _sphere_target(lens: Lens, b: Bundle, chief: ChiefRays):
    """The aim target of `b`'s rays: direction cosines (α, β) of their point on each field's reference
    sphere, seen from the chief ray's image point."""
    cx, cy = b.per_ray(chief.image_xy[:, 0]), b.per_ray(chief.image_xy[:, 1])
    radius = b.per_ray(chief.sphere_radius)
    cz = lens.image_z

    def target(tr: tracer.Traced):
        x, y, _z, _opl, hit = tracer.to_sphere(tr, cx, cy, cz, radius)
        return (x - cx) / radius, (y - cy) / radius, tr.ok & hit

    return target


def _sphere_rim(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, chief: ChiefRays):
    """The rim of the stop seen on each field's reference sphere: entrance coordinates (n, RIM_RAYS)
    each, (α, β) relative to the chief ray, and which rim rays passed; SolasError for a field none passes."""
    nf = len(field_deg)
    rim = Bundle(lens, field_deg, wavelength_nm, RIM_RAYS)
    rim_target = _sphere_target(lens, rim, chief)
    rex, rey, rtr, rok = stop_rim(rim, chief, accept=lambda tr: rim_target(tr)[2])
    ra, rb = (a.reshape(nf, RIM_RAYS) for a in tracer.to_numpy(*rim_target(rtr)[:2]))
    if not rok.any(axis=1).all():
        bad = field_deg[~rok.any(axis=1)][0]
        raise SolasError(f"no real ray reaches the stop's rim for field ({bad[0]:g}, {bad[1]:g}) deg; "
                         "the lens is not usable there")
    return rex, rey, ra - chief.sphere_point[:, 0:1], rb - chief.sphere_point[:, 1:2], rok


def _pupil_grid(chief: ChiefRays, rim, samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rim of the stop (`_sphere_rim`) → per field the (α, β) grid (n, N) each, relative to the chief
    ray, that holds the pupil, and an affine map (n, 3, 2) from (1, α, β) to entrance coordinates (the
    grid's first aim)."""
    rex, rey, ra, rb, rok = rim
    nf = len(rex)
    alpha = np.empty((nf, samples))
    beta = np.empty((nf, samples))
    affine = np.empty((nf, 3, 2))
    for f in range(nf):
        m = rok[f]
        a_rel, b_rel = ra[f, m], rb[f, m]
        for grid, lo, hi in ((alpha, a_rel.min(), a_rel.max()), (beta, b_rel.min(), b_rel.max())):
            half = 0.5 * (hi - lo) * (1.0 + 2.0 / samples) * 1.01
            mid = 0.5 * (hi + lo)
            grid[f] = mid + half * np.linspace(-1.0, 1.0, samples)
        design = np.stack([np.ones(m.sum()), a_rel, b_rel], axis=1)
        affine[f], *_ = np.linalg.lstsq(design, np.stack([rex[f, m], rey[f, m]], axis=1), rcond=None)
    return alpha, beta, affine


def _grid_rays(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, chief: ChiefRays, alpha: np.ndarray,
               beta: np.ndarray, affine: np.ndarray) -> tuple[np.ndarray, ...]:
    """Every grid ray aimed at its (α, β): per field (n, N, N) its OPD to the chief ray (mm), whether it
    converged and reached the sphere, the surface that clipped it (1-based, 0: none), its stop crossing
    (mm) and its entrance coordinates (mm)."""
    nf, samples = alpha.shape
    g = Bundle(lens, field_deg, wavelength_nm, samples * samples)
    ca, cb = chief.sphere_point[:, 0], chief.sphere_point[:, 1]
    ta = np.broadcast_to(alpha[:, None, :], (nf, samples, samples))
    tb = np.broadcast_to(beta[:, :, None], (nf, samples, samples))
    ex0 = affine[:, 0, 0, None, None] + affine[:, 1, 0, None, None] * ta + affine[:, 2, 0, None, None] * tb
    ey0 = affine[:, 0, 1, None, None] + affine[:, 1, 1, None, None] * ta + affine[:, 2, 1, None, None] * tb
    goal_a = tracer.F((ta + ca[:, None, None]).ravel())
    goal_b = tracer.F((tb + cb[:, None, None]).ravel())
    gex, gey, gtr, gconv = aim(g, _sphere_target(lens, g, chief), tracer.F(ex0.ravel()), tracer.F(ey0.ravel()),
                               goal_a, goal_b)
    cx, cy = g.per_ray(chief.image_xy[:, 0]), g.per_ray(chief.image_xy[:, 1])
    _, _, _, opl, hit = tracer.to_sphere(gtr, cx, cy, lens.image_z, g.per_ray(chief.sphere_radius))
    shape = (nf, samples, samples)
    opl, ok, clipped, sx, sy, ex, ey = (a.reshape(shape) for a in tracer.to_numpy(
        opl, gconv & hit, gtr.clipped_by, gtr.stop_x, gtr.stop_y, gex, gey))
    return opl - chief.opl[:, None, None], ok, clipped, sx, sy, ex, ey
