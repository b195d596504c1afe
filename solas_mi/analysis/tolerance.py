"""A Monte Carlo of a lens's tolerances (`solas-mi tolerance`): samples drawn from a tolerance
file (`optics.tolerance`), each refocused by the back-focus compensator and measured: EFL and back focus
at the primary wavelength, the compensator's shift, and MTF50 against field, tangential and sagittal
(`mtf_field.mtf50_field`, the polychromatic diffraction MTF); the sensitivity of each tolerance alone at
±1 σ (normal) or ± its limit (uniform); percentiles and the yield against an MTF50 limit.

Compensators (`optics.tolerance.COMPENSATORS`): "rms-spot" moves the image plane to the least polychromatic
RMS spot on axis (`thermal.best_focus_mm`), "mtf50" from there to the highest MTF50 on axis (a golden-
section search over ± `MTF_FOCUS_SPAN` · 2 λ N², λ the primary wavelength, N the working f-number: a
few depths of focus), "none" leaves it (the lens as assembled on a fixed flange).

A spec with an as-built kind (decentre, tilt, sensor tilt: `optics.tolerance_placement.is_as_built`) draws lenses
that are no longer symmetric: then every lens of the run — the nominal, each sample and each sensitivity —
is measured by one method, `Settings.mtf` = "geometric" (`as_built.mtf50_across_field`: the geometric MTF
at the primary wavelength, no diffraction) at signed fields along y (−half … +half field), so that
percentiles and the yield compare like with like; a symmetric-only spec keeps the diffraction MTF at
0 … half field, its figures as before. The compensator focuses the drawn lens's symmetric part (its
decentres and tilts left out: the Dr.Jit tracer takes one axis), and the as-built lens is refocused by
that shift of its last thickness; EFL and back focus are of that symmetric part too.

Samples are independent: each is drawn from the seed and its index (`optics.tolerance.draw`) by whichever
process measures it, so `workers` (local processes) change the time only, never a number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from ..metrics.mtf import mtf50
from ..optics import tolerance as tol
from ..optics.paraxial import paraxial
from ..optics.tolerance_placement import AS_BUILT
from . import inputs
from .thermal import best_focus_mm, refocused

PERCENTILES = (5, 10, 50, 90, 95)
MTF_FOCUS_SPAN = 4.0  # the mtf50 compensator searches ± this many (2 λ N²) around the RMS-spot focus
MTF_FOCUS_STEPS = 14  # golden-section steps of that search (its span shrinks by 0.618 each)
MAX_SAMPLES = 100_000
MAX_SEED = 2**63 - 1


@dataclass(frozen=True)
class Settings:
    """How each lens is measured: the compensator, the field samples (0 … half field) and pupil samples
    (None: the MTF's default) of `mtf50_field`."""

    compensator: str = "rms-spot"
    field_samples: int = 5
    pupil_samples: int | None = None
    mtf: str = "diffraction"  # `MTF_METHODS`: "geometric" for a run with a lens as built (module docstring)


MTF_METHODS = ("diffraction", "geometric")


def _geometric_mtf50(lens, field_samples: int) -> tuple[tuple[float, ...], np.ndarray]:
    """(signed y fields, degrees; their MTF50 (fields, 2)) of `as_built.mtf50_across_field` at the primary
    wavelength over −half … +half field (2 · `field_samples` − 1 fields)."""
    from .as_built import mtf50_across_field

    fields = tuple(float(f) for f in np.linspace(-1.0, 1.0, 2 * field_samples - 1) * lens.field_deg)
    grid = np.array([[0.0, f] for f in fields])
    return fields, mtf50_across_field(lens, grid, lens.primary_wavelength)


def _axis_mtf50(lens, pupil_samples: int | None) -> float:
    """MTF50 (cycles/mm) on axis of the polychromatic diffraction MTF (the cut-off where it never falls to 1/2)."""
    from .mtf import lens_otf
    from .mtf_field import MTF50_SAMPLES

    wavelengths, weights = inputs.wavelengths(lens, None)
    freq = np.linspace(0.0, inputs.cutoff_cy_mm(lens, min(wavelengths)), MTF50_SAMPLES)
    otf, _ = lens_otf(lens, (0.0,), wavelengths, weights, freq, pupil_samples)
    found = mtf50(np.abs(otf[0, 0]), freq)
    return freq[-1] if found is None or math.isnan(found) else found


def _mtf_focus(lens, start_mm: float, pupil_samples: int | None) -> float:
    """The image-plane shift near `start_mm` of the highest MTF50 on axis (module docstring)."""
    first = paraxial(lens, lens.primary_wavelength)
    half = MTF_FOCUS_SPAN * 2.0 * lens.primary_wavelength * 1e-6 * first.working_f_number**2
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    lo, hi = start_mm - half, start_mm + half
    a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
    fa, fb = (_axis_mtf50(refocused(lens, x), pupil_samples) for x in (a, b))
    for _ in range(MTF_FOCUS_STEPS):
        if fa >= fb:
            hi, b, fb = b, a, fa
            a = hi - ratio * (hi - lo)
            fa = _axis_mtf50(refocused(lens, a), pupil_samples)
        else:
            lo, a, fa = a, b, fb
            b = lo + ratio * (hi - lo)
            fb = _axis_mtf50(refocused(lens, b), pupil_samples)
    return 0.5 * (lo + hi)


def evaluate(lens, settings: Settings, despace_mm: float = 0.0, on_axis=None) -> dict:
    """EFL, back focus (mm, primary wavelength), the compensator's shift (mm) and MTF50 (fields, 2) of `lens`
    assembled (`assembled`: refocused by that shift), with the MTF's warnings. `despace_mm`, the sensor's
    despace that `lens` holds, stays after a compensator: the sensor sits that far from the focus it found.
    `on_axis`: the lens the compensator focuses and the paraxial figures are of, where `lens` is as built
    (its symmetric part: `optics.tolerance.symmetric`); `lens` itself by default."""
    from .mtf_field import mtf50_field

    on_axis = lens if on_axis is None else on_axis
    first = paraxial(on_axis, on_axis.primary_wavelength)
    shift = 0.0
    if settings.compensator != "none":
        shift = best_focus_mm(on_axis)
    if settings.compensator == "mtf50":
        shift = _mtf_focus(on_axis, shift, settings.pupil_samples)
    shift += despace_mm if settings.compensator != "none" else 0.0
    assembled = refocused(lens, shift)
    if settings.mtf == "geometric":
        fields, values, warnings = *_geometric_mtf50(assembled, settings.field_samples), ()
    else:
        result = mtf50_field(assembled, field_samples=settings.field_samples, pupil_samples=settings.pupil_samples)
        fields, values, warnings = result.fields_deg, result.mtf50_cy_mm, result.warnings
    return {
        "efl_mm": first.efl_mm,
        "bfd_mm": first.bfd_mm,
        "focus_shift_mm": shift,
        "fields_deg": fields,
        "mtf50_cy_mm": values,
        "warnings": warnings,
        "assembled": assembled,
    }


def sample(lens, spec: tol.ToleranceSpec, seed: int, index: int, settings: Settings) -> dict:
    """Sample `index` of seed `seed`: its deltas, `evaluate`'s figures, and the lens as assembled (the drawn
    lens with the compensator's image plane), its hash."""
    drawn, deltas = tol.draw(lens, spec, seed, index)
    figures = evaluate(drawn, settings, tol.despace(spec, deltas), tol.symmetric(lens, spec, deltas))
    return {
        "index": index,
        "lens": figures["assembled"],
        "hash": figures["assembled"].hash,
        "deltas": deltas,
        **figures,
    }


def check_run(samples, seed, workers) -> None:
    """SolasError unless the counts are whole numbers in their ranges."""
    for value, what, least, most in (
        (samples, "samples", 1, MAX_SAMPLES),
        (seed, "seed", 0, MAX_SEED),
        (workers, "workers", 1, 1024),
    ):
        if not isinstance(value, int) or isinstance(value, bool) or not least <= value <= most:
            raise SolasError(f"{what} {value!r} must be a whole number from {least} to {most}")


def monte_carlo(lens, spec, samples: int, seed: int, settings: Settings, workers: int = 1, progress=None):
    """Samples 0 … `samples` − 1 (`sample`), in index order, measured by `workers` local processes (1: this
    one); `progress(done, total)` as they finish."""
    check_run(samples, seed, workers)
    rows: dict[int, dict] = {}
    if workers == 1:
        for i in range(samples):
            rows[i] = sample(lens, spec, seed, i, settings)
            if progress:
                progress(len(rows), samples)
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor, as_completed

        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            futures = [pool.submit(sample, lens, spec, seed, i, settings) for i in range(samples)]
            for future in as_completed(futures):
                row = future.result()
                rows[row["index"]] = row
                if progress:
                    progress(len(rows), samples)
    return [rows[i] for i in range(samples)]


def sensitivity(lens, spec: tol.ToleranceSpec, settings: Settings, progress=None) -> list[dict]:
    """Each term of `spec` alone at −1 and +1 σ (or ± its limit): `optics.tolerance.paraxial_sensitivity`'s
    parameter, EFL and dEFL/dparameter, and the compensator's shift and the worst MTF50 (over fields and
    orientations) at both."""
    rows = tol.paraxial_sensitivity(lens, spec)
    for k, row in enumerate(rows):
        for sign, side in tol.SIDES:
            moved, term = tol.alone(lens, spec, k, sign), spec.terms[k]
            despace = sign * term.value if term.kind == "despace" else 0.0
            figures = evaluate(moved, settings, despace, lens if term.kind in AS_BUILT else moved)
            row[f"focus_shift_mm_{side}"] = figures["focus_shift_mm"]
            row[f"worst_mtf50_cy_mm_{side}"] = worst(figures["mtf50_cy_mm"])
        if progress:
            progress(k + 1, len(rows))
    return rows


def worst(mtf50_cy_mm) -> float:
    """The lowest MTF50 over fields and orientations (a field whose MTF never falls to 1/2: none lower)."""
    values = np.asarray(mtf50_cy_mm, dtype=float)
    return float(np.nanmin(values)) if np.any(np.isfinite(values)) else math.inf


def percentiles(rows: list[dict]) -> dict:
    """{percentile: (fields, 2) MTF50} over the samples (NaN-free where a field's MTF never falls to 1/2)."""
    stack = np.array([r["mtf50_cy_mm"] for r in rows], dtype=float)
    return {p: np.nanpercentile(stack, p, axis=0) for p in PERCENTILES}


def check_limit(limit_cy_mm) -> float:
    """An MTF50 limit (cycles/mm), or SolasError naming it."""
    if not isinstance(limit_cy_mm, (int, float)) or not math.isfinite(limit_cy_mm) or limit_cy_mm <= 0:
        raise SolasError(f"MTF50 limit {limit_cy_mm!r} must be a positive number (cycles/mm)")
    return float(limit_cy_mm)


def yield_fraction(rows: list[dict], limit_cy_mm: float) -> tuple[float, float]:
    """(fraction of samples whose worst MTF50 reaches `limit_cy_mm`, its binomial standard error)."""
    check_limit(limit_cy_mm)
    p = sum(worst(r["mtf50_cy_mm"]) >= limit_cy_mm for r in rows) / len(rows)
    return p, math.sqrt(p * (1.0 - p) / len(rows))


__all__ = [
    "MTF_METHODS",
    "PERCENTILES",
    "Settings",
    "check_limit",
    "check_run",
    "evaluate",
    "monte_carlo",
    "percentiles",
    "sample",
    "sensitivity",
    "worst",
    "yield_fraction",
]
