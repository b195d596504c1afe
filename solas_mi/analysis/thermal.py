"""A lens over a temperature range (`solas-mi thermal`): at each temperature (`Lens.at`, the lens, its
mount and the air there) its EFL and back focus at the primary wavelength, where its best focus lies
against the image plane (which the mount carries), and its MTF50 on axis, at 0.7 of the field and at the
edge, tangential and sagittal, as it stands and refocused (the image plane moved to that best focus).

Best focus: the image-plane shift that minimises the polychromatic RMS spot radius on axis (the lens's
wavelengths, equal weights): rays are straight behind the lens, so each ray's height is linear in the
shift, h(δ) = h₀ + t δ, and the least-squares shift is δ = −Σ h₀·t / Σ t·t (t from the spots at two
planes). MTF50: the first frequency (cycles/mm) where the polychromatic diffraction MTF (`mtf.lens_otf`,
the pupil function's autocorrelation) falls to 0.5 (`metrics.mtf.mtf50`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import SolasError
from ..metrics.mtf import mtf50
from ..optics import thermal as optics_thermal
from ..optics.paraxial import paraxial
from . import inputs

FIELD_FRACTIONS = (0.0, 0.7, 1.0)  # of the lens's half field: the axis, 0.7, the edge
FOCUS = ("as built", "refocused")
SPOT_RINGS = 12  # rings of the hexapolar spots that find best focus
PROBE_MM = 0.01  # the second plane of those spots, this far behind the image plane
MAX_TEMPERATURES = 200


def temperatures(start_c: float, stop_c: float, step_c: float) -> list[float]:
    """From `start_c` to `stop_c` (both included) by `step_c` (°C); SolasError for an empty or endless range."""
    optics_thermal.check_environment(start_c, optics_thermal.STANDARD_KPA)
    optics_thermal.check_environment(stop_c, optics_thermal.STANDARD_KPA)
    count = math.floor((stop_c - start_c) / step_c + 1e-9) + 1 if math.isfinite(step_c) and step_c > 0 else 0
    if stop_c < start_c or not 1 <= count <= MAX_TEMPERATURES:
        raise SolasError(
            f"temperatures --from {start_c:g} --to {stop_c:g} --step-c {step_c:g}: give --to >= --from "
            f"and a positive step, at most {MAX_TEMPERATURES} temperatures"
        )
    values = [start_c + i * step_c for i in range(count)]
    return values + ([stop_c] if stop_c - values[-1] > 1e-9 else [])


def best_focus_mm(lens) -> float:
    """The shift (mm, + away from the lens) of the image plane to the least polychromatic RMS spot on axis."""
    from ..optics.spot import spot  # loads Dr.Jit

    probe = refocused(lens, PROBE_MM)
    num = den = 0.0
    for w in lens.wavelengths_nm:
        near, far = spot(lens, (0.0, 0.0), w, density=SPOT_RINGS), spot(probe, (0.0, 0.0), w, density=SPOT_RINGS)
        tx, ty = (far.x_um - near.x_um) / PROBE_MM, (far.y_um - near.y_um) / PROBE_MM
        num += float(np.sum(near.x_um * tx + near.y_um * ty))
        den += float(np.sum(tx * tx + ty * ty))
    return -num / den


def refocused(lens, shift_mm: float):
    """`lens` with its image plane moved `shift_mm` (+ away from the lens)."""
    last = lens.surfaces[-1]
    return replace(lens, surfaces=lens.surfaces[:-1] + (replace(last, thickness=last.thickness + shift_mm),))


def _mtf50s(lens, pupil_samples: int | None) -> tuple[dict, list[str]]:
    """{field fraction: {direction: MTF50 (cycles/mm), None where it never falls to 1/2}} of `lens`'s
    polychromatic diffraction MTF (its wavelengths, equal weights), and its warnings (`mtf.lens_otf`)."""
    from .mtf import DIRECTIONS, lens_otf  # loads Dr.Jit
    from .mtf_field import MTF50_SAMPLES

    wavelengths, weights = inputs.wavelengths(lens, None)
    freq = np.linspace(0.0, inputs.cutoff_cy_mm(lens, min(wavelengths)), MTF50_SAMPLES)
    otf, warnings = lens_otf(
        lens, tuple(f * lens.field_deg for f in FIELD_FRACTIONS), wavelengths, weights, freq, pupil_samples
    )
    return {
        fraction: {d: mtf50(np.abs(otf[i, j]), freq) for j, d in enumerate(DIRECTIONS)}
        for i, fraction in enumerate(FIELD_FRACTIONS)
    }, warnings


def at_temperature(lens, temperature_c: float, pressure_kpa: float, mount, pupil_samples: int | None = None) -> dict:
    """One row of the sweep: the lens at `temperature_c` (`Lens.at`) and its figures (module docstring), with
    the MTF's warnings (a pupil grid too coarse for its wavefront)."""
    there = lens.at(temperature_c, pressure_kpa, mount)
    first = paraxial(there, there.primary_wavelength)
    shift = best_focus_mm(there)
    row = {
        "temperature_c": temperature_c,
        "efl_mm": first.efl_mm,
        "bfd_mm": first.bfd_mm,
        "best_focus_mm": shift,
        "hash": there.hash,
        "mtf50_cy_mm": {},
        "warnings": [],
    }
    for state, one in zip(FOCUS, (there, refocused(there, shift))):
        row["mtf50_cy_mm"][state], warnings = _mtf50s(one, pupil_samples)
        row["warnings"] += [w for w in warnings if w not in row["warnings"]]
    return row


def sweep(
    lens, temperatures_c, pressure_kpa: float, mount, pupil_samples: int | None = None, progress=None
) -> list[dict]:
    """`at_temperature` at each of `temperatures_c`; `progress(done, total)` after each."""
    rows = []
    for i, t in enumerate(temperatures_c):
        rows.append(at_temperature(lens, t, pressure_kpa, mount, pupil_samples))
        if progress:
            progress(i + 1, len(temperatures_c))
    return rows


__all__ = ["at_temperature", "best_focus_mm", "refocused", "sweep", "temperatures"]
