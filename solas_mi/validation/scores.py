"""How far a degraded image is from the reference: relative RMSE (whole image and per annulus), PSNR
and SSIM, each also with the reference's own noise removed.

Errors: relative RMSE = RMS(image − reference)/RMS(reference) over all pixels and channels, and
per annulus (centre < 0.24 R ≤ middle < 0.6 R ≤ edge, R = the centre-to-corner distance, as
`metrics.nssfr`'s automotive annuli: `metrics.annuli`); PSNR with data_range = max(reference); SSIM
from scikit-image (channel_axis=-1, same data_range). The reference's noise σ_ref (`reference`) is
removed in quadrature: e = sqrt(max(0, e_measured² − σ_ref²)). All are unitless (PSNR in dB).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from ..metrics.annuli import ANNULUS_NAMES, annulus_map


@dataclass
class Errors:
    rel_rmse: float  # RMS(image − ref)/RMS(ref)
    rel_rmse_denoised: float  # reference noise removed in quadrature
    rmse: float
    psnr_db: float
    ssim: float
    annuli: dict[str, float]  # relative RMSE per annulus (normalised by the annulus's RMS(ref))
    annuli_denoised: dict[str, float]


def denoise(err: float, noise: float) -> float:
    """An error with a noise of RMS `noise` removed in quadrature (0 where the noise is larger)."""
    return math.sqrt(max(0.0, err * err - noise * noise))


SSIM_WINDOW_PX = 7  # scikit-image's structural_similarity window


def _pixels(values, what: str) -> np.ndarray:
    """`values` as a float64 H×W×C array of finite numbers at least SSIM_WINDOW_PX a side, or SolasError."""
    try:
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise SolasError(f"the {what} must be an H×W×C array of numbers, not {type(values).__name__}") from None
    if a.ndim != 3 or min(a.shape[:2]) < SSIM_WINDOW_PX:
        raise SolasError(
            f"the {what}'s shape {a.shape} must be H×W×C (channels last), at least "
            f"{SSIM_WINDOW_PX} px a side (SSIM's window)"
        )
    if not np.all(np.isfinite(a)):
        raise SolasError(f"the {what} holds NaN or infinite values: only finite pixel values are allowed")
    return a


def compare(image: np.ndarray, ref: np.ndarray, ref_noise: float = 0.0, noise_map: np.ndarray | None = None) -> Errors:
    """Errors of `image` against `ref` (same shape). ref_noise: the reference's RMS noise (absolute);
    noise_map: its per-pixel variance estimate (for the annuli; default uniform)."""
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    image, ref = _pixels(image, "image"), _pixels(ref, "reference")
    if image.shape != ref.shape:
        raise SolasError(f"image shape {image.shape} differs from the reference's {ref.shape}")
    diff2 = (image - ref) ** 2
    ref_rms = math.sqrt(float(np.mean(ref**2)))
    if ref_rms == 0:
        raise SolasError("the reference image is black: nothing to compare against")
    rmse = math.sqrt(float(diff2.mean()))
    top = float(ref.max())
    psnr = float(peak_signal_noise_ratio(ref, image, data_range=top)) if rmse > 0 else float("inf")
    ssim = float(structural_similarity(ref, image, channel_axis=-1, data_range=top))
    rings = annulus_map(*ref.shape[:2])
    var = noise_map if noise_map is not None else np.full(ref.shape[:2], ref_noise**2)
    ann, ann_dn = {}, {}
    for i, name in enumerate(ANNULUS_NAMES):
        m = rings == i
        if not m.any():
            continue
        rr = math.sqrt(float(np.mean(ref[m] ** 2)))
        e = math.sqrt(float(diff2[m].mean())) / rr
        ann[name] = e
        ann_dn[name] = denoise(e, math.sqrt(float(np.mean(var[m]))) / rr)
    rel = rmse / ref_rms
    return Errors(rel, denoise(rel, ref_noise / ref_rms), rmse, psnr, ssim, ann, ann_dn)
