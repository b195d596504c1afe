"""What a lens file leaves to its optical program to compute, computed as Zemax does: the stop's size
from the system aperture, the field angle of object-height and image-height fields, and automatic
clear semi-diameters. Used by the readers of other programs' files (`zemax`, `codev`).

`solve(spec, aperture, fields, primary_nm, where)` takes a lens-file dictionary whose surfaces may hold
`"diameter": None` (automatic), the aperture as (kind, value) — ("float", 0) keeps the stop's own
diameter, ("epd", mm), ("fnum", image-space F/# = EFL / EPD at the primary wavelength), ("working fnum", the paraxial working
F/# 1 / (2 n' u') of the marginal ray from the axial object point), ("na",
object-space n sin u of the paraxial marginal ray, finite objects) — and the fields as (kind, radial
sizes) with kind "angle" (degrees), "object height", "paraxial image height" or "real image height"
(mm). It returns the dictionary with every diameter set and field_deg the widest field as an angle.
Automatic semi-diameters: the largest height at each surface of the real chief ray and the rays aimed
at the stop's rim of every field and wavelength, so no aperture but the stop's cuts the beam; where the
file gives vignetting factors, at the rim squeezed by them (CODE V's VUY/VLY/VUX/VLX, taken at the stop).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import SolasError
from .formats import floats
from .lens import Lens
from .paraxial import paraxial, pupil_distance

_OPEN = 0.999  # a provisional automatic aperture: this fraction of the sphere's radius
_FLAT_OPEN_MM = 1e4  # … or this, for flat and aspheric surfaces
_SECANT_STEPS = 40  # real-image-height fields: secant steps on the field angle


def default_stop(rows: list[dict], keyword: str, whose: str) -> str:
    """Where no row of `rows` (the surfaces between object and image) is the stop, make surface 1 the stop,
    as the program's new lens has it, and say so (the note for the description); "" where one is."""
    if any(r.get("stop") for r in rows):
        return ""
    rows[0]["stop"] = True
    return f"no {keyword} in the file: the stop is surface 1, {whose}"


def solve(
    spec: dict,
    aperture: tuple[str, float],
    fields: tuple[str, list[float]],
    primary_nm: float | None,
    where: str,
    vignetting: list[tuple[float, float, float, float]] | None = None,
) -> dict:
    """`spec` solved (module docstring); `vignetting`: per field of `fields`, the fractions (+x, −x, +y, −y)
    of the pupil that the file's vignetting factors cut off, which the automatic semi-diameters then follow."""
    rows = spec["surface"]
    auto = [i for i, r in enumerate(rows) if r["diameter"] is None]
    stop = next((i for i, r in enumerate(rows) if r.get("stop")), None)
    if aperture[0] == "float" and stop is not None and rows[stop]["diameter"] is None:
        raise SolasError(
            f"{where}: the system aperture floats by stop size (FLOA, or no aperture named) on the "
            f"stop, surface {stop + 1} "
            f"({rows[stop].get('label', '')}), which has no DIAM: the beam's size is then "
            "undefined; give the stop's DIAM or a system aperture (ENPD, FNUM)"
        )
    if not auto and aperture[0] == "float" and fields[0] == "angle":
        spec["field_deg"] = max(fields[1], default=0.0)
        return spec
    provisional = {**spec, "surface": [{**r, "diameter": r["diameter"] or 1e-6} for r in rows]}
    lens = Lens.from_dict(provisional, source=where) if stop is not None else None
    if lens is None:
        return spec  # from_dict names the missing stop
    lens = _opened(lens, auto)
    wl = primary_nm or lens.primary_wavelength
    lens = _stop_sized(lens, aperture, wl, where)
    field_deg = _angles(lens, fields, wl, where)
    lens = replace(lens, field_deg=max(field_deg, default=0.0))
    cuts = dict(zip(field_deg, vignetting or []))
    semi = _automatic(lens, auto, field_deg, where, cuts) if auto else {}
    for i, r in enumerate(rows):
        r["diameter"] = 2.0 * semi[i] if i in semi and i != stop else lens.surfaces[i].diameter  # the stop: as sized
    spec["field_deg"] = lens.field_deg
    return spec


def _opened(lens: Lens, auto: list[int]) -> Lens:
    """`lens` with its automatic apertures open wide (nothing clips there while they are found)."""

    def wide(s):
        return _OPEN * 2.0 * abs(s.radius) if s.radius and s.is_sphere else 2.0 * _FLAT_OPEN_MM

    return replace(
        lens, surfaces=tuple(replace(s, diameter=wide(s)) if i in auto else s for i, s in enumerate(lens.surfaces))
    )


def _stop_sized(lens: Lens, aperture: tuple[str, float], wl: float, where: str) -> Lens:
    """`lens` with its stop sized so that the paraxial entrance pupil is what the system aperture says
    (the pupil scales with the stop)."""
    kind, value = aperture
    if kind == "float":
        return lens
    p = paraxial(lens, wl)
    if kind == "epd":
        epd = value
    elif kind == "fnum":
        epd = abs(p.efl_mm) / value
    elif kind == "working fnum":  # 1 / (2 n' u') of the paraxial marginal ray, u' in proportion to the pupil
        epd = p.entrance_pupil_diameter_mm * p.working_f_number / value
    else:
        if lens.at_infinity:
            raise SolasError(f"{where}: an object-space NA needs a finite object; the object is at infinity")
        n0 = float(lens.object_glass.index(wl))
        if not value < n0:
            raise SolasError(f"{where}: object-space NA {value:g} must be below the object space's index {n0:g}")
        epd = 2.0 * math.tan(math.asin(value / n0)) * abs(pupil_distance(lens, p.entrance_pupil_z_mm))  # virtual too
    k = lens.stop_index
    stop = lens.surfaces[k]
    scaled = replace(stop, diameter=stop.diameter * epd / p.entrance_pupil_diameter_mm)
    return replace(lens, surfaces=lens.surfaces[:k] + (scaled,) + lens.surfaces[k + 1 :])


def _angles(lens: Lens, fields: tuple[str, list[float]], wl: float, where: str) -> list[float]:
    """Each field as the angle (degrees) of its chief ray toward the entrance pupil."""
    kind, sizes = fields
    if kind == "angle" or not sizes:
        return list(sizes)
    p = paraxial(lens, wl, [45.0])
    if kind == "object height":
        if lens.at_infinity:
            raise SolasError(f"{where}: object-height fields need a finite object; the object is at infinity")
        # the chief ray's slope between the object point and the entrance pupil, as a magnitude: a virtual
        # object (behind surface 1) lies beyond the pupil, where that distance is negative
        return [math.degrees(math.atan(h / abs(pupil_distance(lens, p.entrance_pupil_z_mm)))) for h in sizes]
    per_tan = p.chief_ray_image_height_mm[0]  # the paraxial image height is linear in the field's tangent
    guess = [math.degrees(math.atan(h / abs(per_tan))) for h in sizes]
    return guess if kind == "paraxial image height" else _real_heights(lens, sizes, guess, wl, where)


def _real_heights(lens: Lens, heights: list[float], guess: list[float], wl: float, where: str) -> list[float]:
    """Field angles whose real chief rays land at `heights` (mm): the secant method from the paraxial
    guess, all fields at once."""
    from .pupil import chief_rays

    want = np.asarray(heights, dtype=np.float64)
    top = lens.field_type.largest_deg

    def height(theta: np.ndarray) -> np.ndarray:
        fields = np.stack([np.zeros(len(theta)), np.clip(theta, 0.0, top)], axis=-1)
        return np.abs(chief_rays(lens, fields, np.full(len(theta), wl)).image_xy[:, 1])

    a = np.asarray(guess, dtype=np.float64)
    b = np.where(a > 0, a * 0.99, 0.0)
    fa, fb = height(a) - want, height(b) - want
    for _ in range(_SECANT_STEPS):
        slope = np.where(a != b, (fa - fb) / np.where(a != b, a - b, 1.0), 1.0)
        step = np.where((slope != 0) & (want > 0), fa / np.where(slope != 0, slope, 1.0), 0.0)
        b, fb = a, fa
        a = np.clip(a - step, 0.0, top)
        fa = height(a) - want
        if np.all(np.abs(fa) <= 1e-12 * np.maximum(want, 1.0)):
            return a.tolist()
    bad = int(np.argmax(np.abs(fa)))
    raise SolasError(
        f"{where}: no field's real chief ray lands at image height {want[bad]:g} mm "
        f"(closest {fa[bad] + want[bad]:g} mm at {a[bad]:g} deg)"
    )


def _automatic(
    lens: Lens,
    auto: list[int],
    field_deg: list[float],
    where: str,
    cuts: dict[float, tuple[float, float, float, float]],
) -> dict[int, float]:
    """Semi-diameters (mm) of the `auto` surfaces: the largest height there of the real chief and stop-rim
    rays of every field (on the y axis: the lens is rotationally symmetric) and wavelength; the rim of a
    field in `cuts` squeezed by its vignetting factors."""
    from . import tracer
    from .pupil import RIM_RAYS, Bundle, chief_rays, stop_rim

    thetas = sorted(set(field_deg) | {0.0})
    fields = np.array([[0.0, t] for t in thetas for _ in lens.wavelengths_nm])
    waves = np.array([w for _ in thetas for w in lens.wavelengths_nm])
    chief = chief_rays(lens, fields, waves)
    rim = Bundle(lens, fields, waves, RIM_RAYS)
    ex, ey, _, ok = stop_rim(
        rim, chief, vignetting=[cuts.get(t, (0.0,) * 4) for t in thetas for _ in lens.wavelengths_nm] if cuts else None
    )
    reach = np.zeros(len(lens.surfaces))
    for e, b, passed in (
        (chief.entrance, Bundle(lens, fields, waves, 1), np.ones(len(fields), bool)),
        (np.stack([ex.ravel(), ey.ravel()], axis=-1), rim, ok.ravel()),
    ):
        heights: list = []
        tr = b.trace(tracer.F(e[:, 0]), tracer.F(e[:, 1]), heights=heights)
        good, *r2 = tracer.to_numpy(tr.ok, *heights)
        good &= passed
        if not good.any():
            raise SolasError(f"{where}: no real ray passes the lens; automatic semi-diameters cannot be found")
        reach = np.maximum(reach, [math.sqrt(float(np.max(h[good]))) for h in r2])
    return {i: float(reach[i]) for i in auto}


def vignetting_factors(top: dict, count: int, where: str) -> list[tuple[float, ...]] | None:
    """A .zmx file's vignetting (`zemax`): per field, the pupil's fractions (+x, −x, +y, −y) cut off by the
    VDXN/VCXN/VDYN/VCYN factors (the pupil coordinate p becomes VD + (1 − VC) p); None when all are 0."""
    dx, cx, dy, cy = (
        [*floats((top.get(k) or [[]])[0][:count], f"{where}: {k}"), *[0.0] * count][:count]
        for k in ("VDXN", "VCXN", "VDYN", "VCYN")
    )
    cuts = [(cx[i] - dx[i], cx[i] + dx[i], cy[i] - dy[i], cy[i] + dy[i]) for i in range(count)]
    if any(not -1.0 < c < 1.0 for cut in cuts for c in cut):
        raise SolasError(f"{where}: vignetting factors VDXN/VCXN/VDYN/VCYN leave no pupil at some field: {cuts}")
    return cuts if any(any(cut) for cut in cuts) else None
