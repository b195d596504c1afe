"""Radial annuli of an image, as fractions of the centre-to-corner radius: the automotive scheme
(centre < 0.24, middle < 0.6, edge ≤ 1) and three equal-area rings."""
from __future__ import annotations

import math

ANNULI: dict[str, tuple[float, float, float]] = {
    "automotive": (0.24, 0.6, 1.0),
    "equal-area": (math.sqrt(1 / 3), math.sqrt(2 / 3), 1.0),
}
ANNULUS_NAMES = ("centre", "middle", "edge")
