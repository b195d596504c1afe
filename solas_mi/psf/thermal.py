"""A lens over a temperature range (`solas-mi thermal`): at each temperature (`Lens.at`, the lens, its
mount and the air there) its EFL and back focus at the primary wavelength, where its best focus lies
against the image plane (which the mount carries), and its MTF50 on axis, at 0.7 of the field and at the
edge, tangential and sagittal, as it stands and refocused (the image plane moved to that best focus).

Best focus: the image-plane shift that minimises the polychromatic RMS spot radius on axis (the lens's
wavelengths, equal weights): rays are straight behind the lens, so each ray's height is linear in the
shift, h(δ) = h₀ + t δ, and the least-squares shift is δ = −Σ h₀·t / Σ t·t (t from the spots at two
planes). MTF50: the first frequency (cycles/mm) where the modulation of the polychromatic Fraunhofer
PSF's line spread function along y (tangential, for fields on the y axis) or x (sagittal) falls to 0.5.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import SolasError
from ..optics import thermal as optics_thermal
from ..optics.paraxial import paraxial

FIELD_FRACTIONS = (0.0, 0.7, 1.0)  # of the lens's half field: the axis, 0.7, the edge
ORIENTATIONS = {"tangential": 1, "sagittal": 0}  # the PSF's axis (0: rows, along y; 1: columns) summed away
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
        raise SolasError(f"temperatures --from {start_c:g} --to {stop_c:g} --step-c {step_c:g}: give --to >= --from "
                         f"and a positive step, at most {MAX_TEMPERATURES} temperatures")
    values = [start_c + i * step_c for i in range(count)]
    return values + ([stop_c] if stop_c - values[-1] > 1e-9 else [])


def auto_pitch_um(lens) -> float:
    """A PSF pitch (µm) that samples the diffraction limit: a quarter of λ_min·F/# (EFL / EPD)."""
    first = paraxial(lens, lens.primary_wavelength)
    return 0.25 * min(lens.wavelengths_nm) / 1000.0 * abs(first.f_number)


def best_focus_mm(lens) -> float:
    """The shift (mm, + away from the lens) of the image plane to the least polychromatic RMS spot on axis."""
    from ..optics.spot import spot  # loads Dr.Jit

    probe = replace(lens, surfaces=lens.surfaces[:-1] + (
        replace(lens.surfaces[-1], thickness=lens.surfaces[-1].thickness + PROBE_MM),))
    num = den = 0.0
    for w in lens.wavelengths_nm:
        near, far = spot(lens, (0.0, 0.0), w, density=SPOT_RINGS), spot(probe, (0.0, 0.0), w, density=SPOT_RINGS)
        tx, ty = (far.x_um - near.x_um) / PROBE_MM, (far.y_um - near.y_um) / PROBE_MM
        num += float(np.sum(near.x_um * tx + near.y_um * ty))
        den += float(np.sum(tx * tx + ty * ty))
    return -num / den


def mtf50_cy_mm(data: np.ndarray, pitch_um: float, orientation: str) -> float | None:
    """MTF50 (cycles/mm) of a PSF along `orientation` (`ORIENTATIONS`); None where it never falls to 0.5."""
    lsf = np.asarray(data, dtype=np.float64).sum(axis=ORIENTATIONS[orientation])
    x_mm = (np.arange(lsf.size) - lsf.size // 2) * pitch_um / 1000.0
    freq = np.linspace(0.0, 500.0 / pitch_um, 2001)  # to the PSF sampling's Nyquist frequency
    mtf = np.abs(np.exp(-2j * np.pi * freq[:, None] * x_mm[None, :]) @ lsf) / lsf.sum()
    below = np.flatnonzero(mtf < 0.5)
    if below.size == 0:
        return None
    i = int(below[0])
    return float(freq[i - 1] + (mtf[i - 1] - 0.5) * (freq[i] - freq[i - 1]) / (mtf[i - 1] - mtf[i])) if i else 0.0


def _mtf50s(lens, pitch_um: float, size: int) -> dict:
    """{field fraction: {orientation: MTF50}} of `lens`'s polychromatic PSFs (equal weights)."""
    from .methods import psf  # loads Dr.Jit

    out = {}
    for fraction in FIELD_FRACTIONS:
        result = psf(lens, (0.0, fraction * lens.field_deg), list(lens.wavelengths_nm), pitch_um=pitch_um, size=size,
                     auto_window=True)
        out[fraction] = {o: mtf50_cy_mm(result.data, result.pitch_um, o) for o in ORIENTATIONS}
    return out


def at_temperature(lens, temperature_c: float, pressure_kpa: float, mount, pitch_um: float, size: int) -> dict:
    """One row of the sweep: the lens at `temperature_c` (`Lens.at`) and its figures (module docstring)."""
    there = lens.at(temperature_c, pressure_kpa, mount)
    first = paraxial(there, there.primary_wavelength)
    shift = best_focus_mm(there)
    last = there.surfaces[-1]
    refocused = replace(there, surfaces=there.surfaces[:-1] + (replace(last, thickness=last.thickness + shift),))
    return {"temperature_c": temperature_c, "efl_mm": first.efl_mm, "bfd_mm": first.bfd_mm,
            "best_focus_mm": shift, "hash": there.hash,
            "mtf50_cy_mm": {FOCUS[0]: _mtf50s(there, pitch_um, size), FOCUS[1]: _mtf50s(refocused, pitch_um, size)}}


def sweep(lens, temperatures_c, pressure_kpa: float, mount, pitch_um: float, size: int, progress=None) -> list[dict]:
    """`at_temperature` at each of `temperatures_c`; `progress(done, total)` after each."""
    rows = []
    for i, t in enumerate(temperatures_c):
        rows.append(at_temperature(lens, t, pressure_kpa, mount, pitch_um, size))
        if progress:
            progress(i + 1, len(temperatures_c))
    return rows


__all__ = ["auto_pitch_um", "best_focus_mm", "mtf50_cy_mm", "sweep", "temperatures"]
