"""Zernike polynomials over the unit disc (ρ ≤ 1, θ from +x toward +y) and their least-squares fit.

Two orders and normalisations:

- "fringe" (University of Arizona): terms grouped by (n + |m|)/2, within a group by falling |m|, cos
  before sin, j = (1 + (n + |m|)/2)² − 2|m| + (1 − sign m)/2; not normalised (each is 1 at the rim at
  θ = 0 for cos terms): Z1 = 1, Z2 = ρ cos θ, Z3 = ρ sin θ, Z4 = 2ρ² − 1, …, Z9 = 6ρ⁴ − 6ρ² + 1, …,
  Z36 = ρ¹⁰ spherical; Z1–Z36 as Zemax's Fringe and optiland's ZernikeFringe (Z37 is (6, 6) here and in
  optiland, 12th-order spherical in Zemax);
- "noll" (R. J. Noll, JOSA 66 (1976) 207; Zemax's Standard): ordered by n, then |m|, even j cos and odd
  j sin, each normalised to unit RMS over the disc: √(n+1) for m = 0, √(2(n+1)) otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError
from .options import ZERNIKE_KINDS


def fringe_index(j: int) -> tuple[int, int]:
    """(n, m) of Fringe term j (1-based); m > 0: cos mθ, m < 0: sin |m|θ."""
    count = 0
    group = 0
    while True:
        for m in range(group, -1, -1):
            for sign in (1, -1) if m else (1,):
                count += 1
                if count == j:
                    return 2 * group - m, sign * m
        group += 1


def noll_index(j: int) -> tuple[int, int]:
    """(n, m) of Noll term j (1-based); m > 0: cos mθ, m < 0: sin |m|θ."""
    n, rest = 0, j - 1
    while rest > n:
        n += 1
        rest -= n
    m = (n % 2) + 2 * ((rest + ((n + 1) % 2)) // 2)
    return n, m if j % 2 == 0 else -m


def radial(n: int, m: int, rho: np.ndarray) -> np.ndarray:
    """R_n^|m|(ρ) = Σ_k (−1)^k (n−k)! / (k! ((n+|m|)/2−k)! ((n−|m|)/2−k)!) ρ^(n−2k)."""
    m = abs(m)
    out = np.zeros_like(rho, dtype=np.float64)
    for k in range((n - m) // 2 + 1):
        c = (
            (-1) ** k
            * math.factorial(n - k)
            / (math.factorial(k) * math.factorial((n + m) // 2 - k) * math.factorial((n - m) // 2 - k))
        )
        out += c * rho ** (n - 2 * k)
    return out


def indices(kind: str, terms: int) -> list[tuple[int, int]]:
    """(n, m) of terms 1 … `terms` of `kind`."""
    if kind not in ZERNIKE_KINDS:
        raise SolasError(f"Zernike kind {kind!r} must be one of {', '.join(ZERNIKE_KINDS)}")
    if not isinstance(terms, int) or isinstance(terms, bool) or not 1 <= terms <= 231:
        raise SolasError(f"Zernike terms {terms!r} must be a whole number from 1 to 231")
    index = fringe_index if kind == "fringe" else noll_index
    return [index(j) for j in range(1, terms + 1)]


def polynomial(kind: str, n: int, m: int, rho: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """The term (n, m) of `kind` at (ρ, θ)."""
    value = radial(n, m, rho) * (np.cos(m * theta) if m > 0 else np.sin(-m * theta) if m < 0 else 1.0)
    if kind == "noll":
        value = value * math.sqrt((n + 1) * (1 if m == 0 else 2))
    return value


def fit(kind: str, terms: int, x: np.ndarray, y: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Least-squares coefficients of terms 1 … `terms` of `kind` for `values` at pupil points (x, y)
    (normalised, inside the unit disc)."""
    rho, theta = np.hypot(x, y), np.arctan2(y, x)
    basis = np.stack([polynomial(kind, n, m, rho, theta) for n, m in indices(kind, terms)], axis=1)
    coefficients, *_ = np.linalg.lstsq(basis, values, rcond=None)
    return coefficients
