"""The MTF50 that a PSF grid predicts for a slanted edge: the PSF's line spread function along the
edge normal, convolved with the square pixel aperture, Fourier-transformed.

The MTF along a direction is the modulus of the PSF's optical transfer function on the line through
the origin of frequency space in that direction (projection-slice theorem: the Fourier transform of
the line spread function), times the pixel aperture's transfer function there: for a square pixel
|sinc(f·cos φ)·sinc(f·sin φ)|, for the film's Gaussian reconstruction filter of standard deviation σ
(px) exp(−2π²σ²f²), f in cy/px. An image that is the scene seen through the PSF and the aperture has
this MTF at every edge, so the e-SFR measured on it should match, up to the e-SFR's own sampling and
noise.
"""
from __future__ import annotations

import numpy as np

from ...errors import SolasError

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
        phi = np.radians(normal_deg)
        return np.abs(np.sinc(f * np.cos(phi)) * np.sinc(f * np.sin(phi)))
    return np.exp(-2.0 * np.pi ** 2 * APERTURES[aperture] ** 2 * f ** 2)


def mtf_along(psf: np.ndarray, psf_pitch_um: float, pixel_um: float, normal_deg: float,
              aperture: str = "box", freq_cy_px: np.ndarray = FREQ) -> np.ndarray:
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


def edge_normal_deg(orientation: str, angle_deg: float) -> float:
    """Edge normal from the e-SFR's orientation ("vertical": a near-vertical edge, normal near x) and
    its tilt (degrees): the normal, in degrees from +x."""
    return float(angle_deg) if orientation.startswith("v") else 90.0 + float(angle_deg)


def predicted_mtf50(grid, lay, x_px: float, y_px: float, normal_deg: float, aperture: str = "box",
                    channel: int = 0) -> float | None:
    """MTF50 (cy/px) that `grid` (a PSFGrid) predicts at pixel (x_px, y_px) of the image it is laid on
    (`lay`: `convolution.kernels.layout` of the grid on that image): the PSF of the nearest node, its
    MTF along `normal_deg` with the `aperture` of the layout's camera's pixels."""
    col = int(np.argmin(np.abs(lay.col_knots - x_px)))
    row = int(np.argmin(np.abs(lay.row_knots - y_px)))
    return mtf50(mtf_along(grid.data[channel, row, col], grid.pitch_um, lay.camera.pitch_um, normal_deg, aperture))
