"""A Huygens-Fresnel sum over a reference sphere in Dr.Jit's LLVM backend (the third route of
bench_optiland.py): U(P) = sum_j w_j e^{ik(d_j - R)} / d_j over wavelets from points Q_j = p0 + R n_j of
a sphere of radius R about the image point p0 to image points P = p0 + delta in the image plane, with
exact distances d_j = |P - Q_j| (no Fraunhofer approximation).

Vectorised over image points, a symbolic loop over the pupil's samples (UNROLL per turn), in float32
with the phase taken without cancellation: |P - Q|^2 = R^2 + s with s = |delta|^2 - 2 R delta . n
(delta in the image plane: delta . n = x n_x + y n_y), so d - R = s / (d + R), reduced to a fraction of a
wave before its sine and cosine; the sums are accumulated in float32 over CHUNK pupil samples (one kernel
launch each, one compiled kernel for all, the bounds opaque) and in float64 over chunks.
"""

from __future__ import annotations

import numpy as np

UNROLL = 4  # pupil samples per turn of the loop
CHUNK = 16384  # pupil samples per kernel launch, summed in float32 (about 1e-5 of their magnitude)


def huygens_intensity(
    n_x: np.ndarray,
    n_y: np.ndarray,
    weight: np.ndarray,
    radius_mm: float,
    wavelength_mm: float,
    x_mm: np.ndarray,
    y_mm: np.ndarray,
) -> np.ndarray:
    """|U|^2 on the grid of image-plane offsets (y_mm rows, x_mm columns) from the sphere's centre, summed
    over wavelets from the sphere's points of unit directions (n_x, n_y, .) with complex weights `weight`
    (the e^{ik(d-R)}/d of each wavelet multiplies its weight)."""
    from solas_mi.llvm import import_drjit

    dr = import_drjit()
    from drjit.llvm import Float, Float64, UInt32

    pad = -len(weight) % UNROLL  # zero weights round the pupil up to whole turns
    two_r = np.concatenate([2.0 * radius_mm * np.stack([n_x, n_y]), np.zeros((2, pad))], axis=1)
    w = np.concatenate([weight, np.zeros(pad)])
    ax, ay, wr, wi = (Float(v.astype(np.float32)) for v in (two_r[0], two_r[1], w.real, w.imag))
    gx, gy = (v.ravel() for v in np.meshgrid(x_mm, y_mm))
    x, y, rho2 = (Float(v.astype(np.float32)) for v in (gx, gy, gx**2 + gy**2))
    r, r2, inv_lam = Float(radius_mm), Float(radius_mm**2), Float(1.0 / wavelength_mm)

    def turn(i, stop, ur, ui):
        for u in range(UNROLL):
            j = i + u
            s = rho2 - dr.fma(x, dr.gather(Float, ax, j), y * dr.gather(Float, ay, j))
            d = dr.sqrt(r2 + s)
            waves = s / (d + r) * inv_lam
            sin, cos = dr.sincos(2.0 * np.pi * (waves - dr.round(waves)))
            a, b, g = dr.gather(Float, wr, j), dr.gather(Float, wi, j), dr.rcp(d)
            ur = dr.fma(a * cos - b * sin, g, ur)
            ui = dr.fma(a * sin + b * cos, g, ui)
        return i + UNROLL, stop, ur, ui

    ur, ui = dr.zeros(Float64, len(gx)), dr.zeros(Float64, len(gx))
    for start in range(0, len(w), CHUNK):
        i = dr.full(UInt32, 0, len(gx)) + dr.opaque(UInt32, start)
        stop = dr.opaque(UInt32, min(start + CHUNK, len(w)))
        zero = dr.zeros(Float, len(gx))
        _, _, vr, vi = dr.while_loop(state=(i, stop, zero, zero), cond=lambda i, stop, ur, ui: i < stop, body=turn)
        ur, ui = ur + Float64(vr), ui + Float64(vi)
        dr.eval(ur, ui)
    return (ur.numpy() ** 2 + ui.numpy() ** 2).reshape(len(y_mm), len(x_mm))
