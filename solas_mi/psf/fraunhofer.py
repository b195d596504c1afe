"""Fraunhofer PSFs: |matrix DFT of the pupil function|² on an image-plane grid of any pitch.

The pupil function (`optics.pupil`) is sampled on a regular grid of direction cosines on the exit
pupil's reference sphere, so the Fraunhofer integral is a separable matrix Fourier transform at any
image-plane pitch, with no FFT padding or λ·F/(Q·D) constraint.

References: J. W. Goodman, "Introduction to Fourier Optics", 3rd ed., Roberts & Company, 2005
(Fraunhofer diffraction from the exit pupil); R. Soummer, L. Pueyo, A. Sivaramakrishnan and
R. J. Vanderbei, "Fast computation of Lyot-style coronagraph propagation", Optics Express 15(24),
15935–15951, 2007 (the matrix Fourier transform).
"""

from __future__ import annotations

import math

import numpy as np

from ..blas import single_threaded_blas
from ..optics import tracer
from ..optics.pupil import PupilFunction, Pupils
from ..threads import in_threads
from .base import Computed, centring_warnings, grid_offsets, window_centres_um
from .geometric import entrance_grid_hits, geometric, light_offsets_um

dr = tracer.dr


def compute(
    lens,
    field_deg: np.ndarray,
    wavelength_nm: np.ndarray,
    pitch_um: float,
    size: int,
    *,
    shared_origin: bool = False,
    pupil_samples: int,
    most: int,
) -> Computed:
    """Fraunhofer PSFs of field/wavelength pairs from their pupil functions on pupil_samples² grids
    (the method "fraunhofer" of `registry`, which gives `most`, the largest pupil samples allowed)."""
    pupils = Pupils(lens, field_deg, wavelength_nm)
    pf = pupils.sampled(pupil_samples)
    light = light_offsets_um(lens, field_deg, wavelength_nm, pf.chief)
    center = window_centres_um(pf.chief, light, shared_origin)
    data = fraunhofer(pf, pitch_um, size, center)
    error = sampling_errors(pupils, pf, data, pitch_um, size, center)
    fields = np.atleast_2d(field_deg)
    transmission = pf.transmission.copy()
    folded, fold_warnings = caustic_fallback(lens, pf, data, transmission, pitch_um, size, center, fields)
    error[folded] = 0.0  # those PSFs are the geometric method's
    resolved = np.where(error > ERROR_LIMIT, sampling_need(pf, pitch_um, size, ~folded)[2], 0.0)
    warnings = []
    for w in dict.fromkeys(pf.wavelength_nm.tolist()):  # each wavelength's worst PSF, as when computed alone
        mine = pf.wavelength_nm == w
        warnings += sampling_warnings(pf, pitch_um, size, fields, ~folded & mine, most) + convergence_warnings(
            np.where(mine, error, 0.0), pupil_samples, most, fields, pf.wavelength_nm, resolved[mine].max()
        )
    return Computed(
        data=data,
        chief=pf.chief,
        transmission=transmission,
        vignetted_by=pf.vignetted_by,
        centre_um=center,
        warnings=tuple(warnings + fold_warnings + centring_warnings(pf.chief, light, field_deg)),
    )


FOLD_POWER = 20.0  # a pupil cell's power above this many times the median: the pupil may fold (a caustic)
FOLD_TRANSMISSION = 0.05  # ... confirmed where the transmission differs from a ray count by this fraction
FOLD_CHECK_RAYS = 128  # rays per side of that count
FOLD_RAYS = 512  # rays per side of the geometric PSF that replaces a folded pupil's


def caustic_fallback(
    lens,
    pf: PupilFunction,
    data: np.ndarray,
    transmission: np.ndarray,
    pitch_um: float,
    size: int,
    center: np.ndarray | None,
    field_deg: np.ndarray,
) -> tuple[np.ndarray, list[str]]:
    """Near a pupil caustic (rays close to total internal reflection: the map from pupil grid to entrance
    folds, the power per cell grows without bound) the pupil function's integral is wrong (Cooke triplet at
    31°: transmission 1.09 against 0.39). Such fields, found by their power peak and confirmed by a ray
    count, get the geometric method's PSF and transmission in `data` and `transmission` (in place); returns
    which fields and a warning naming them."""
    # a field whose chief ray is lost (Cooke at 32°: totally reflected) has its pupil built about a
    # substitute ray; its integral is checked too (transmission 0.015 against 0.079 by ray count)
    suspect = np.flatnonzero(power_peaks(pf.power, pf.coverage >= 1) | pf.chief.vignetted)
    if not len(suspect):
        return np.zeros(len(data), dtype=bool), []
    wl, chief = pf.wavelength_nm[suspect], pf.chief.subset(suspect)
    counted = np.array([w.sum() for *_, w in entrance_grid_hits(lens, field_deg[suspect], wl, FOLD_CHECK_RAYS, chief)])
    off = np.abs(transmission[suspect] - counted) > FOLD_TRANSMISSION * counted
    folded, chief = suspect[off], pf.chief.subset(suspect[off])
    if not len(folded):
        return np.zeros(len(data), dtype=bool), []
    i = folded[0]
    text = (
        f"the pupil function fails at field ({field_deg[i, 0]:g}, {field_deg[i, 1]:g}) deg, "
        f"{pf.wavelength_nm[i]:g} nm (it folds over a caustic, rays near total internal reflection, or is "
        f"built about a substitute for a lost chief ray; Fraunhofer transmission "
        f"{transmission[i]:.3g} against {counted[off][0]:.3g} by ray count): the PSF of {len(folded)} "
        f"field(s) is the geometric method's ({FOLD_RAYS} x {FOLD_RAYS} rays), without diffraction"
    )
    sub = None if center is None else center[folded]
    data[folded], _, transmission[folded] = geometric(
        lens, field_deg[folded], pf.wavelength_nm[folded], pitch_um, size, FOLD_RAYS, chief, sub
    )
    mask = np.zeros(len(data), dtype=bool)
    mask[folded] = True
    return mask, [text]


def power_peaks(power: np.ndarray, full: np.ndarray) -> np.ndarray:
    """Per pupil (n, N, N), whether its largest power over the cells `full` (a mask) exceeds FOLD_POWER times
    their median (at least 1e-300; 0 where no cell is full): `caustic_fallback`'s first test. The median is
    compared by counting the cells below the bound (the same answer as computing it, at a fraction of a
    sort's cost), and computed only where the count leaves it open (an even count split at the bound)."""
    peak = np.where(full, power, 0.0).max(axis=(1, 2))
    cells = full.sum(axis=(1, 2))
    below = (full & (FOLD_POWER * power < peak[:, None, None])).sum(axis=(1, 2))
    # the median (the middle cell, or the mean of the two middle ones) times FOLD_POWER is below the peak when
    # more than half the cells are; not when half or fewer are, except an even count split evenly, whose
    # mean of the two middle cells decides
    over = below > cells // 2
    for i in np.flatnonzero((cells > 0) & (cells % 2 == 0) & (below == cells // 2)):
        over[i] = peak[i] > FOLD_POWER * np.median(power[i][full[i]])
    return over & (peak > FOLD_POWER * 1e-300)


ERROR_LIMIT = 0.02  # largest PSF error (fraction of its peak) left unflagged: check-stability's criterion


def coarse_samples(samples: int) -> int:
    """The pupil grid of the error estimate: two thirds as fine."""
    return max(4, (2 * samples) // 3)


PROBE_STRIDE = 16  # the error estimate's first pass: every 16th PSF, the 1/16 with the steepest wavefronts ...
PROBE_WIDEN = 0.25  # ... and every vignetted one; all of them where one of those is within 4x of ERROR_LIMIT


def sampling_errors(
    pupils: Pupils, pf: PupilFunction, data: np.ndarray, pitch_um: float, size: int, center: np.ndarray | None
) -> np.ndarray:
    """`error_estimate` of the PSFs `data` (n, size, size) from the pupil functions `pf`, in two passes: first
    the PSFs where sampling errors gather (measured on the shipped lenses: every PSF beyond ERROR_LIMIT had a
    pupil clipped by an aperture other than the stop, whose hard edge converges as 1/N, or one of the
    steepest wavefronts), then, where one of those comes within PROBE_WIDEN of the limit, every PSF;
    the others, below, count as 0."""
    n = len(data)
    first = np.zeros(n, dtype=bool)
    first[::PROBE_STRIDE] = True
    first[np.argsort(-pf.phase_step, kind="stable")[: max(1, n // PROBE_STRIDE)]] = True
    first |= np.array([bool(v) for v in pf.vignetted_by]) | pf.chief.vignetted
    error = np.zeros(n)
    for index in (np.flatnonzero(first), np.flatnonzero(~first)):
        if len(index) == 0:
            continue
        coarse = pupils.sampled(coarse_samples(pf.alpha.shape[1]), index)
        sub = None if center is None else center[index]
        error[index] = error_estimate(data[index], fraunhofer(coarse, pitch_um, size, sub), pf.alpha.shape[1])
        if error.max() <= PROBE_WIDEN * ERROR_LIMIT:
            break
    return error


def error_estimate(data: np.ndarray, coarse: np.ndarray, samples: int) -> np.ndarray:
    """Per PSF, its error as a fraction of its peak, from the same PSF on a coarser pupil grid: the
    error falls as 1/N² (measured: 9.8 %, 2.2 %, 0.9 % of peak at 256, 512, 768 samples on the doublet
    at f/3.33), so the fine one's is |fine − coarse| / ((N/Nc)² − 1) (Richardson)."""
    ratio = samples / coarse_samples(samples)
    peak = np.maximum(data.max(axis=(1, 2)), 1e-300)
    return np.abs(data - coarse).max(axis=(1, 2)) / peak / (ratio * ratio - 1.0)


def convergence_warnings(
    error: np.ndarray, samples: int, most: int, field_deg: np.ndarray, wavelength_nm: np.ndarray, floor: float = 0.0
) -> list[str]:
    """A warning naming the worst PSF whose estimated error exceeds ERROR_LIMIT of its peak, with the
    pupil samples that bring it within (error ∝ 1/N²; at least `floor`, the count that resolves the
    wavefront: the 1/N² estimate holds only once it is resolved), or saying that `most` samples cannot."""
    if not (error > ERROR_LIMIT).any():
        return []
    i = int(np.argmax(error))
    need = max(int(math.ceil(samples * math.sqrt(error[i] / ERROR_LIMIT) * 1.15 / 8) * 8), int(floor))
    head = (
        f"the PSF at field ({field_deg[i, 0]:g}, {field_deg[i, 1]:g}) deg, {wavelength_nm[i]:g} nm is about "
        f"{100 * error[i]:.1f} % of its peak off its converged value with {samples} pupil samples "
        f"(limit {100 * ERROR_LIMIT:g} %)"
    )
    if need <= most:
        return [f"{head}; use --pupil-samples {need} or more"]
    return [
        f"{head}; that needs about {need} pupil samples, beyond the {most} maximum: use "
        "--psf-method geometric (the wavefront is far from diffraction-limited)"
    ]


def sampling_need(
    pf: PupilFunction, pitch_um: float, size: int, keep: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per field: the largest phase step (rad) between neighbouring pupil cells, the PSF period λ'/Δα
    (µm), and the pupil samples that would keep every step within π/2 and the period beyond the
    window. Fields not in `keep` (a mask; default all) need nothing."""
    n = pf.alpha.shape[1]
    steps = pf.phase_step
    period_um = (pf.wavelength_nm * 1e-3 / pf.chief.n_image) / np.minimum(
        pf.alpha[:, 1] - pf.alpha[:, 0], pf.beta[:, 1] - pf.beta[:, 0]
    )
    if keep is not None:
        steps, period_um = np.where(keep, steps, 0.0), np.where(keep, period_um, np.inf)
    need = np.maximum(n * steps / (0.5 * math.pi), n * size * pitch_um / period_um)
    return steps, period_um, np.ceil(need / 8) * 8


def sampling_warnings(
    pf: PupilFunction,
    pitch_um: float,
    size: int,
    field_deg: np.ndarray,
    keep: np.ndarray | None = None,
    most: int | None = None,
) -> list[str]:
    """Where the pupil grid cannot carry the wavefront: a phase step above π between neighbouring
    cells (the wavefront is under-sampled), or a PSF period λ'/Δα shorter than the window (copies of
    the PSF fold into it). Each names the worst field and the pupil samples that would do, or, where
    that is beyond `most` (the most allowed), the geometric method; fields not in `keep` (a mask;
    default all) are left out."""
    n = pf.alpha.shape[1]
    steps, period_um, need = sampling_need(pf, pitch_um, size, keep)
    window_um = size * pitch_um
    advice = (
        f"use --pupil-samples {int(need.max())} or more"
        if most is None or need.max() <= most
        else f"that needs about {int(need.max())} pupil samples, beyond the {most} maximum: use --psf-method "
        "geometric (the wavefront is far from diffraction-limited)"
    )
    out = []
    if (steps > math.pi).any():
        i = int(np.argmax(steps))
        out.append(
            f"pupil samples {n} under-resolve the wavefront at field ({field_deg[i, 0]:g}, {field_deg[i, 1]:g}) "
            f"deg, {pf.wavelength_nm[i]:g} nm: phase steps up to {steps[i]:.1f} rad per cell (> pi); {advice}"
        )
    if (period_um < window_um).any():
        i = int(np.argmin(period_um))
        out.append(
            f"the {window_um:g} um window is wider than the PSF period {period_um[i]:.1f} um of {n} pupil samples "
            f"at field ({field_deg[i, 0]:g}, {field_deg[i, 1]:g}) deg: copies of the PSF fold in; {advice}"
        )
    return out


def fraunhofer(pf: PupilFunction, pitch_um: float, size: int, center_um: np.ndarray | None = None) -> np.ndarray:
    """Fraunhofer PSFs (n, size, size) in 1/µm² from pupil functions, by matrix DFT.

    `center_um` (n, 2) shifts each grid's origin from the chief ray (default: none)."""
    n = len(pf.alpha)
    offs = grid_offsets(size, pitch_um) * 1e-3  # mm
    u = np.broadcast_to(offs, (n, size)).copy()
    v = np.broadcast_to(-offs, (n, size)).copy()
    if center_um is not None:
        u += center_um[:, 0:1] * 1e-3
        v += center_um[:, 1:2] * 1e-3
    lam = pf.wavelength_nm * 1e-6 / pf.chief.n_image  # mm, in image space
    k = 2.0 * math.pi / lam
    # separable DFT kernels exp(−i k α u): phases in float64, values and products in complex64 (errors ~1e-7
    # of the peak)
    ex = dft_kernels(k, pf.alpha, u)  # (n, N, size)
    ey = dft_kernels(k, pf.beta, v).transpose(0, 2, 1)  # (n, size, N)
    scale = (pf.cell_area / lam) ** 2 * 1e-6  # |U|² in 1/mm² → 1/µm²
    out = np.empty((n, size, size))

    def product(f: int) -> None:
        field_ = (ey[f] @ pf.complex_pupil[f]) @ ex[f]
        np.multiply(
            np.square(field_.real, dtype=np.float64) + np.square(field_.imag, dtype=np.float64), scale[f], out=out[f]
        )

    with single_threaded_blas():  # many small products: one BLAS thread each, a thread per core
        in_threads(product, list(range(n)))
    return out


def dft_kernels(k: np.ndarray, axis: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """exp(−i k_f a_fj o_fm) as complex64 (n, len(a), len(o)): one Dr.Jit kernel, the phase in float64."""
    n, na = axis.shape
    no = offsets.shape[1]
    e = dr.arange(tracer.UInt32, n * na * no)
    f = e // (na * no)
    x = (
        tracer.gather(k, f)
        * tracer.gather(axis.ravel(), f * na + (e // no) % na)
        * tracer.gather(offsets.ravel(), f * no + e % no)
    )
    sin, cos = dr.sincos(x)
    f32 = dr.float32_array_t(tracer.F)
    real, imag = f32(cos), f32(-sin)
    dr.eval(real, imag)
    out = np.empty((n, na, no), dtype=np.complex64)
    out.real, out.imag = np.asarray(real).reshape(out.shape), np.asarray(imag).reshape(out.shape)
    return out
