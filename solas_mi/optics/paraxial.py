"""First-order (paraxial) optics of a lens: focal length, pupils, f-number, chief rays.

Lengths in mm; z measured from surface 1's vertex; slopes are paraxial angles (tangents).

Reference: the y-nu paraxial ray trace, W. J. Smith, "Modern Optical Engineering", 4th ed.,
McGraw-Hill, 2008, ch. 2–3.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import SolasError
from .lens import Lens, check_lens


@dataclass(frozen=True)
class Paraxial:
    """Paraxial data at one wavelength (mm unless named otherwise)."""

    wavelength_nm: float
    efl_mm: float  # 1/power: the EFL in air (Zemax's "in air"), object and image heights' scale
    efl_image_space_mm: float  # n'/power: the EFL in the image medium (Zemax's "in image space", optiland's f2)
    bfd_mm: float  # from the last refracting surface (the medium changes there) to the paraxial focus
    focus_z_mm: float  # paraxial image of the object
    image_z_mm: float  # the lens file's image plane
    image_offset_mm: float  # image plane − paraxial focus (negative: the plane lies inside focus)
    entrance_pupil_z_mm: float
    entrance_pupil_diameter_mm: float
    exit_pupil_z_mm: float
    exit_pupil_diameter_mm: float
    f_number: float  # EFL / EPD
    working_f_number: float  # 1 / (2 n' |u'|) of the marginal ray
    exit_pupil_f_number: float  # (image plane − exit pupil) / exit pupil diameter
    fields_deg: tuple[float, ...]
    chief_ray_image_height_mm: tuple[float, ...]  # paraxial chief ray at the image plane

    def as_dict(self) -> dict:
        return asdict(self)


def ynu_trace(
    lens: Lens,
    wavelength_nm: float,
    y1: float,
    u0: float,
    start: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Paraxial ray heights at each surface and slopes after each surface.

    The ray has height `y1` at surface `start` and slope `u0` just before it (earlier entries are NaN).
    """
    n = lens.indices(wavelength_nm)
    z = lens.vertex_z
    m = len(lens.surfaces)
    y = np.full(m, np.nan)
    u = np.full(m, np.nan)
    height, slope = y1, u0
    for k in range(start, m):
        if k > start:
            height = height + slope * (z[k] - z[k - 1])
        s = lens.surfaces[k]
        power = (n[k + 1] - n[k]) * s.paraxial_curvature + (1.0 / s.focal_length if s.focal_length is not None else 0.0)
        slope = (n[k] * slope - height * power) / n[k + 1]
        y[k], u[k] = height, slope
    return y, u


@functools.lru_cache(maxsize=64)
def ideal_conjugates(lens: Lens) -> dict[int, float | None]:
    """Per ideal thin lens (surface index k → w, 1/mm): the signed inverse distance from it to the paraxial
    image of the object formed by the surfaces before it, at the primary wavelength (0: at infinity;
    negative: a real point in front of it). That point is the conjugate whose pencil the ideal lens
    makes perfect (`tracer`); an ideal lens at that point (marginal height 0: an intermediate image, or a
    virtual object on it) takes None (`ideal.deflect`)."""
    wl = lens.primary_wavelength
    y, u = ynu_trace(lens, wl, 1.0, 0.0) if lens.at_infinity else _object_ray(lens, wl, 0.0, 1.0)
    before = np.concatenate([[0.0 if lens.at_infinity else 1.0], u[:-1]])
    return {k: (-float(before[k] / y[k]) if y[k] != 0 else None) for k, s in enumerate(lens.surfaces) if s.ideal}


def pupil_distance(lens: Lens, ep_z: float) -> float:
    """mm from a finite object to the entrance pupil at `ep_z` (negative where the pupil lies beyond a virtual
    object); SolasError where the object lies in the pupil, as every chief ray meets there."""
    distance = ep_z + lens.object_distance
    if abs(distance) <= 1e-9 * abs(lens.object_distance):
        raise SolasError(
            f"lens {lens.name}: the object lies in the entrance pupil ({ep_z:g} mm from surface 1), "
            "where every chief ray meets: a field names no object point; move the object or the stop"
        )
    return distance


def _object_ray(lens: Lens, wavelength_nm: float, y_obj: float, u0: float) -> tuple[np.ndarray, np.ndarray]:
    """A ray leaving the object plane at height `y_obj` with slope `u0` (finite objects)."""
    return ynu_trace(lens, wavelength_nm, y_obj + u0 * lens.object_distance, u0)


def paraxial(lens: Lens, wavelength_nm: float | None = None, fields_deg: list[float] | None = None) -> Paraxial:
    """First-order data of a lens at one wavelength: focal lengths, pupils, f-numbers, chief rays.

    From the y-nu paraxial ray trace. Results for the default fields are memoised by the lens's content
    (every field of the frozen `Lens` takes part in its equality and hash), so a changed lens always gets
    fresh data.

    Parameters
    ----------
    lens : Lens
        The lens.
    wavelength_nm : float, optional
        The wavelength (nm); default: the lens's primary wavelength.
    fields_deg : list of float, optional
        y field angles (degrees) of the chief rays; default: 0 and the lens's field.

    Returns
    -------
    Paraxial
        EFL, back focal distance, paraxial focus and image offset, entrance and exit pupils, f-numbers and
        the chief rays' image heights (mm unless named otherwise).

    Raises
    ------
    SolasError
        For a lens that is not a `Lens`, a wavelength a glass does not take, fields that are not finite
        angles below 180°, or a lens that forms no image.

    Examples
    --------
    >>> from solas_mi import Lens, paraxial
    >>> data = paraxial(Lens.load("solas-doublet"), 531.0)
    >>> round(data.efl_mm, 4), round(data.f_number, 3), round(data.entrance_pupil_diameter_mm, 2)
    (99.9468, 7.991, 12.51)
    """
    check_lens(lens)
    wl = lens.check_wavelength(wavelength_nm if wavelength_nm is not None else lens.primary_wavelength)
    if fields_deg is not None:
        return _paraxial(lens, wl, _check_fields(fields_deg))
    return _memoised(lens, wl)


def _check_fields(fields_deg) -> list[float]:
    """y field angles (degrees) as floats, each finite and below 180° in magnitude."""
    try:
        fields = [float(f) for f in fields_deg if not isinstance(f, (bool, str))]
        ok = len(fields) == len(fields_deg) and all(abs(f) < 180.0 for f in fields)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise SolasError(
            f"fields {fields_deg!r} must be a list of y field angles in degrees, each finite and below 180 in magnitude"
        )
    return fields


@functools.lru_cache(maxsize=256)
def _memoised(lens: Lens, wavelength_nm: float) -> Paraxial:
    return _paraxial(lens, wavelength_nm)


def _paraxial(lens: Lens, wavelength_nm: float, fields_deg: list[float] | None = None) -> Paraxial:
    wavelength_nm = lens.check_wavelength(wavelength_nm)
    n = lens.indices(wavelength_nm)
    z = lens.vertex_z
    last = len(lens.surfaces) - 1

    # Two base rays at surface 1: a = (y=1, u=0), b = (y=0, u=1); every ray is a mix of them.
    ya, ua = ynu_trace(lens, wavelength_nm, 1.0, 0.0)
    yb, _ub = ynu_trace(lens, wavelength_nm, 0.0, 1.0)
    efl = -1.0 / (n[-1] * ua[-1]) if ua[-1] != 0 else math.inf  # 1/power: n'u' = −y1·power
    ep_z, ep_radius, xp_z, xp_radius, xp_f_number = _pupils(lens, wavelength_nm, ya, yb)
    ym, um, obj_z = _marginal_ray(lens, wavelength_nm, ya, ua)
    focus_z = z[last] - ym[last] / um[last]
    refracting = [k for k in range(last + 1) if n[k + 1] != n[k] or lens.surfaces[k].ideal]
    bfd = focus_z - z[refracting[-1] if refracting else last]
    image_z = lens.image_z
    fields = list(fields_deg) if fields_deg is not None else [0.0, lens.field_deg]
    heights = [_chief_height(lens, wavelength_nm, f, ep_z, obj_z) for f in fields]

    epd = 2.0 * ep_radius
    return Paraxial(
        wavelength_nm=wavelength_nm,
        efl_mm=float(efl),
        efl_image_space_mm=float(n[-1] * efl),
        bfd_mm=float(bfd),
        focus_z_mm=float(focus_z),
        image_z_mm=float(image_z),
        image_offset_mm=float(image_z - focus_z),
        entrance_pupil_z_mm=float(ep_z),
        entrance_pupil_diameter_mm=float(epd),
        exit_pupil_z_mm=float(xp_z),
        exit_pupil_diameter_mm=float(2.0 * xp_radius),
        f_number=float(efl / epd),
        working_f_number=float(1.0 / (2.0 * n[-1] * abs(um[last]))),
        exit_pupil_f_number=float(xp_f_number),
        fields_deg=tuple(float(f) for f in fields),
        chief_ray_image_height_mm=tuple(heights),
    )


def _pupils(
    lens: Lens, wavelength_nm: float, ya: np.ndarray, yb: np.ndarray
) -> tuple[float, float, float, float, float]:
    """Entrance pupil z and radius, exit pupil z and radius (mm), and the exit pupil's f-number from the
    image plane, (image z − exit pupil z) / exit pupil diameter, from the heights of the base rays
    a = (y=1, u=0) and b = (y=0, u=1) at surface 1. The f-number is written with the slope u_c of the
    chief ray leaving the last surface, sign(u_c)·(y_c + u_c·t)/(2|y_r u_c − u_r y_c|) (t: last surface
    to image, r the stop's rim ray; the denominator by the Lagrange invariant, exact), which stays finite where the exit pupil is at infinity (a lens
    telecentric in image space: −1/(2 u_r), where the ratio of its two infinities read NaN)."""
    z = lens.vertex_z
    s = lens.stop_index
    last = len(lens.surfaces) - 1
    r_stop = lens.surfaces[s].semi_diameter
    if ya[s] == 0:  # rays parallel to the axis all cross the stop's centre
        raise SolasError(
            f"lens {lens.name}: the stop (surface {s + 1}) lies in the rear focal plane of the surfaces "
            f"before it at {wavelength_nm:g} nm, so the entrance pupil is at infinity (telecentric in "
            "object space), which the ray aiming does not model; move the stop"
        )
    # Entrance pupil: the object-space chief ray (slope 1) crosses the axis where y_stop = 0.
    y1_chief = -yb[s] / ya[s]  # height at surface 1 of the slope-1 ray through the stop centre
    ep_z = z[0] - y1_chief  # y(z) = y1 + (z − z1) = 0
    ep_radius = r_stop / abs(ya[s])  # parallel rays: height at the pupil equals height at surface 1
    # Exit pupil: the image of the stop by the surfaces after it.
    if s == last:
        return ep_z, ep_radius, z[s], r_stop, (lens.image_z - z[s]) / (2.0 * r_stop)
    # chief ray leaves the stop centre with slope 1; rim ray leaves the stop edge with slope 0
    yc, uc = _from_stop(lens, wavelength_nm, 0.0, 1.0)
    yr, ur = _from_stop(lens, wavelength_nm, r_stop, 0.0)
    yc, uc, yr, ur = yc[last], uc[last], yr[last], ur[last]
    with np.errstate(divide="ignore"):  # an exit pupil at infinity (uc = 0): z and radius infinite, said so
        xp_z = z[last] - yc / uc if uc != 0 else -math.inf * np.sign(yc)
        xp_radius = abs(yr + ur * (xp_z - z[last])) if uc != 0 else math.inf
    n = lens.indices(wavelength_nm)  # n·(y_r u_c − u_r y_c) is the Lagrange invariant: n_stop·r_stop at the stop
    f_number = math.copysign(1.0, uc) * (yc + uc * (lens.image_z - z[last])) * n[last + 1] / (2.0 * r_stop * n[s + 1])
    return ep_z, ep_radius, xp_z, xp_radius, f_number


def _marginal_ray(
    lens: Lens, wavelength_nm: float, ya: np.ndarray, ua: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float]:
    """Heights and slopes of the marginal ray (from the axial object point through the stop edge), and
    the object's z (mm); SolasError when it leaves the lens parallel (no image)."""
    s = lens.stop_index
    r_stop = lens.surfaces[s].semi_diameter
    if lens.at_infinity:
        ym, um = ya * (r_stop / ya[s]), ua * (r_stop / ya[s])
        obj_z = -math.inf
    else:
        # ray from the axial object point with slope 1 → height at stop; scale to the stop edge
        y0, u0 = _object_ray(lens, wavelength_nm, 0.0, 1.0)
        if y0[s] == 0:  # the object's image lies on the stop: the object in the entrance pupil
            pupil_distance(lens, -lens.object_distance)
        scale = r_stop / y0[s]
        ym, um = y0 * scale, u0 * scale
        obj_z = -lens.object_distance
    if um[-1] == 0:
        raise SolasError(
            f"lens {lens.name} forms no image at {wavelength_nm:g} nm: rays from an object point leave "
            "it parallel (no optical power, or the object in the front focal plane)"
        )
    return ym, um, obj_z


def _chief_height(lens: Lens, wavelength_nm: float, field_deg: float, ep_z: float, obj_z: float) -> float:
    """Image-plane height (mm) of the paraxial chief ray of field `field_deg` (toward the entrance pupil
    centre at `ep_z`; from the object point at `obj_z` for a finite object)."""
    if abs(field_deg) >= 90.0:  # a polar field at or beyond 90°: its paraxial image lies at infinity
        return math.copysign(math.inf, field_deg)
    z = lens.vertex_z
    last = len(lens.surfaces) - 1
    slope = math.tan(math.radians(field_deg))
    if lens.at_infinity:
        y, u = ynu_trace(lens, wavelength_nm, slope * (z[0] - ep_z), slope)
    else:
        # chief ray: from the object point toward the entrance pupil centre
        y_obj = -slope * (ep_z - obj_z)
        y, u = _object_ray(lens, wavelength_nm, y_obj, slope)
    return float(y[last] + u[last] * (lens.image_z - z[last]))


def _from_stop(lens: Lens, wavelength_nm: float, y_stop: float, u_after: float) -> tuple[np.ndarray, np.ndarray]:
    """A ray leaving the stop at height `y_stop` with slope `u_after`, traced to the last surface."""
    s = lens.stop_index
    y, u = ynu_trace(lens, wavelength_nm, y_stop + u_after * lens.surfaces[s].thickness, u_after, start=s + 1)
    y[s], u[s] = y_stop, u_after
    return y, u
