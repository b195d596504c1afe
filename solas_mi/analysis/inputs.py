"""The inputs of the lens analyses, checked before any work: fields within the lens's half field,
wavelengths its glasses accept, weights, frequencies up to the diffraction cut-off, focus ranges,
sample counts. Each bad value is a SolasError naming it and what is allowed."""

from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import SolasError
from ..metrics.mtf import pixel_mtf
from ..optics.lens import check_lens
from ..optics.paraxial import paraxial
from ..psf.base import check_wavelengths
from ..psf.methods import _weights
from . import options as O


def _number(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def fields(lens, fields_deg) -> tuple[float, ...]:
    """y field angles (degrees) within ± the lens's half field; default: `options.FIELD_FRACTIONS` of it."""
    check_lens(lens)
    half = lens.field_deg
    if fields_deg is None:
        if half <= 0:
            raise SolasError(f"lens {lens.name} states no field (field_deg = 0); give the field angles (--fields)")
        return tuple(f * half for f in O.FIELD_FRACTIONS)
    values = list(np.ravel(fields_deg)) if not isinstance(fields_deg, (list, tuple)) else list(fields_deg)
    if not values or not all(_number(v) for v in values):
        raise SolasError(f"fields {fields_deg!r} must be one or more field angles in degrees")
    for v in values:
        if half > 0 and abs(v) > half * (1 + 1e-12):
            raise SolasError(
                f"field {v:g} deg is beyond lens {lens.name}'s half field {half:g} deg (field_deg of "
                f"its lens file); allowed: -{half:g} to {half:g} deg"
            )
        lens.field_type.check((0.0, float(v)))
    return tuple(float(v) for v in values)


def field_range(lens, samples) -> tuple[float, ...]:
    """`samples` field angles from 0 to the lens's half field (degrees), evenly spaced."""
    check_lens(lens)
    samples = count(samples, "field samples", 2)
    if lens.field_deg <= 0:
        raise SolasError(
            f"lens {lens.name} states no field (field_deg = 0): an analysis against field needs its half field"
        )
    return tuple(np.linspace(0.0, lens.field_deg, samples).tolist())


def count(value, what: str, least: int, most: int = 4096) -> int:
    """A whole number from `least` to `most`."""
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or not least <= value <= most:
        raise SolasError(f"{what} {value!r} must be a whole number from {least} to {most}")
    return int(value)


def pupil_samples(value) -> int | None:
    """Pupil samples a side, 16 to options.MOST_PUPIL_SAMPLES; None (the default) stays None: the MTF then
    takes options.PUPIL_SAMPLES, more where the wavefront needs them."""
    return None if value is None else count(value, "pupil samples", 16, O.MOST_PUPIL_SAMPLES)


def wavelengths(lens, wavelengths_nm, weights=None) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Wavelengths (nm; default the lens file's) and their weights summing to 1 (default equal)."""
    check_lens(lens)
    wl = check_wavelengths(lens, lens.wavelengths_nm if wavelengths_nm is None else wavelengths_nm)
    return wl, tuple(_weights(weights, len(wl)).tolist())


def wavelength(lens, wavelength_nm) -> float:
    """One wavelength (nm; default the lens's primary)."""
    check_lens(lens)
    return lens.check_wavelength(lens.primary_wavelength if wavelength_nm is None else wavelength_nm)


def cutoff_cy_mm(lens, wavelength_nm: float) -> float:
    """The paraxial diffraction cut-off 1/(λ N) in cycles/mm, N the working f-number 1/(2 n' u')."""
    return 1.0 / (wavelength_nm * 1e-6 * paraxial(lens, wavelength_nm).working_f_number)


def frequencies(lens, values, wavelengths_nm, what: str = "frequency") -> tuple[float, ...]:
    """Spatial frequencies (cycles/mm) in (0, cut-off at the shortest of `wavelengths_nm`]; default
    `options.FREQUENCY_FRACTIONS` of the cut-off at the primary wavelength, whole cycles/mm."""
    top = cutoff_cy_mm(lens, min(wavelengths_nm))
    if values is None:
        base = cutoff_cy_mm(lens, wavelength(lens, None))
        return tuple(float(max(1, round(f * base))) for f in O.FREQUENCY_FRACTIONS)
    values = [values] if _number(values) else list(values)
    for v in values:
        if not _number(v) or not 0 < v <= top:
            raise SolasError(
                f"{what} {v!r} cycles/mm must be above 0 and at most the diffraction cut-off "
                f"{top:.4g} cycles/mm (1/(lambda N) at {min(wavelengths_nm):g} nm)"
            )
    if not values:
        raise SolasError(f"at least one {what} (cycles/mm) is needed")
    return tuple(float(v) for v in values)


def max_frequency(lens, value, wavelengths_nm) -> float:
    """The largest frequency of MTF curves: at most the cut-off at the shortest wavelength (default it)."""
    if value is None:
        return cutoff_cy_mm(lens, min(wavelengths_nm))
    return frequencies(lens, [value], wavelengths_nm, "largest frequency")[0]


def focus_range(lens, range_um) -> float:
    """Half range (µm) of a through-focus scan: positive; default `options.FOCUS_DEPTHS` λN²."""
    if range_um is None:
        w = wavelength(lens, None)
        return O.FOCUS_DEPTHS * w * 1e-3 * paraxial(lens, w).working_f_number ** 2
    if not _number(range_um) or range_um <= 0:
        raise SolasError(
            f"focus range {range_um!r} um must be a positive number: the image plane moves from "
            "-R to +R about its place"
        )
    return float(range_um)


def pixel(pitch_um, fill_factor) -> tuple[float | None, float]:
    """The pixel pitch (µm, None: no pixel) and fill factor (0, 1], checked by `metrics.mtf.pixel_mtf`."""
    if pitch_um is None:
        if fill_factor != 1.0:
            raise SolasError(
                f"fill factor {fill_factor!r} needs a pixel pitch (--pixel-pitch-um): without one "
                "the MTF is the lens's alone"
            )
        return None, 1.0
    pixel_mtf(np.zeros(1), pitch_um, fill_factor)
    return float(pitch_um), float(fill_factor)


def choice(value, choices: tuple[str, ...], what: str) -> str:
    """`value`, one of `choices`."""
    if value not in choices:
        raise SolasError(f"{what} {value!r} must be one of {', '.join(choices)}")
    return value
