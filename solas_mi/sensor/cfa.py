"""Colour filter arrays: which filter covers each pixel, and the mosaic of a three-channel image.

A pattern names the 2×2 tile row by row ("RGGB": R at (0, 0), G at (0, 1) and (1, 0), B at (1, 1)).
R, G and B sites sample the image's channels 0, 1 and 2; a clear site (C, of RCCB and RCCC, the
automotive patterns) has no colour filter and collects all three (`CHANNELS`: the scalar model; a QE
curve also gives each filter what it passes of the other channels, `qe`).
"""

import numpy as np

from ..errors import SolasError

PATTERNS = ("RGGB", "BGGR", "GRBG", "GBRG", "RCCB", "RCCC")
FILTERS = "RGBC"  # index of each filter in a site map
CHANNELS = {"R": (0,), "G": (1,), "B": (2,), "C": (0, 1, 2)}  # the image channels each filter collects


def check_pattern(pattern: str) -> str:
    if not isinstance(pattern, str) or pattern not in PATTERNS:
        raise SolasError(
            f"sensor cfa = {pattern!r} must be one of {', '.join(PATTERNS)} (the colour filter array's "
            "2×2 tile, row by row)"
        )
    return pattern


def site_map(pattern: str, shape: tuple[int, int]) -> np.ndarray:
    """The filter index (into FILTERS) of each pixel of a (height, width) sensor with `pattern`."""
    tile = np.array([FILTERS.index(f) for f in check_pattern(pattern)], dtype=np.int8).reshape(2, 2)
    height, width = shape
    return np.tile(tile, ((height + 1) // 2, (width + 1) // 2))[:height, :width]


def mosaic(image: np.ndarray, pattern: str, weights: np.ndarray) -> np.ndarray:
    """One value per pixel of a (H, W, 3) image: a site of filter f takes Σ_c weights[f, c] image[..., c]
    (`weights` 4 × 3, rows in FILTERS order: the effective quantum efficiency, `qe` module)."""
    sites = site_map(pattern, image.shape[:2])
    out = np.zeros(image.shape[:2], dtype=np.float64)
    for index in range(len(FILTERS)):
        here = sites == index
        if here.any():
            out[here] = image[here] @ weights[index]
    return out
