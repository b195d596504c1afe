"""Radial annuli of an image, the one definition every report uses (natural-scene SFR, the
cross-validation's error maps): a point's radius r/R is its distance from the image centre over R,
the centre-to-corner distance of the image (R = √(W² + H²)/2), with pixel (column c, row r) centred
at (c, r) and the image centre at ((W − 1)/2, (H − 1)/2).

Schemes (outer bounds of centre / middle / edge as fractions of R): "automotive" 0.24 / 0.6 / 1.0,
as in the SOLAS paper's figure 5, and "equal-area", three rings of equal area.
"""

from __future__ import annotations

import math

import numpy as np

ANNULI: dict[str, tuple[float, float, float]] = {
    "automotive": (0.24, 0.6, 1.0),
    "equal-area": (math.sqrt(1 / 3), math.sqrt(2 / 3), 1.0),
}
ANNULUS_NAMES = ("centre", "middle", "edge")


def corner_radius(height: int, width: int) -> float:
    """R: distance from the centre of a height×width image to a corner (px)."""
    return math.hypot(height, width) / 2


def radius_fraction(x, y, height: int, width: int):
    """r/R of points (x, y) in pixel coordinates (pixel centres at integers)."""
    return np.hypot(np.asarray(x) - (width - 1) / 2, np.asarray(y) - (height - 1) / 2) / corner_radius(height, width)


def annulus_index(fraction, scheme: str = "automotive"):
    """Annulus (0 centre, 1 middle, 2 edge) of radius fractions r/R."""
    return np.searchsorted(np.array(ANNULI[scheme][:-1]), fraction, side="right")


def annulus_map(height: int, width: int, scheme: str = "automotive") -> np.ndarray:
    """Annulus index of every pixel of a height×width image."""
    y, x = np.mgrid[0:height, 0:width]
    return annulus_index(radius_fraction(x, y, height, width), scheme)
