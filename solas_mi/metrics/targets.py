"""Synthetic slanted-edge targets with a known MTF: Gaussian PSF, 100 % fill-factor square pixels.

Analytic MTF of the straight edge (ISO 12233 test, spec §3), f in cy/px along the edge normal:
    MTF(f) = exp(−2π²σ²f²) · |sinc(f cos θ) · sinc(f sin θ)|
Pixel (i, j) covers x ∈ [j − ½, j + ½], y ∈ [i − ½, i + ½] (px); row 0 is the top.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq
from scipy.special import ndtr

from ..errors import SolasError
from ..imageio import srgb_encode

ENCODINGS = ("linear", "srgb")
_SMALL = 1e-6  # pixel-footprint spread below which the 1-D pixel integral is used


def analytic_mtf(freq: np.ndarray | float, sigma_px: float, angle_deg: float) -> np.ndarray:
    """MTF of the target edge at `freq` cy/px along the edge normal (Gaussian σ in px, tilt in degrees)."""
    f = np.asarray(freq, dtype=np.float64)
    t = math.radians(angle_deg)
    return np.exp(-2.0 * np.pi**2 * sigma_px**2 * f**2) * np.abs(np.sinc(f * math.cos(t)) * np.sinc(f * math.sin(t)))


def analytic_mtf50(sigma_px: float, angle_deg: float, level: float = 0.5) -> float:
    """Where the analytic MTF of a target edge falls to a level: its MTF50 by default.

    MTF(f) = exp(−2π²σ²f²) · |sinc(f cos θ) · sinc(f sin θ)| (this module's docstring), solved by root
    finding.

    Parameters
    ----------
    sigma_px : float
        The Gaussian PSF's σ (px).
    angle_deg : float
        The edge's tilt θ (degrees).
    level : float, default 0.5
        The MTF level.

    Returns
    -------
    float
        The first frequency (cy/px along the edge normal) where the MTF falls to `level`.

    Raises
    ------
    SolasError
        Where the MTF stays above `level` up to 2 cy/px.

    Examples
    --------
    >>> from solas_mi.metrics import analytic_mtf50
    >>> round(analytic_mtf50(1.0, 5.0), 4)
    0.18
    """
    grid = np.linspace(0.0, 2.0, 4001)
    below = np.flatnonzero(analytic_mtf(grid, sigma_px, angle_deg) < level)
    if below.size == 0:
        raise SolasError(f"the analytic MTF stays above {level} up to 2 cy/px")
    hi = grid[below[0]]
    return float(brentq(lambda f: float(analytic_mtf(f, sigma_px, angle_deg)) - level, hi - 5e-4, hi, xtol=1e-12))


def _step_double_integral(n: np.ndarray, sigma: float) -> np.ndarray:
    """Second antiderivative in n (px²) of the blurred step Φ(n/σ), vanishing at n → −∞."""
    if sigma == 0.0:
        return 0.5 * np.maximum(n, 0.0) ** 2
    u = n / sigma
    return sigma**2 * (0.5 * (u * u + 1.0) * ndtr(u) + 0.5 * u * np.exp(-0.5 * u * u) / math.sqrt(2 * math.pi))


def _step_single_integral(n: np.ndarray, sigma: float) -> np.ndarray:
    """Antiderivative in n (px) of Φ(n/σ), vanishing at n → −∞."""
    if sigma == 0.0:
        return np.maximum(n, 0.0)
    u = n / sigma
    return sigma * (u * ndtr(u) + np.exp(-0.5 * u * u) / math.sqrt(2 * math.pi))


def _pixel_integrated_step(n0: np.ndarray, a: float, b: float, sigma: float) -> np.ndarray:
    """Mean of Φ(n/σ) over a unit pixel whose centre lies n0 px from the edge; a = |cos θ|, b = |sin θ|.

    Over the pixel, n = n0 + a·u + b·v with u, v uniform in [−½, ½]; the mean is an exact second
    difference of the double antiderivative. Computed for −|n0| and mirrored (Φ(−u) = 1 − Φ(u))
    so that no large values cancel.
    """
    m = -np.abs(n0)
    a, b = max(a, b), min(a, b)
    if b < _SMALL:
        v = (_step_single_integral(m + a / 2, sigma) - _step_single_integral(m - a / 2, sigma)) / a
    else:
        g = _step_double_integral
        v = (
            g(m + (a + b) / 2, sigma)
            - g(m + (a - b) / 2, sigma)
            - g(m - (a - b) / 2, sigma)
            + g(m - (a + b) / 2, sigma)
        ) / (a * b)
    return np.where(n0 > 0, 1.0 - v, v)


def _finish(
    field_: np.ndarray,
    low: float,
    high: float,
    noise: float,
    seed: int | None,
    clip: bool,
    encoding: str,
    bit_depth: int | None,
) -> np.ndarray:
    """Map a [0, 1] edge field to levels, add noise (sd = noise·(high − low)), clip, encode, quantise."""
    if encoding not in ENCODINGS:
        raise SolasError(f"encoding {encoding!r} is not supported: allowed {', '.join(ENCODINGS)}")
    if bit_depth not in (None, 8, 16):
        raise SolasError(f"bit depth {bit_depth} is not supported: allowed None (float), 8, 16")
    if not (isinstance(noise, (int, float)) and 0 <= noise < math.inf):
        raise SolasError(f"noise {noise!r} must be a finite number ≥ 0 (sd as a fraction of the step)")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise SolasError(f"noise seed {seed!r} must be a whole number ≥ 0 (or none: a fresh one)")
    img = low + (high - low) * field_
    if noise > 0:
        img = img + np.random.default_rng(seed).normal(0.0, noise * abs(high - low), img.shape)
    if clip or encoding == "srgb" or bit_depth is not None:
        img = np.clip(img, 0.0, 1.0)
    if encoding == "srgb":
        img = srgb_encode(img)
    if bit_depth is not None:
        full = 2**bit_depth - 1
        img = np.round(img * full).astype(np.uint8 if bit_depth == 8 else np.uint16)
    return img


def _check_common(shape: tuple[int, int], sigma_px: float) -> None:
    if len(shape) != 2 or min(shape) < 8:
        raise SolasError(f"target shape {shape} is too small: need (rows, columns), both ≥ 8 px")
    if not sigma_px >= 0:
        raise SolasError(f"sigma {sigma_px} px must be ≥ 0")


# many parameters: a synthetic target's independent knobs (geometry, blur, levels, noise, clipping, encoding), each
# with its default and keyword-only past the first three: a caller sets the few it varies
# long: the public API's numpydoc docstring is half of it
def slanted_edge(
    shape: tuple[int, int] = (128, 128),
    angle_deg: float = 5.0,
    sigma_px: float = 1.0,
    *,
    offset_px: float = 0.0,
    low: float = 0.2,
    high: float = 0.8,
    noise: float = 0.0,
    seed: int | None = None,
    clip: bool = True,
    encoding: str = "linear",
    bit_depth: int | None = None,
) -> np.ndarray:
    """A straight edge blurred by a Gaussian PSF and integrated exactly over each pixel: a known MTF.

    Parameters
    ----------
    shape : (int, int), default (128, 128)
        (rows, columns) px, each at least 8.
    angle_deg : float, default 5.0
        The edge turned this far counter-clockwise from vertical as displayed (row 0 at the top): its top
        end leans left (90°: horizontal, bright side up).
    sigma_px : float, default 1.0
        The Gaussian PSF's σ (px).
    offset_px : float, default 0.0
        The edge passes this far right of the image centre.
    low, high : float, default 0.2, 0.8
        Linear levels: left/bottom, and the other side.
    noise : float, default 0.0
        Gaussian noise's sd as a fraction of the step.
    seed : int, optional
        The noise's seed.
    clip : bool, default True
        Clip to [0, 1].
    encoding : str, default "linear"
        One of `ENCODINGS`: "srgb" encodes the linear values.
    bit_depth : int, optional
        8 or 16: quantise to unsigned integers.

    Returns
    -------
    numpy.ndarray
        (rows, columns) values; integers with `bit_depth`.

    Raises
    ------
    SolasError
        For a shape under 8×8 px, a negative σ, or a bad encoding or bit depth.

    Examples
    --------
    >>> from solas_mi.metrics import slanted_edge
    >>> edge = slanted_edge((64, 96), angle_deg=5.0, sigma_px=1.5)
    >>> edge.shape, round(float(edge.min()), 2), round(float(edge.max()), 2)
    ((64, 96), 0.2, 0.8)
    """
    _check_common(shape, sigma_px)
    rows, cols = shape
    t = math.radians(angle_deg)
    y, x = np.mgrid[0:rows, 0:cols].astype(np.float64)
    n0 = (x - (cols - 1) / 2 - offset_px) * math.cos(t) - (y - (rows - 1) / 2) * math.sin(t)
    field_ = _pixel_integrated_step(n0, abs(math.cos(t)), abs(math.sin(t)), sigma_px)
    return _finish(field_, low, high, noise, seed, clip, encoding, bit_depth)


@dataclass(frozen=True)
class Square:
    """A slanted square: centre (x, y) px, side px, rotation degrees, PSF sigma px, inside level."""

    x: float
    y: float
    side: float
    angle_deg: float
    sigma_px: float
    level: float


def slanted_squares(
    shape: tuple[int, int],
    squares: Sequence[Square],
    *,
    background: float = 0.8,
    noise: float = 0.0,
    seed: int | None = None,
    clip: bool = True,
    encoding: str = "linear",
    bit_depth: int | None = None,
    supersample: int = 8,
) -> np.ndarray:
    """Squares on a uniform background (linear level), each blurred by its own Gaussian PSF (σ px).

    `shape` is (rows, columns) px. The blurred square is exact at a point (the isotropic Gaussian
    separates along the square's own axes); the pixel area is integrated with supersample² sub-pixel
    samples. noise: Gaussian sd in linear units; clip, encoding, bit_depth as in `slanted_edge`.
    """
    _check_common(shape, 0.0)
    if supersample < 1:
        raise SolasError(f"supersample {supersample} must be ≥ 1")
    rows, cols = shape
    field_ = np.zeros(shape)
    weight = np.zeros(shape)
    sub = (np.arange(supersample) + 0.5) / supersample - 0.5
    for sq in squares:
        if not sq.sigma_px >= 0 or sq.side <= 0:
            raise SolasError(f"square {sq}: sigma must be ≥ 0 px and side > 0 px")
        reach = sq.side * math.sqrt(0.5) + 6 * sq.sigma_px + 2
        r0, r1 = max(0, int(sq.y - reach)), min(rows, int(sq.y + reach) + 2)
        c0, c1 = max(0, int(sq.x - reach)), min(cols, int(sq.x + reach) + 2)
        if r0 >= r1 or c0 >= c1:
            continue
        yy = (np.arange(r0, r1)[:, None] + sub[None, :]).reshape(-1)
        xx = (np.arange(c0, c1)[:, None] + sub[None, :]).reshape(-1)
        t = math.radians(sq.angle_deg)
        dx, dy = xx[None, :] - sq.x, yy[:, None] - sq.y
        u = dx * math.cos(t) + dy * math.sin(t)
        v = -dx * math.sin(t) + dy * math.cos(t)
        h = sq.side / 2
        s = max(sq.sigma_px, 1e-9)
        inside = (ndtr((h - u) / s) - ndtr((-h - u) / s)) * (ndtr((h - v) / s) - ndtr((-h - v) / s))
        inside = inside.reshape(r1 - r0, supersample, c1 - c0, supersample).mean(axis=(1, 3))
        field_[r0:r1, c0:c1] += inside * (sq.level - background)
        weight[r0:r1, c0:c1] += inside
    if weight.max() > 1.0 + 1e-9:
        raise SolasError("squares overlap: place them at least 6 sigma apart")
    return _finish(field_ + background, 0.0, 1.0, noise, seed, clip, encoding, bit_depth)
