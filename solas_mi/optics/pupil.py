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
from dataclasses import fields as dataclass_fields

import numpy as np

from ..errors import SolasError
from . import pupil_grid, tracer
from .aiming import Bundle, aim, chief_aim, continued_aim, nearest_passing, stop_target
from .lens import Lens
from .paraxial import paraxial, pupil_distance

__all__ = [
    "Bundle",
    "aim",
    "ChiefRays",
    "chief_rays",
    "widest_field",
    "stop_rim",
    "stop_aim",
    "PupilFunction",
    "pupil_function",
    "entrance_power",
    "nearest_passing",
    "Pupils",
]
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

    def subset(self, index: np.ndarray) -> ChiefRays:
        """The chief rays of the fields `index`."""
        return ChiefRays(**{f.name: getattr(self, f.name)[index] for f in dataclass_fields(self)})


def chief_rays(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray) -> ChiefRays:
    """Real chief rays aimed through the stop centre; SolasError for a field no ray can reach."""
    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),))
    b = Bundle(lens, field_deg, wavelength_nm, 1)
    e0, goal, aimed = chief_aim(lens, b)
    ex, ey, tr, conv = aimed or aim(
        b,
        stop_target,
        tracer.array(e0[:, 0]),
        tracer.array(e0[:, 1]),
        tracer.array(goal[:, 0]),
        tracer.array(goal[:, 1]),
    )
    missed = np.flatnonzero(~tracer.to_numpy(conv)[0])
    if len(missed):  # the aim at the stop centre can miss at the very edge of the fields it reaches (the Cooke
        for f in missed:  # triplet at 31.842°): the passing ray nearest it, as where none reaches it; refused
            found = nearest_passing(lens, field_deg[f], wavelength_nm[f])  # only where no ray passes the stop
            if found is not None:
                e0[f], goal[f] = found
        ex, ey, tr, conv = aim(
            b,
            stop_target,
            tracer.array(e0[:, 0]),
            tracer.array(e0[:, 1]),
            tracer.array(goal[:, 0]),
            tracer.array(goal[:, 1]),
        )
    image_z = tracer.opaque(lens.image_z)  # a kernel input, not a literal: a new lens reuses the kernels
    px, py, _ = tracer.to_plane(tr, image_z)
    distinct, which = np.unique(wavelength_nm, return_inverse=True)  # paraxial data once per wavelength
    xp_z = np.array([paraxial(lens, w).exit_pupil_z_mm for w in distinct])[which.ravel()]
    qx, qy, qopl = tracer.to_plane(tr, b.per_ray(xp_z))
    radius = dr.sqrt((qx - px) ** 2 + (qy - py) ** 2 + (b.per_ray(xp_z) - image_z) ** 2)
    ex, ey, px, py, radius, qopl, sa, sb, n_image, conv, clipped = tracer.to_numpy(
        ex, ey, px, py, radius, qopl, (qx - px) / radius, (qy - py) / radius, tr.n_image, conv, tr.clipped_by
    )
    if not conv.all():
        bad = field_deg[~conv][0]
        raise SolasError(
            f"no real ray of {wavelength_nm[~conv][0]:g} nm passes the stop for field "
            f"({bad[0]:g}, {bad[1]:g}) deg; the lens does not image that field"
        )
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


def stop_rim(
    rim: Bundle,
    chief: ChiefRays,
    accept=None,
    vignetting: np.ndarray | None = None,
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
        cos, sin = (
            cos * (1.0 - np.where(cos >= 0, v[:, 0], v[:, 1])),
            sin * (1.0 - np.where(sin >= 0, v[:, 2], v[:, 3])),
        )

    def at(scale: np.ndarray):
        ex, ey, tr, ok = stop_aim(rim, chief, tracer.array(r_stop * scale * cos), tracer.array(r_stop * scale * sin))
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
        ratio = tracer.opaque(entrance_pupil_footprint(lens) / lens.surfaces[lens.stop_index].semi_diameter)
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
    complex_pupil: np.ndarray  # (n, N, N) complex64: amplitude × e^{i 2π opd / λ}, the Fraunhofer integrand
    phase_step: np.ndarray  # (n,) largest phase step (rad) between neighbouring cells inside the pupil

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


def entrance_power(
    lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, ex: np.ndarray, ey: np.ndarray
) -> np.ndarray:
    """Power per unit entrance area (1/mm²) of rays at entrance coordinates ex, ey (n, ...) for
    fields (n, 2): the on-axis entrance pupil carries 1. Finite objects add cos³ of the ray's angle
    to the axis (a point source's power per area of the aim plane)."""
    density = power_densities(lens, wavelength_nm).reshape((-1,) + (1,) * (np.ndim(ex) - 1))
    if lens.at_infinity:
        return np.broadcast_to(density, np.shape(ex))
    pts = tracer.object_points(lens, field_deg).reshape((-1, 2) + (1,) * (np.ndim(ex) - 1))
    return density * _obliquity(lens, ex - pts[:, 0], ey - pts[:, 1], np.sqrt)


def _obliquity(lens: Lens, dx, dy, sqrt):
    """cos³ of the angle to the axis of rays from an object point offset (dx, dy) mm from where they
    meet the aim plane (any array type, given its `sqrt`): a virtual object's converging cone alike."""
    dist2 = dx * dx + dy * dy + lens.object_distance**2
    return abs(lens.object_distance) ** 3 / (dist2 * sqrt(dist2))


def power_densities(lens: Lens, wavelength_nm: np.ndarray) -> np.ndarray:
    """`_power_density` per wavelength (n,), each distinct wavelength's paraxial data computed once."""
    distinct, which = np.unique(np.asarray(wavelength_nm, dtype=np.float64), return_inverse=True)
    return np.array([_power_density(lens, float(w)) for w in distinct])[which.ravel()]


def _power_density(lens: Lens, wavelength_nm: float) -> float:
    """Power per unit entrance area (1/mm²) on axis, such that the on-axis entrance pupil carries 1."""
    p = paraxial(lens, wavelength_nm)
    r_ep = 0.5 * p.entrance_pupil_diameter_mm
    if lens.at_infinity:
        return 1.0 / (math.pi * r_ep**2)
    half = math.atan(r_ep / pupil_distance(lens, p.entrance_pupil_z_mm))
    solid = 4.0 * math.pi * math.sin(0.5 * half) ** 2  # = 2π(1 − cos θ), without its cancellation
    return 1.0 / (lens.object_distance**2 * solid)


def pupil_function(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, samples: int) -> PupilFunction:
    """Pupil function on an N×N (α, β) grid (N = `samples`, checked by `psf.methods.check_method`) for each
    field/wavelength pair."""
    return pupil_functions(lens, field_deg, wavelength_nm, (samples,))[0]


def pupil_functions(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, samples) -> list[PupilFunction]:
    """`pupil_function` at each of several grid sizes `samples`, sharing the chief rays and the rim."""
    pupils = Pupils(lens, field_deg, wavelength_nm)
    return [pupils.sampled(n) for n in samples]


class Pupils:
    """The chief rays and stop rims of field/wavelength pairs, from which their pupil functions are
    sampled at any grid size, of every pair or of some (`sampled`)."""

    def __init__(self, lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray):
        self.lens = lens
        self.field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
        self.wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(self.field_deg),)).copy()
        self.chief = chief_rays(lens, self.field_deg, self.wavelength_nm)
        self.rim = _sphere_rim(lens, self.field_deg, self.wavelength_nm, self.chief)
        self.solved: dict[int, tuple] = {}  # per grid size sampled of every pair, its rays (`grid_rays`)

    def sampled(self, samples: int, index: np.ndarray | None = None) -> PupilFunction:
        """The pupil functions on samples² (α, β) grids: of every pair, or of the pairs `index`. A grid
        no finer than one already sampled of every pair is aimed from that one's rays."""
        lens, fields, waves, chief, rim = self.lens, self.field_deg, self.wavelength_nm, self.chief, self.rim
        finer = [n for n in self.solved if n >= samples]
        start = self.solved[min(finer)] if finer else None
        if index is not None:
            fields, waves, chief, rim = fields[index], waves[index], chief.subset(index), tuple(r[index] for r in rim)
            start = None if start is None else ([v[index] for v in start[0]], start[1][index], start[2][index])
        alpha, beta = pupil_grid.grid_axes(rim, samples)
        g, ex, ey, ok, kept, solved = pupil_grid.grid_rays(
            lens, fields, waves, chief, alpha, beta, pupil_grid.affine_map(rim), start
        )
        if index is None:
            self.solved[samples] = solved
        density = g.per_ray(power_densities(lens, waves))
        if lens.at_infinity:

            def power(ex, ey):
                return density
        else:
            pts = tracer.object_points(lens, fields)

            def power(ex, ey):
                return density * _obliquity(lens, ex - g.per_ray(pts[:, 0]), ey - g.per_ray(pts[:, 1]), dr.sqrt)

        return PupilFunction(
            alpha,
            beta,
            chief=chief,
            wavelength_nm=waves,
            **pupil_grid.cells(lens, g, ex, ey, ok, kept, alpha, beta, power),
        )


def _sphere_rim(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, chief: ChiefRays):
    """The rim of the stop seen on each field's reference sphere: entrance coordinates (n, RIM_RAYS)
    each, (α, β) relative to the chief ray, and which rim rays passed; SolasError for a field none passes."""
    nf = len(field_deg)
    rim = Bundle(lens, field_deg, wavelength_nm, RIM_RAYS)
    rim_target = pupil_grid.sphere_target(lens, rim, chief)
    rex, rey, rtr, rok = stop_rim(rim, chief, accept=lambda tr: rim_target(tr)[2])
    ra, rb = (a.reshape(nf, RIM_RAYS) for a in tracer.to_numpy(*rim_target(rtr)[:2]))
    if not rok.any(axis=1).all():
        bad = field_deg[~rok.any(axis=1)][0]
        raise SolasError(
            f"no real ray reaches the stop's rim for field ({bad[0]:g}, {bad[1]:g}) deg; the lens is not usable there"
        )
    return rex, rey, ra - chief.sphere_point[:, 0:1], rb - chief.sphere_point[:, 1:2], rok
