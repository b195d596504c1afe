"""An RGB colour as a spectrum, as Mitsuba's emitters make it (`image_object`'s `spectrum` "srgb"):
Mitsuba's smooth spectral upsampling (W. Jakob, J. Hanika, "A Low-Dimensional Function Space for
Efficient Spectral Upsampling", Computer Graphics Forum 38(2), 2019): coefficients of a sigmoid of a
quadratic in λ (nm) per colour, `mi.srgb_model_fetch`, evaluated by `mi.srgb_model_eval`."""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np


def upsampled(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per texel of an H×W×3 linear sRGB image (negative values as 0): Mitsuba's sigmoid coefficients
    (n×3) of c/s, s = 2·max(c), and s (n) (0 for black)."""
    flat = np.maximum(rgb.reshape(-1, 3), 0.0).astype(np.float32)
    scale = 2.0 * flat.max(axis=1)
    unit = flat / np.where(scale > 0, scale, 1.0)[:, None]
    colours, inverse = np.unique(unit, axis=0, return_inverse=True)
    coeff = np.array([list(mi.srgb_model_fetch(mi.ScalarColor3f(*(float(x) for x in c)))) for c in colours])
    return coeff[inverse.ravel()], scale


def sigmoid(c0, c1, c2, lam):
    """Mitsuba's `srgb_model_eval` of coefficients (c0, c1, c2) at `lam` (nm), written out so that a
    mono variant (whose `srgb_model_eval` takes no wavelength) evaluates it too."""
    x = dr.fma(dr.fma(c0, lam, c1), lam, c2)
    value = dr.maximum(dr.fma(0.5 * x, dr.rsqrt(dr.fma(x, x, 1.0)), 0.5), 0.0)
    return dr.select(dr.isinf(c2), dr.select(c2 > 0, 1.0, 0.0), value)
