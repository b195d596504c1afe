"""The iris's starburst in a lens-camera render (`render --ghosts`, `render.flare`): the diffraction of the
stop's shape, which a geometric ray tracer leaves out, convolved onto the direct image.

Why a kernel and not sampling: the camera's rays are geometric; to sample diffraction each ray would have to
be deflected at the stop by a direction drawn from the aperture's Fraunhofer pattern (a 2D table per
wavelength, drawn inside the render's kernel), and the spikes of a sun far from its pixel would still be
found by few samples. The pattern is shift-invariant over the field where the stop is (its shape and the
working f-number change little), so one kernel convolved by FFT onto the whole direct image gives every
bright pixel its spikes, noise-free, in one pass.

The kernel (`iris_kernel`) is the aberration-free diffraction pattern of the stop's shape (the iris's
polygon of `blades`, straight or curved, or the round stop: its Airy pattern) at the lens's working f-number and one
wavelength, |FFT(aperture)|² sampled at `OVERSAMPLE`·(Nyquist) over two windows (no spike folds back into
the window) and binned to the film's pixels, normalised
to sum 1 over its window (the energy beyond it is dropped: the window is `KERNEL_PX` pixels, fewer where the
sampling would exceed `MAX_FFT`, one where pixels are so large that all but a few 1e-4 of the light stays in
its own). Not the lens's Fraunhofer PSF: that one holds the aberrations too, which
the render has already traced. Only its wings, the kernel less its centre pixel, are spread
(`spread`): each pixel keeps the fraction of its light the centre pixel holds and gives the rest to the
wings, so the frame's light is kept.
"""

from __future__ import annotations

import math

import numpy as np

KERNEL_PX = 127  # the kernel's side in pixels (odd), where the sampling allows
MAX_FFT = 3072  # the most samples per side of the aperture's FFT (its complex array: 150 MB)
OVERSAMPLE = 2  # samples per Nyquist interval (λN/2) of the pattern, at least


def iris_kernel(stop, f_number: float, wavelength_nm: float, pitch_um: float) -> np.ndarray:
    """The diffraction pattern of surface `stop`'s aperture (its iris: `blades`, `blade_rotation`, or round)
    at `f_number` and `wavelength_nm`, binned to pixels of `pitch_um`: an odd square window, centred, sum 1."""
    lam_n = wavelength_nm * 1e-3 * f_number  # λN (µm)
    # samples per pixel: odd, so that a pixel's samples lie symmetric about its centre (the pattern's at a sample)
    per_pixel = 2 * max(1, math.ceil(OVERSAMPLE * pitch_um / lam_n)) + 1
    size = min(KERNEL_PX, MAX_FFT // (2 * per_pixel))
    size -= 1 - size % 2
    if size < 3:  # pixels so large that all but a few 1e-4 of the light stays in its own
        return np.ones((1, 1))
    side = size * per_pixel  # the window's samples per side, at the pattern's spacing pitch / per_pixel
    # the pupil sampled so that the pattern repeats every two windows (a spike that leaves the window does
    # not come back into it across the opposite edge), its radius 1
    n, step = 2 * side, lam_n / (size * pitch_um)
    u = (np.arange(n) - n // 2) * step
    x, y = np.meshgrid(u * stop.semi_diameter, u * stop.semi_diameter)
    inside = stop.iris_margin(x, y, np.hypot, np.arctan2, np.cos, np.floor) >= 0
    field = np.fft.fft2(np.fft.ifftshift(inside.astype(np.float64)))
    start = n // 2 - side // 2
    pattern = np.fft.fftshift(np.abs(field) ** 2)[start : start + side, start : start + side]
    kernel = pattern.reshape(size, per_pixel, size, per_pixel).sum(axis=(1, 3))
    return kernel / kernel.sum()


def spread(image: np.ndarray, kernel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`image` (H×W×C) with its light spread by `kernel`'s wings: (the image less what its pixels give to the
    wings, what the wings bring each pixel), their sum the image convolved by the kernel."""
    from scipy.signal import fftconvolve

    c = kernel.shape[0] // 2
    wings = kernel.copy()
    wings[c, c] = 0.0
    image = image.astype(np.float64)
    brought = np.stack([fftconvolve(image[..., k], wings, mode="same") for k in range(image.shape[-1])], axis=-1)
    return image * kernel[c, c], np.maximum(brought, 0.0)  # FFT round-off below 0 is no light
