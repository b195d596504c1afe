"""Image irradiance of a uniform object, from the sequential tracer: the relative illumination
that a render of a white object must reproduce.

For an object at infinity of radiance L, the irradiance at the image of field θ is
E(θ) = L · A(θ) · dω/dA_image, with A(θ) the transmitted cross-section of the collimated beam
(the pupil's transmission × the paraxial entrance-pupil area) and dω/dA_image = cos³θ / J(θ), where
J = |∂(x, y)/∂(tan θx, tan θy)| of the chief ray's image point; `chief_ray_illumination` gives
E(θ)/E(0) in this form. Rays through the rim of a beam map with a slightly different J than its
chief ray (by ≈ u'², 0.4 % for the doublet, and more off axis), and a blurred image (a ball lens)
takes light from fields far from the chief ray's, so `irradiance` integrates exactly on the image
side instead: E = L ∫ cos θ dω over the directions from the image point that leave through the lens,
wherever they cross the last vertex plane (a wide-angle's steep rays far outside the last aperture);
`relative_illumination` is its ratio to the axis's.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import SolasError
from .lens import Lens
from .paraxial import paraxial

_STEP = 1e-4  # tangent step of the finite differences
EDGE_MARGIN = 1e-9  # relative: how far the image-scale table stays inside the last field with a chief ray
_POLAR_STEP_DEG = 0.01  # polar-angle step of the finite differences of lenses with polar fields


def _jacobian(lens: Lens, field_deg: np.ndarray, wavelength_nm: float) -> np.ndarray:
    """|∂(x, y)/∂(tan x, tan y)| (mm²) of the chief ray's image point at each field (n, 2)."""
    from .pupil import chief_rays

    tan = np.tan(np.radians(field_deg))
    steps = np.array([[_STEP, 0.0], [-_STEP, 0.0], [0.0, _STEP], [0.0, -_STEP]])
    shifted = (tan[:, None, :] + steps[None]).reshape(-1, 2)
    xy = chief_rays(lens, np.degrees(np.arctan(shifted)), np.full(len(shifted), wavelength_nm)).image_xy
    xy = xy.reshape(-1, 4, 2)
    dx = (xy[:, 0] - xy[:, 1]) / (2 * _STEP)
    dy = (xy[:, 2] - xy[:, 3]) / (2 * _STEP)
    return np.abs(dx[:, 0] * dy[:, 1] - dx[:, 1] * dy[:, 0])


def irradiance(lens: Lens, image_xy: np.ndarray, wavelength_nm: float, samples: int = 512) -> np.ndarray:
    """E / L (steradians) of a lossless lens at image points (n, 2) in mm: ∫ cos θ dω over the rays
    from each point that pass every aperture (the lens traced backwards), on a samples² grid over the
    part of the last surface's vertex plane where they cross it. Where that is comes from a coarse
    grid (COARSE² points) over the square that holds every ray leaving the lens toward the point
    (`exit_pupil.exit_reach`: steep rays cross the plane far outside the last surface's aperture)."""
    from .exit_pupil import reversed_lens
    from .overlap import check_image_distance

    if not lens.at_infinity:
        raise SolasError("image irradiance is defined here for objects at infinity only")
    check_image_distance(lens, "the image irradiance")
    rev = reversed_lens(lens)
    dz = lens.surfaces[-1].thickness
    out = []
    for x, y in np.atleast_2d(np.asarray(image_xy, dtype=np.float64)):
        box = _lit_box(lens, rev, x, y, wavelength_nm)
        out.append(0.0 if box is None else _projected_solid_angle(rev, x, y, box, dz, samples, wavelength_nm))
    return np.array(out)


COARSE = 128  # points per side of the grid that finds where an image point's rays leave the lens
FEW = 16  # passing points of the coarse grid below which it is laid again, finer, over what they found


def _lit_box(lens: Lens, rev: Lens, x: float, y: float, wavelength_nm: float):
    """(u0, u1, v0, v1) (mm) on the last vertex plane holding the rays from image point (x, y) that
    leave the lens, widened by a coarse cell each side; None where none does. A beam whose footprint
    there is far smaller than a coarse cell (an image plane just behind the last surface, far from
    focus: COTS-0002-01's, 0.2 mm behind it, is lit through a disc of 0.02 mm in a 6 mm square) is
    found again on a second grid: over the first one's few points or, where it found none, over the
    paraxial beam's footprint (the cone from the image point to the exit pupil) widened threefold."""
    from .exit_pupil import exit_reach

    reach = exit_reach(lens, math.hypot(x, y))
    box = (-reach, reach, -reach, reach)
    found = _coarse_hits(rev, x, y, box, wavelength_nm)
    if found is None or found[1] < FEW:
        fine = _footprint_box(lens, x, y, wavelength_nm) if found is None else found[0]
        found = _coarse_hits(rev, x, y, fine, wavelength_nm) or found
    return None if found is None else found[0]


def _coarse_hits(rev: Lens, x: float, y: float, box, wavelength_nm: float):
    """(the box of the passing points of a COARSE² grid over `box`, widened by a cell each side, their
    count), or None where none passes."""
    from .exit_pupil import passes

    u0, u1, v0, v1 = box
    du, dv = (u1 - u0) / COARSE, (v1 - v0) / COARSE
    ex, ey = (a.ravel() for a in np.meshgrid(u0 + (np.arange(COARSE) + 0.5) * du, v0 + (np.arange(COARSE) + 0.5) * dv))
    ok = passes(rev, x, y, ex, ey, wavelength_nm)
    if not ok.any():
        return None
    return (ex[ok].min() - du, ex[ok].max() + du, ey[ok].min() - dv, ey[ok].max() + dv), int(ok.sum())


def _footprint_box(lens: Lens, x: float, y: float, wavelength_nm: float):
    """A square (mm) on the last vertex plane, thickness dz above image point (x, y), three times the
    paraxial beam's footprint there: the cone to the exit pupil (z_p, half width dz / 2N, N its f-number
    from the image plane) centred on (x, y)·(1 + dz / (z_p − z_image))."""
    px = paraxial(lens, wavelength_nm)
    dz = lens.surfaces[-1].thickness
    to_pupil = px.exit_pupil_z_mm - px.image_z_mm
    scale = 1.0 + dz / to_pupil if math.isfinite(to_pupil) and to_pupil != 0 else 1.0
    f_number = abs(px.exit_pupil_f_number)
    half = 3.0 * dz / (2.0 * f_number if math.isfinite(f_number) and f_number > 0 else 1.0) + 1e-9
    return x * scale - half, x * scale + half, y * scale - half, y * scale + half


def _projected_solid_angle(rev: Lens, x: float, y: float, box, dz: float, samples: int, wavelength_nm: float) -> float:
    """∫ cos θ dω (sr) over the rays from (x, y) through `box` on the plane dz above it that pass:
    dω cos θ = cos⁴θ dA / dz² on the plane, by the midpoint rule on samples² points."""
    from .exit_pupil import passes

    u0, u1, v0, v1 = box
    du, dv = (u1 - u0) / samples, (v1 - v0) / samples
    ex, ey = (
        a.ravel() for a in np.meshgrid(u0 + (np.arange(samples) + 0.5) * du, v0 + (np.arange(samples) + 0.5) * dv)
    )
    ok = passes(rev, x, y, ex, ey, wavelength_nm)
    cos2 = dz * dz / ((ex - x) ** 2 + (ey - y) ** 2 + dz * dz)
    return float(np.sum((cos2 * cos2)[ok]) * du * dv / (dz * dz))


def axis_irradiance(lens: Lens, wavelength_nm: float) -> float:
    """E / L on the axis of a lossless lens (steradians)."""
    return float(irradiance(lens, np.zeros((1, 2)), wavelength_nm, samples=1024)[0])


def ideal_irradiance(lens: Lens, focal_mm: float, wavelength_nm: float | None = None) -> float:
    """E / L (steradians) of the ideal camera (`camera`): the lens's paraxial entrance pupil area over
    the pinhole focal length squared. Renders and convolutions report irradiance in this unit, so an
    ideal lossless lens returns the input radiance."""
    r_ep = 0.5 * paraxial(lens, wavelength_nm).entrance_pupil_diameter_mm
    return math.pi * r_ep**2 / focal_mm**2


def relative_illumination(
    lens: Lens, field_deg: np.ndarray, wavelength_nm: float, pupil_samples: int = 128
) -> np.ndarray:
    """E(θ)/E(0) at fields (n, 2) in degrees: the image irradiance of a uniform sky at each field's chief
    ray image point over that on the axis (`irradiance`, exact however blurred the image). A finite
    object takes the chief-ray form (`chief_ray_illumination`, its pupils on `pupil_samples`² grids).
    The chief-ray form alone was off where the image is blurred: the ball lens
    (tests/data/stiff/ball_lens.toml) at 20°, 40°, 45° gave 1.34, 0.63, 0.24 where this gives 0.49, 0.44,
    0.79 and a forward trace of the sky 0.51, 0.45, 0.81 (a coarse grid: a few % of noise)."""
    from .pupil import chief_rays

    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    lens.check_wavelength(wavelength_nm)
    if not lens.at_infinity:
        return chief_ray_illumination(lens, field_deg, wavelength_nm, pupil_samples)
    fields = np.vstack([np.zeros((1, 2)), field_deg])
    e = irradiance(lens, chief_rays(lens, fields, np.full(len(fields), wavelength_nm)).image_xy, wavelength_nm)
    _check_axis_lit(lens, e[0], wavelength_nm)
    return e[1:] / e[0]


def _check_axis_lit(lens: Lens, axis: float, wavelength_nm: float) -> None:
    """E(θ)/E(0) is undefined where no light reaches the image's centre (an obscured axis)."""
    if not axis > 0:
        raise SolasError(
            f"lens {lens.name}: no light reaches the centre of the image at {wavelength_nm:g} nm "
            "(every ray toward it is stopped by an aperture), so the relative illumination "
            "E(θ)/E(0) is undefined"
        )


def chief_ray_illumination(
    lens: Lens, field_deg: np.ndarray, wavelength_nm: float, pupil_samples: int = 128
) -> np.ndarray:
    """E(θ)/E(0) at fields (n, 2) in degrees in the chief-ray form: transmission × obliquity × J(0)/J(θ),
    relative to the transmission on the axis (per solid angle for polar fields; the obliquity in
    `_obliquity`). Exact for a sharp image up to the beam's spread of mappings (0.4 % on the doublet, 3 %
    at the fisheye's 90°); far off where the image is blurred, light from fields far from the chief ray's
    landing at its point."""
    from .pupil import pupil_function

    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    lens.check_wavelength(wavelength_nm)
    fields = np.vstack([np.zeros((1, 2)), field_deg])
    pf = pupil_function(lens, fields, np.full(len(fields), wavelength_nm), pupil_samples)
    transmission = pf.transmission
    _check_axis_lit(lens, transmission[0], wavelength_nm)
    if lens.field_type.sideways:  # fields to 90° and beyond: per solid angle, sinθ dθ dφ onto h dh dφ
        scale = _polar_scale(lens, fields, wavelength_nm)
        return transmission[1:] / transmission[0] * scale[0] / scale[1:]
    tilt = _obliquity(lens, fields, pf.chief.entrance)
    j = _jacobian(lens, fields, wavelength_nm)
    return transmission[1:] / transmission[0] * tilt[1:] / tilt[0] * j[0] / j[1:]


def _obliquity(lens: Lens, field_deg: np.ndarray, entrance: np.ndarray) -> np.ndarray:
    """The factor between the transmission (`PupilFunction.transmission`) and the image irradiance
    per J at fields (n, 2) of tangent type. At infinity cos³θ: the solid angle of the field per unit
    of its tangents. A finite object's area per unit of field tangents is constant, and its transmission
    already weighs each ray as a point source's power per area (cos³ of the ray's angle): a Lambertian
    object's radiance adds the cosine of the angle at which the chief ray (toward `entrance`, (n, 2))
    leaves it: the cos⁴ law (the ray's cos³ twice, cos⁶, made an ideal relay's 0.203 of cos⁴'s 0.344 at 40°)."""
    from . import tracer

    if lens.at_infinity:
        return (1.0 + (np.tan(np.radians(field_deg)) ** 2).sum(axis=1)) ** -1.5
    d = lens.object_distance
    return d / np.sqrt(((entrance - tracer.object_points(lens, field_deg)) ** 2).sum(axis=1) + d * d)


def _polar_scale(lens: Lens, field_deg: np.ndarray, wavelength_nm: float) -> np.ndarray:
    """Image area per unit solid angle, h·(dh/dθ)/sin θ (mm²/sr; (dh/dθ)² on the axis), at polar fields
    (n, 2) of a rotationally symmetric lens: h the chief ray's image height, dh/dθ from a second chief
    ray _POLAR_STEP_DEG nearer the axis (the edge of the field has nothing beyond it)."""
    from .pupil import chief_rays

    theta = np.radians(np.hypot(field_deg[:, 0], field_deg[:, 1]))
    step = np.radians(_POLAR_STEP_DEG)
    other = np.where(theta > 0, np.maximum(theta - step, 0.0), step)
    azimuth = np.arctan2(field_deg[:, 1], field_deg[:, 0])
    direction = np.stack([np.cos(azimuth), np.sin(azimuth)], -1)
    both = np.degrees(np.concatenate([theta, other]))[:, None] * np.vstack([direction, direction])
    h = np.hypot(*chief_rays(lens, both, np.full(len(both), wavelength_nm)).image_xy.T)
    h, h_other = h[: len(theta)], h[len(theta) :]
    slope = (h - h_other) / (theta - other)
    return np.where(theta > 0, h * slope / np.maximum(np.sin(theta), 1e-300), slope**2)


def image_scales(lens: Lens, max_height_mm: float, wavelength_nm: float, samples: int = 64):
    """Radial and tangential image scales of the chief ray (mm per unit field tangent) at image
    heights 0…max_height_mm: (heights, dh/dt, h/t). Their reciprocals turn a length on the image plane
    into a width in field tangent (a pixel's footprint on the object). Where the film reaches past the
    lens's image (no chief ray through the stop centre beyond some field) the table ends at the last field
    that has one; where it reaches past the last chief ray that passes every aperture, a warning names
    that field: a render shows the dark corners a real camera shows."""
    from .pupil import chief_rays

    f0 = math.sqrt(float(_jacobian(lens, np.zeros((1, 2)), wavelength_nm)[0]))
    wanted = 1.05 * max_height_mm / f0  # past the farthest height, distortion being small
    t_max = _last_chief_tangent(lens, wanted, wavelength_nm)
    t = np.linspace(0.0, t_max, samples)
    # differences forward, or backward where chief rays end at t_max
    tt = np.concatenate([t, t + _STEP if t_max == wanted else np.maximum(t - _STEP, 0.0)])
    chief = chief_rays(
        lens, np.stack([np.degrees(np.arctan(tt)), np.zeros_like(tt)], -1), np.full(len(tt), wavelength_nm)
    )
    h = chief.image_xy[:, 0]
    dt = tt[samples:] - t
    radial = (h[samples:] - h[:samples]) / np.where(dt != 0, dt, 1.0)
    radial[0] = radial[0] if dt[0] != 0 else radial[1]
    tangential = np.concatenate([[radial[0]], h[1:samples] / t[1:]])
    clear = np.flatnonzero(np.cumprod(~chief.vignetted[:samples]))  # chief rays that pass every aperture
    last = clear[-1] if len(clear) else 0
    if (t_max < wanted or last < samples - 1) and h[last] < max_height_mm:  # cut short by the lens, not the table
        warnings.warn(
            f"lens {lens.name}'s chief rays pass every aperture up to field "
            f"{math.degrees(math.atan(t[last])):.4g} deg (image height {h[last]:.4g} mm) at {wavelength_nm:g} "
            f"nm and the film reaches {max_height_mm:.4g} mm: beyond, the image darkens to the dark corners "
            "a real camera shows",
            stacklevel=2,
        )
    return h[:samples], radial, tangential


def _last_chief_tangent(lens: Lens, t_max: float, wavelength_nm: float, bisections: int = 40) -> float:
    """t_max, or where chief rays through the stop centre end before it the largest field tangent (along
    x) that has one: beyond, a field's light (if any) lands where no chief ray maps it."""
    from .pupil import chief_rays

    def exists(t: float) -> bool:  # a ray through the stop centre (a substitute nearest it maps nothing)
        try:
            chief = chief_rays(lens, [[math.degrees(math.atan(t)), 0.0]], [wavelength_nm])
        except SolasError:
            return False
        return not bool(chief.off_centre[0])

    if exists(t_max):
        return t_max
    lo, hi = 0.0, t_max
    for _ in range(bisections):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if exists(mid) else (lo, mid)
    # backed off the edge, where round-off decides whether the aim reaches the stop centre: the Cooke
    # triplet's chief ray there fell to a substitute in the table's batch, its image height turned back and
    # a negative footprint rendered the whole image black (--fov-deg 30)
    return lo * (1.0 - EDGE_MARGIN)
