"""The MTF50 that a PSF grid predicts for a slanted edge: the PSF's line spread function along the
edge normal, convolved with the square pixel aperture, Fourier-transformed (`metrics.mtf.mtf_along`).

The MTF along a direction is the modulus of the PSF's optical transfer function on the line through
the origin of frequency space in that direction, times the pixel aperture's transfer function there:
for a square pixel |sinc(f·cos φ)·sinc(f·sin φ)|, for the film's Gaussian reconstruction filter of
standard deviation σ (px) exp(−2π²σ²f²), f in cy/px. An image that is the scene seen through the PSF and the aperture has
this MTF at every edge, so the e-SFR measured on it should match, up to the e-SFR's own sampling and
noise.
"""

from __future__ import annotations

import numpy as np

from ...metrics.mtf import mtf50, mtf_along


def edge_normal_deg(orientation: str, angle_deg: float) -> float:
    """Edge normal from the e-SFR's orientation ("vertical": a near-vertical edge, normal near x) and
    its tilt (degrees): the normal, in degrees from +x."""
    return float(angle_deg) if orientation.startswith("v") else 90.0 + float(angle_deg)


def predicted_mtf50(
    grid, lay, x_px: float, y_px: float, normal_deg: float, aperture: str = "box", channel: int = 0
) -> float | None:
    """MTF50 (cy/px) that `grid` (a PSFGrid) predicts at pixel (x_px, y_px) of the image it is laid on
    (`lay`: `convolution.kernels.layout` of the grid on that image): the PSF of the nearest node, its
    MTF along `normal_deg` with the `aperture` of the layout's camera's pixels."""
    col = int(np.argmin(np.abs(lay.col_knots - x_px)))
    row = int(np.argmin(np.abs(lay.row_knots - y_px)))
    return mtf50(mtf_along(grid.data[channel, row, col], grid.pitch_um, lay.camera.pitch_um, normal_deg, aperture))
