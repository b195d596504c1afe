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
from ..optics.pupil import PupilFunction, pupil_function
from .base import Computed, centring_warnings, grid_offsets, window_centres_um
from .geometric import light_offsets_um


def compute(lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, pitch_um: float, size: int, *,
            shared_origin: bool = False, pupil_samples: int) -> Computed:
    """Fraunhofer PSFs of field/wavelength pairs from their pupil functions on pupil_samples² grids
    (the method "fraunhofer" of `registry`)."""
    pf = pupil_function(lens, field_deg, wavelength_nm, pupil_samples)
    light = light_offsets_um(lens, field_deg, wavelength_nm, pf.chief)
    center = window_centres_um(pf.chief, light, shared_origin)
    return Computed(data=fraunhofer(pf, pitch_um, size, center), chief=pf.chief, transmission=pf.transmission,
                    vignetted_by=pf.vignetted_by, centre_um=center,
                    warnings=tuple(sampling_warnings(pf, pitch_um, size, np.atleast_2d(field_deg))
                                   + centring_warnings(pf.chief, light, field_deg)))


def sampling_warnings(pf: PupilFunction, pitch_um: float, size: int, field_deg: np.ndarray) -> list[str]:
    """Where the pupil grid cannot carry the wavefront: a phase step above π between neighbouring
    cells (the wavefront is under-sampled), or a PSF period λ'/Δα shorter than the window (copies of
    the PSF fold into it). Each names the worst field and the pupil samples that would do."""
    n = pf.alpha.shape[1]
    lam_nm = pf.wavelength_nm[:, None, None]
    phase = 2.0 * math.pi / (lam_nm * 1e-6) * pf.opd_mm
    inside = pf.coverage > 0
    steps = np.zeros(len(phase))
    for axis in (1, 2):
        both = np.logical_and(np.take(inside, range(1, n), axis=axis), np.take(inside, range(n - 1), axis=axis))
        step = np.abs(np.diff(phase, axis=axis))
        steps = np.maximum(steps, np.where(both, step, 0.0).max(axis=(1, 2)))
    period_um = (pf.wavelength_nm * 1e-3 / pf.chief.n_image) / np.minimum(pf.alpha[:, 1] - pf.alpha[:, 0],
                                                                          pf.beta[:, 1] - pf.beta[:, 0])
    window_um = size * pitch_um
    need = np.maximum(n * steps / (0.5 * math.pi), n * window_um / period_um)
    out = []
    if (steps > math.pi).any():
        i = int(np.argmax(steps))
        out.append(f"pupil samples {n} under-resolve the wavefront at field ({field_deg[i, 0]:g}, {field_deg[i, 1]:g}) "
                   f"deg, {pf.wavelength_nm[i]:g} nm: phase steps up to {steps[i]:.1f} rad per cell (> pi); use "
                   f"--pupil-samples {int(math.ceil(need.max() / 8) * 8)} or more")
    if (period_um < window_um).any():
        i = int(np.argmin(period_um))
        out.append(f"the {window_um:g} um window is wider than the PSF period {period_um[i]:.1f} um of {n} pupil samples "
                   f"at field ({field_deg[i, 0]:g}, {field_deg[i, 1]:g}) deg: copies of the PSF fold in; use "
                   f"--pupil-samples {int(math.ceil(need.max() / 8) * 8)} or more")
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
    phase = (2.0 * math.pi / (pf.wavelength_nm * 1e-6))[:, None, None] * pf.opd_mm
    pupil = (pf.amplitude * np.exp(1j * phase)).astype(np.complex64)
    # separable DFT kernels; phases in float64, products in complex64 (errors ~1e-7 of the peak)
    ex = np.exp(-1j * k[:, None, None] * pf.alpha[:, :, None] * u[:, None, :]).astype(np.complex64)  # (n, N, size)
    ey = np.exp(-1j * k[:, None, None] * v[:, :, None] * pf.beta[:, None, :]).astype(np.complex64)  # (n, size, N)
    field_ = np.empty((n, len(offs), len(offs)), dtype=np.complex64)
    with single_threaded_blas():  # many small products: BLAS threads only contend for the cores
        for f in range(n):
            field_[f] = (ey[f] @ pupil[f]) @ ex[f]
    scale = (pf.cell_area / lam) ** 2 * 1e-6  # |U|² in 1/mm² → 1/µm²
    return (field_.real.astype(np.float64) ** 2 + field_.imag.astype(np.float64) ** 2) * scale[:, None, None]
