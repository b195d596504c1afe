"""Forbes' Q-type asphere polynomials (G. W. Forbes, Opt. Express 15, 5218 (2007); the recurrences of
Opt. Express 18, 19700 (2010)).

- Qbfs ("best-fit sphere", slope-orthonormal): the departure u²(1 − u²) Σ a_m Q_m^bfs(u²), u = r/ρ
  (ρ the normalisation radius), measured along the base conic's normal (Forbes 2011's conic form, the
  factor φ below; φ = 1/√(1 − c²r²) for a sphere, the 2007 form). `qbfs_sum` gives Σ a_m Q_m^bfs(x)
  and its x-derivative with only +, −, × and ÷ by numbers, so it runs on NumPy and Dr.Jit arrays alike.
- Qcon: u⁴ Σ a_m Q_m^con(u²), Q_m^con(x) = P_m^(0,4)(2x − 1) (Jacobi), a polynomial in r², so
  `qcon_to_even` rewrites it exactly as even-asphere terms A4, A6, … .
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np


@cache
def _fgh(m: int) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """Forbes 2010's f_0…f_m, g_0…g_(m−1), h_0…h_(m−2) (Q_m = (P_m − g_(m−1) Q_(m−1) − h_(m−2) Q_(m−2)) / f_m)."""
    f, g, h = [2.0, math.sqrt(19.0) / 2.0], [-0.5], []
    for n in range(2, m + 1):
        h.append(-n * (n - 1) / (2.0 * f[n - 2]))
        g.append(-(1.0 + g[n - 2] * h[n - 2]) / f[n - 1])
        f.append(math.sqrt(n * (n + 1) + 3.0 - g[n - 1] ** 2 - h[n - 2] ** 2))
    return tuple(f), tuple(g), tuple(h)


def qbfs_sum(x, coefficients: tuple[float, ...]):
    """(Σ a_m Q_m^bfs(x), its derivative d/dx) for x = u² (any array type, or a float)."""
    f, g, h = _fgh(max(len(coefficients) - 1, 1))
    p_prev, dp_prev = 0.0 * x + 2.0, 0.0 * x  # P_0 = 2
    p, dp = 6.0 - 8.0 * x, 0.0 * x - 8.0  # P_1 = 6 − 8x
    q = [(p_prev / f[0], dp_prev / f[0])]
    for m in range(1, len(coefficients)):
        if m > 1:  # P_m = (2 − 4x) P_(m−1) − P_(m−2)
            p, p_prev, dp, dp_prev = ((2.0 - 4.0 * x) * p - p_prev, p, (2.0 - 4.0 * x) * dp - 4.0 * p - dp_prev, dp)
        qm, dqm = p - g[m - 1] * q[-1][0], dp - g[m - 1] * q[-1][1]
        if m > 1:
            qm, dqm = qm - h[m - 2] * q[-2][0], dqm - h[m - 2] * q[-2][1]
        q.append((qm / f[m], dqm / f[m]))
    total, slope = 0.0 * x, 0.0 * x
    for a, (qm, dqm) in zip(coefficients, q):
        total, slope = total + a * qm, slope + a * dqm
    return total, slope


def qbfs_departure(
    r2,
    curvature: float,
    conic: float,
    coefficients: tuple[float, ...],
    norm_radius: float,
    sqrt=np.sqrt,
    maximum=np.maximum,
):
    """(Qbfs departure z (mm), its derivative dz/d(r²)) at squared radius r2 (mm²): φ x(1 − x) S(x),
    x = r²/ρ², φ = √((1 − k c² r²)/(1 − (1 + k) c² r²)), the inverse z-component of the base conic's normal."""
    c2 = curvature * curvature
    inv = 1.0 / (norm_radius * norm_radius)
    x = r2 * inv
    s, ds = qbfs_sum(x, coefficients)
    below = maximum(1.0 - (1.0 + conic) * c2 * r2, 1e-300)
    phi = sqrt(maximum(1.0 - conic * c2 * r2, 0.0) / below)
    dphi = 0.5 * c2 / (maximum(phi, 1e-300) * below * below)
    poly = x * (1.0 - x)
    return phi * poly * s, dphi * poly * s + phi * inv * ((1.0 - 2.0 * x) * s + poly * ds)


def _jacobi_0_4(m: int) -> list[np.ndarray]:
    """Power-series coefficients in x of Q_n^con(x) = P_n^(0,4)(2x − 1), n = 0…m (lowest power first)."""
    t = np.polynomial.Polynomial([-1.0, 2.0])  # 2x − 1
    polys = [np.polynomial.Polynomial([1.0]), 3.0 * t - 2.0]  # P_1^(0,β) = ((β + 2) t − β)/2 with β = 4 → 3t − 2
    a, b = 0.0, 4.0
    for n in range(2, m + 1):  # the three-term recurrence of Jacobi polynomials
        c1 = 2 * n * (n + a + b) * (2 * n + a + b - 2)
        c2 = (2 * n + a + b - 1) * (a * a - b * b)
        c3 = (2 * n + a + b - 2) * (2 * n + a + b - 1) * (2 * n + a + b)
        c4 = 2 * (n + a - 1) * (n + b - 1) * (2 * n + a + b)
        polys.append(((c2 + c3 * t) * polys[n - 1] - c4 * polys[n - 2]) / c1)
    return [p.coef for p in polys[: m + 1]]


def qcon_to_even(coefficients: tuple[float, ...], norm_radius: float) -> list[float]:
    """Even-asphere terms [A4, A6, …] (mm^(1−2i)) equal to the Qcon departure u⁴ Σ a_m Q_m^con(u²)."""
    if not coefficients:
        return []
    powers = np.zeros(len(coefficients))
    for a, series in zip(coefficients, _jacobi_0_4(len(coefficients) - 1)):
        powers[: len(series)] += a * series
    return [float(p) / norm_radius ** (4 + 2 * j) for j, p in enumerate(powers)]


__all__ = ["qbfs_sum", "qbfs_departure", "qcon_to_even"]
