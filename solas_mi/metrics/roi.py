"""The ROI an e-SFR measures: its box, its values and the test that it holds one step edge.

A ROI is (x, y, w, h) in px: top-left corner (column, row), width and height. Values are linear in
scene luminance; `luminance` reduces a colour ROI to one plane. The step-edge test is the one the
natural-scene SFR (nssfr) uses to reject lines, texture and double edges (spec §4.4); `esfr` applies
it to every ROI.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy import ndimage as ndi

from ..errors import SolasError

Roi = tuple[int, int, int, int]

LUMA_WEIGHTS = (0.213, 0.715, 0.072)
MIN_ROI_PX = 8  # px, the shortest ROI side
STEP_ROW_LIMIT = 0.5  # fraction of rows that must be single steps
STEP_THRESHOLD = 0.02  # gradient run threshold, fraction of the step per px
STEP_SMOOTHING_PX = (2.0, 1.5)  # Gaussian sd (rows, columns) of the step test's gradient


def linear_pixels(image, what: str) -> np.ndarray:
    """`image` (H×W, H×W×1, H×W×3 or H×W×4) as an array of finite linear floats at least MIN_ROI_PX a side, or a
    SolasError naming `what` ("ROI", "image") and what is wrong with it."""
    data = np.asarray(image)
    if not np.issubdtype(data.dtype, np.floating):
        raise SolasError(
            f"{what} has {data.dtype} values: pass linear floats (decode integer sRGB images with "
            "solas_mi.imageio.read_image or srgb_decode)"
        )
    if data.ndim < 2 or min(data.shape[:2]) < MIN_ROI_PX:
        raise SolasError(f"{what} shape {data.shape} is too small: both sides must be ≥ {MIN_ROI_PX} px")
    if data.ndim > 3 or (data.ndim == 3 and data.shape[2] not in (1, 3, 4)):
        raise SolasError(f"{what} shape {data.shape} is not H×W, H×W×1, H×W×3 or H×W×4")
    if not np.all(np.isfinite(data)):
        raise SolasError(f"{what} holds NaN or infinite values: only finite pixel values are allowed")
    return data


def is_grey(image: np.ndarray) -> bool:
    """Whether an image (H×W, H×W×1, H×W×3 or H×W×4) has one channel, no colour ones."""
    return image.ndim == 2 or image.shape[2] == 1


def luminance(image: np.ndarray, channel: int | None = None) -> np.ndarray:
    """2-D float64 luminance Y = 0.213 R + 0.715 G + 0.072 B of linear values (H×W, H×W×1, H×W×3 or
    H×W×4: alpha is ignored), or one channel (0 R, 1 G, 2 B) of a colour image."""
    a = np.asarray(image, dtype=np.float64)
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (1, 3, 4)):
        raise SolasError(f"image shape {a.shape} is not H×W, H×W×1, H×W×3 or H×W×4")
    if channel is not None and is_grey(a):
        raise SolasError(
            f"channel {channel} asked of a grey image (one channel): it has no colour channels; "
            "measure its grey values (no channel)"
        )
    if channel is not None:
        if not 0 <= channel < 3:
            raise SolasError(f"channel {channel} does not exist: allowed 0…2")
        return a[:, :, channel]
    if is_grey(a):
        return a.reshape(a.shape[:2])
    return a[:, :, 0] * LUMA_WEIGHTS[0] + a[:, :, 1] * LUMA_WEIGHTS[1] + a[:, :, 2] * LUMA_WEIGHTS[2]


def clipped_fraction(image: np.ndarray, full_scale: float | None) -> float:
    """Fraction (0–1) of pixels with any colour channel at or below 0 or at or above `full_scale` (the
    saturation level in the image's units; None: no upper limit)."""
    a = np.asarray(image, dtype=np.float64)
    bad = a <= 0.0
    if full_scale is not None:
        bad |= a >= full_scale
    if a.ndim == 3:
        bad = bad[:, :, :3].any(axis=2)
    return float(bad.mean())


def crop(image: np.ndarray, roi: Roi) -> np.ndarray:
    """The ROI (x, y, w, h) in px of an image; SolasError if it leaves the image."""
    x, y, w, h = roi
    height, width = image.shape[:2]
    if w < MIN_ROI_PX or h < MIN_ROI_PX:
        raise SolasError(f"ROI {x},{y},{w},{h} is too small: width and height must be ≥ {MIN_ROI_PX} px")
    if x < 0 or y < 0 or x + w > width or y + h > height:
        raise SolasError(
            f"ROI {x},{y},{w},{h} leaves the {width}×{height} image: need 0 ≤ x, x+w ≤ {width}, 0 ≤ y, y+h ≤ {height}"
        )
    return image[y : y + h, x : x + w]


def parse_roi(text: str) -> Roi:
    """Parse "x,y,w,h" (non-negative integers, px)."""
    parts = text.split(",")
    try:
        values = tuple(int(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 4 or min(values) < 0:
        raise SolasError(f"--roi {text!r} is malformed: expected x,y,w,h as 4 non-negative integers (px)")
    return values  # type: ignore[return-value]  # four integers, checked above


def _step_filter(a: np.ndarray) -> np.ndarray:
    """Row gradient (per px) smoothed by a Gaussian of STEP_SMOOTHING_PX (rows, columns)."""
    return ndi.gaussian_filter(a, STEP_SMOOTHING_PX, order=(0, 1), mode="nearest")


@functools.lru_cache(maxsize=1)
def _step_noise_gain() -> float:
    """Sd of the smoothed gradient per unit sd of white pixel noise."""
    impulse = np.zeros((41, 41))
    impulse[20, 20] = 1.0
    return float(np.sqrt(np.sum(_step_filter(impulse) ** 2)))


def step_rows(a: np.ndarray, sign: float, noise: float) -> tuple[float, float]:
    """Fractions of rows that are single steps of the edge's sign, and of rows with no gradient run.

    `a` is in units of the step height, `noise` its noise sd in the same units; `sign` is +1 for an
    edge whose values rise along the row (left to right), −1 for a falling one. A row is a step if
    its smoothed gradient has exactly one connected run above the threshold (0.02 of the step per px,
    raised to 4 noise sd on noisy ROIs) and none below minus the threshold.
    """
    g = _step_filter(a) * sign
    threshold = max(STEP_THRESHOLD, 4.0 * _step_noise_gain() * noise)
    pos = g > threshold
    neg = g < -threshold

    def runs(m: np.ndarray) -> np.ndarray:
        return m[:, 0].astype(int) + np.count_nonzero(m[:, 1:] & ~m[:, :-1], axis=1)

    rp, rn = runs(pos), runs(neg)
    return float(np.mean((rp == 1) & (rn == 0))), float(np.mean((rp == 0) & (rn == 0)))
