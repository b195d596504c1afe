"""The iris's starburst: the diffraction of the stop's shape, which geometric ray tracing leaves out, as a kernel
spread onto an image (`render --ghosts` onto the lens camera's direct image, `degrade --ghosts` onto the degraded
frame: `convolution.ghosts`), so that rendered and degraded frames carry the same spikes.

Why a kernel and not sampling: the camera's rays are geometric; to sample diffraction each ray would have to
be deflected at the stop by a direction drawn from the aperture's Fraunhofer pattern (a 2D table per
wavelength, drawn inside the render's kernel), and the spikes of a sun far from its pixel would still be
found by few samples. The pattern is shift-invariant over the field where the stop is (its shape and the
working f-number change little), so one kernel convolved by FFT onto the whole image gives every
bright pixel its spikes, noise-free, in one pass.

The kernel (`iris_kernel`) is the aberration-free diffraction pattern of the stop's shape (the iris's
polygon of `blades`, straight or curved, or the round stop: its Airy pattern) at the lens's working f-number and one
wavelength, |FFT(aperture)|² sampled at `OVERSAMPLE`·(Nyquist) over two windows (no spike folds back into
the window) and binned to the image's pixels, normalised
to sum 1 over its window (the energy beyond it is dropped: the window is `KERNEL_PX` pixels, fewer where the
sampling would exceed `MAX_FFT`, one where pixels are so large that all but a few 1e-4 of the light stays in
its own). Not the lens's Fraunhofer PSF: that one holds the aberrations too, which
the render has traced and the degradation convolved. Only its wings, the kernel less its centre pixel, are spread
(`spread`): each pixel keeps the fraction of its light the centre pixel holds and gives the rest to the
wings, so the frame's light is kept (less what the wings carry beyond its edges). `lens_starburst`: a lens's
kernel and what a metadata block says of it.
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


def lens_starburst(lens, wavelength_nm: float, pitch_um: float) -> tuple[np.ndarray, dict] | None:
    """The starburst kernel of `lens`'s stop (`iris_kernel`) at its working f-number, `wavelength_nm` and pixels of
    `pitch_um`, and what the metadata says of it; None for a lens without a stop or an f-number (no image)."""
    from .stray_light import working_f_number

    stops = [s for s in lens.surfaces if s.stop]
    f_number = working_f_number(lens)
    if not stops or not math.isfinite(f_number):
        return None
    kernel = iris_kernel(stops[0], f_number, wavelength_nm, pitch_um)
    centre = kernel.shape[0] // 2
    about = {
        "kernel_px": kernel.shape[0],
        "wavelength_nm": float(wavelength_nm),
        "pitch_um": float(pitch_um),
        "f_number": f_number,
        "blades": stops[0].blades,
        "wings": float(1.0 - kernel[centre, centre]),
    }
    return kernel, about
