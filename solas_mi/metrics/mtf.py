"""MTF routines every stage shares: the MTF of a sampled PSF along a direction (`mtf_along`), the pixel
aperture's MTF (`aperture_mtf`, `pixel_mtf`: a box of the pixel's active width, or Mitsuba's Gaussian
reconstruction filter), and the frequency where an MTF falls to one half (`mtf50`).

The MTF along a direction is the modulus of the PSF's optical transfer function on the line through
the origin of frequency space in that direction (projection-slice theorem: the Fourier transform of
the line spread function). A square pixel of pitch p whose light-sensitive part is a centred square
of fill factor F (its area over p²) integrates the image over a box of width a = p·√F: its MTF along
the direction φ is |sinc(ν a cos φ)·sinc(ν a sin φ)|, sinc(x) = sin(πx)/(πx).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError

FREQ = np.linspace(0.0, 1.0, 2001)  # cy/px, where MTF50 is looked for
BIN = 0.125  # LSF bin (PSF pixels); its own MTF, sinc(f·bin), is above 0.9996 to 1 cy/px for PSF pitch ≤ pixel/8
APERTURES = {"box": 0.0, "gaussian": 0.5}  # pixel aperture → Gaussian σ (px; Mitsuba's default), 0: a box


def aperture_mtf(freq_cy_px: np.ndarray, normal_deg: float, aperture: str = "box") -> np.ndarray:
    """MTF of the pixel aperture along `normal_deg` (degrees from +x): "box", a square pixel, or
    "gaussian", Mitsuba's Gaussian reconstruction filter (σ = 0.5 px)."""
    if aperture not in APERTURES:
        raise SolasError(f"pixel aperture {aperture!r} must be one of {', '.join(APERTURES)}")
    f = np.asarray(freq_cy_px, dtype=np.float64)
    if aperture == "box":
        return box_mtf(f, 1.0, normal_deg)
    return np.exp(-2.0 * np.pi**2 * APERTURES[aperture] ** 2 * f**2)


def mtf_along(
    psf: np.ndarray,
    psf_pitch_um: float,
    pixel_um: float,
    normal_deg: float,
    aperture: str = "box",
    freq_cy_px: np.ndarray = FREQ,
) -> np.ndarray:
    """MTF at `freq_cy_px` (cy/px) along the direction `normal_deg` (degrees from the image's +x axis,
    +y down) of a PSF sampled at `psf_pitch_um` (µm; rows along y), seen by pixels of `pixel_um` (µm)
    with `aperture` ("box" or "gaussian", `aperture_mtf`), normalised to 1 at zero frequency."""
    psf = np.asarray(psf, dtype=np.float64)
    total = psf.sum()
    if psf.ndim != 2 or not total > 0:
        raise SolasError(f"a PSF of shape {psf.shape} must be a 2-D array with a positive sum")
    if not (psf_pitch_um > 0 and pixel_um > 0):
        raise SolasError(f"PSF pitch {psf_pitch_um!r} um and pixel pitch {pixel_um!r} um must be positive")
    phi = np.radians(normal_deg)
    rows, cols = psf.shape
    y = (np.arange(rows) - (rows - 1) / 2) * psf_pitch_um
    x = (np.arange(cols) - (cols - 1) / 2) * psf_pitch_um
    # the line spread function: the PSF's mass projected on the normal (µm), in bins of BIN × the PSF pitch
    s = (x[None, :] * np.cos(phi) + y[:, None] * np.sin(phi)).ravel()
    keep = psf.ravel() > 0
    width = BIN * psf_pitch_um
    index = np.floor(s[keep] / width).astype(np.int64)
    lsf = np.bincount(index - index.min(), weights=psf.ravel()[keep] / total)
    centres = (np.arange(lsf.size) + index.min() + 0.5) * width
    f_um = np.asarray(freq_cy_px, dtype=np.float64)[:, None] / pixel_um
    otf = np.abs(np.exp(-2j * np.pi * f_um * centres[None, :]) @ lsf)
    return otf * aperture_mtf(freq_cy_px, normal_deg, aperture)


def mtf50(mtf: np.ndarray, freq_cy_px: np.ndarray = FREQ) -> float | None:
    """The first frequency (cy/px) where `mtf` falls to 0.5, linearly interpolated; None if it never does."""
    below = np.flatnonzero(np.asarray(mtf) < 0.5)
    if below.size == 0:
        return None
    i = int(below[0])
    if i == 0:
        return float(freq_cy_px[0])
    f0, f1, m0, m1 = freq_cy_px[i - 1], freq_cy_px[i], mtf[i - 1], mtf[i]
    return float(f0 + (m0 - 0.5) * (f1 - f0) / (m0 - m1))


def box_mtf(freq: np.ndarray, width: float, normal_deg: float = 0.0) -> np.ndarray:
    """MTF of a square box of side `width` (in the unit whose inverse `freq` is in) along `normal_deg`
    (degrees from the box's x side): |sinc(ν a cos φ)·sinc(ν a sin φ)|."""
    phi = math.radians(normal_deg)
    f = np.asarray(freq, dtype=np.float64)
    return np.abs(np.sinc(f * width * math.cos(phi)) * np.sinc(f * width * math.sin(phi)))


def pixel_mtf(freq_cy_mm: np.ndarray, pitch_um: float, fill_factor: float = 1.0, normal_deg: float = 0.0) -> np.ndarray:
    """MTF of square pixels of `pitch_um` (µm) whose sensitive part is a centred square of `fill_factor`
    (0 < F ≤ 1, its area over the pixel's) at `freq_cy_mm` (cycles/mm) along `normal_deg` (degrees from
    the pixel rows): `box_mtf` of width pitch·√F."""
    if not (isinstance(pitch_um, (int, float)) and math.isfinite(pitch_um) and pitch_um > 0):
        raise SolasError(f"pixel pitch {pitch_um!r} um must be a positive number")
    if not (isinstance(fill_factor, (int, float)) and 0 < fill_factor <= 1):
        raise SolasError(f"pixel fill factor {fill_factor!r} must be in (0, 1]: the sensitive area over the pixel's")
    return box_mtf(freq_cy_mm, pitch_um * 1e-3 * math.sqrt(fill_factor), normal_deg)
