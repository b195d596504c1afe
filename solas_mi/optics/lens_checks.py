"""The checks every lens passes when it is built from a lens file's table (`validate`, from `Lens.from_dict`):
values no lens may hold, each a SolasError naming the value, its surface and what is allowed."""

from __future__ import annotations

import math

from ..errors import SolasError
from . import overlap
from .formats import MAX_SURFACES, MAX_WAVELENGTHS, check_count

# The longest length a lens file may give (mm): an object beyond it is at infinity to every digit (its image
# lies f²/d ≈ 1e-11 mm from the focus of an f = 100 mm lens); a film 1e30 mm away rendered NaN, one at 1e300
# overflowed lens info's projection fits.
MAX_LENGTH_MM = 1e15
_VIRTUAL = (
    ": the image plane lies before the last surface, a virtual image (a diverging lens's focus) that no film records"
)


def check_size(surfaces, wavelengths, where: str) -> None:
    """SolasError unless there are at most `formats.MAX_SURFACES` surfaces and `MAX_WAVELENGTHS` wavelengths."""
    check_count(len(surfaces), "surfaces", MAX_SURFACES, where)
    check_count(len(wavelengths), "wavelengths", MAX_WAVELENGTHS, where)


def validate(lens, where: str) -> None:
    """SolasError naming the first of `lens`'s values a lens may not hold (`Lens.from_dict` checks every lens
    it builds): field, wavelengths, image diameter, one stop, object distance, each surface's sizes and shape."""
    if not 0 <= lens.field_deg < 180:
        raise SolasError(f"{where}: field_deg = {lens.field_deg:g} must be a half field angle in [0, 180) degrees")
    for w in lens.wavelengths_nm:
        if not w > 0:
            raise SolasError(f"{where}: wavelengths_nm holds {w:g}; wavelengths must be positive (nm)")
    if not 0 <= lens.image_diameter <= MAX_LENGTH_MM:
        raise SolasError(
            f"{where}: image diameter {lens.image_diameter:g} mm must be positive, at most "
            f"{MAX_LENGTH_MM:g} mm (or left out)"
        )
    stops = [i for i, s in enumerate(lens.surfaces) if s.stop]
    if not stops:
        raise SolasError(f"{where}: no surface is marked as the aperture stop (set stop = true on one)")
    if len(stops) > 1:
        raise SolasError(
            f"{where}: surfaces {', '.join(str(i + 1) for i in stops)} are all marked stop; exactly one may be"
        )
    if not abs(lens.object_distance) <= MAX_LENGTH_MM and math.isfinite(lens.object_distance):
        raise SolasError(
            f"{where}: object distance {lens.object_distance:g} mm must lie within ±{MAX_LENGTH_MM:g} "
            'mm, or be "infinity" (a farther object is at infinity to every digit)'
        )
    for i, s in enumerate(lens.surfaces, start=1):
        ident = f"{where}: surface {i} ({s.label})"
        if not 0 < s.diameter <= MAX_LENGTH_MM:
            raise SolasError(f"{ident}: diameter {s.diameter:g} mm must be positive and at most {MAX_LENGTH_MM:g} mm")
        if not abs(s.thickness) <= MAX_LENGTH_MM:
            raise SolasError(
                f"{ident}: thickness {s.thickness:g} mm must lie within ±{MAX_LENGTH_MM:g} mm, the "
                "longest length a lens file may give"
            )
        if s.radius != 0 and s.conic == 0 and s.semi_diameter >= abs(s.radius):
            raise SolasError(
                f"{ident}: clear semi-diameter {s.semi_diameter:g} mm is not smaller than |radius| "
                f"{abs(s.radius):g} mm; the sphere cannot hold that aperture"
            )
        if s.conic != 0 and (1.0 + s.conic) * (s.curvature * s.semi_diameter) ** 2 >= 1.0:
            raise SolasError(
                f"{ident}: conic {s.conic:g} with radius {s.radius:g} mm closes before the clear "
                f"semi-diameter {s.semi_diameter:g} mm; the conic cannot hold that aperture"
            )
        if s.form is not None:
            s.form.check_aperture(s.semi_diameter, ident)
    lens.field_type.check_lens(lens, where)
    last = lens.surfaces[-1]
    if last.thickness < 0:
        raise SolasError(
            f"{where}: surface {len(lens.surfaces)} ({last.label}): distance to the image "
            f"{last.thickness:g} mm must be positive" + _VIRTUAL + "; 0 mm puts it on the last surface"
        )
    overlap.notes(lens, where)


def features(lens) -> list[tuple[str, bool]]:
    """(feature, whether `lens` uses it) of what a lens file format may not hold (`Lens.save`)."""
    surfaces = lens.surfaces
    return [
        ("coatings", any(s.coating for s in surfaces)),
        ("blades", any(s.blades for s in surfaces)),
        ("surfaces without rotational symmetry", any(s.form for s in surfaces)),
        ("coordinate breaks", any(s.placement for s in surfaces) or lens.image_placement is not None),
    ]


def as_built(lens) -> bool:
    """Whether `lens` has a surface without rotational symmetry or behind a coordinate break, or a placed
    sensor: a lens as built, which the tracers in local frames trace (`local_trace` in NumPy, `tracer_local` in
    Dr.Jit)."""
    return any(s.form is not None or s.placement is not None for s in lens.surfaces) or lens.image_placement is not None


def refuse_as_built(lens, engine: str) -> None:
    """SolasError naming `lens`'s first surface that is not rotationally symmetric or sits behind a coordinate
    break, which `engine` (named in the message) does not trace: the tracers in local frames do."""
    for i, s in enumerate(lens.surfaces, start=1):
        if s.form is not None or s.placement is not None:
            what = f"a {s.form.kind}" if s.form is not None else "decentred or tilted (a coordinate break before it)"
            raise SolasError(
                f"lens {lens.name}: surface {i} ({s.label}) is {what}, which {engine} does not take yet "
                "(only rotationally symmetric surfaces on one axis); the NumPy tracer optics.local_trace traces it"
            )
    if lens.image_placement is not None:
        raise SolasError(
            f"lens {lens.name}: its image plane (the sensor) is decentred or tilted, which {engine} does not take "
            "yet; the NumPy tracer optics.local_trace traces it"
        )
