"""A rotationally symmetric surface's sag and its slope: the conic, the even-asphere terms and Forbes'
Qbfs departure (`forbes`), for NumPy and Dr.Jit arrays alike (the tracer, the mesh scene, the lens's
checks). The formula is stated in `lens`'s docstring."""

from __future__ import annotations

import numpy as np

from . import forbes

ASPHERE_ITERATIONS = 8  # Newton steps from the conic root; quadratic convergence reaches Float64 rounding
ASPHERE_TOL_MM = 1e-7  # a ray whose residual |z − sag| stays above this misses the asphere (every tracer)


def sag(
    r2,
    curvature: float,
    conic: float = 0.0,
    aspheric: tuple[float, ...] = (),
    sqrt=np.sqrt,
    maximum=np.maximum,
    qbfs: tuple[float, ...] = (),
    norm_radius: float = 1.0,
):
    """Asphere sag z (mm) at squared radial distance r2 (mm²), for any array type given its `sqrt`
    and `maximum` (NumPy, Dr.Jit); beyond a conic's rim (1 − (1 + k) c² r² < 0) the root is taken as 0."""
    c = curvature
    z = c * r2 / (1.0 + sqrt(maximum(1.0 - (1.0 + conic) * c * c * r2, 0.0)))
    power = r2 * r2
    for a in aspheric:
        z = z + a * power
        power = power * r2
    if any(qbfs):
        z = z + forbes.qbfs_departure(r2, c, conic, qbfs, norm_radius, sqrt, maximum)[0]
    return z


def sag_slope(
    r2,
    curvature: float,
    conic: float = 0.0,
    aspheric: tuple[float, ...] = (),
    sqrt=np.sqrt,
    maximum=np.maximum,
    qbfs: tuple[float, ...] = (),
    norm_radius: float = 1.0,
):
    """dz/d(r²) of `sag` (1/mm): the surface normal is (−2x·s', −2y·s', 1), normalised."""
    c = curvature
    slope = 0.5 * c / sqrt(maximum(1.0 - (1.0 + conic) * c * c * r2, 1e-300))
    power = r2
    for i, a in enumerate(aspheric, start=2):
        slope = slope + i * a * power
        power = power * r2
    if any(qbfs):
        slope = slope + forbes.qbfs_departure(r2, c, conic, qbfs, norm_radius, sqrt, maximum)[1]
    return slope


__all__ = ["sag", "sag_slope", "ASPHERE_ITERATIONS", "ASPHERE_TOL_MM"]
