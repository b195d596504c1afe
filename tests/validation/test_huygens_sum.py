"""The optiland bench's third route (`benchmarks/huygens.py`): its float32 Dr.Jit Huygens-Fresnel sum
against a float64 NumPy sum of the same wavelets with the distances taken directly, and against the
Airy pattern of a uniform spherical wave."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import huygens

RADIUS_MM = 50.0
WAVELENGTH_MM = 587.6e-6
NA = 0.25


def disc(samples: int):
    """Unit directions (x, y) of a square grid over a disc of sine NA, and the grid's pitch."""
    a = np.linspace(-NA, NA, samples)
    nx, ny = np.meshgrid(a, a)
    inside = np.hypot(nx, ny) <= NA
    return nx[inside], ny[inside], a[1] - a[0]


def direct(n_x, n_y, weight, x, y) -> np.ndarray:
    """|U|^2 in float64 with each distance |P - Q| taken as it is (P = (x, y, 0), Q = R n)."""
    q = RADIUS_MM * np.stack([n_x, n_y, -np.sqrt(1 - n_x**2 - n_y**2)], axis=-1)
    gx, gy = np.meshgrid(x, y)
    p = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=-1)
    d = np.linalg.norm(p[:, None] - q[None], axis=-1)
    u = (np.exp(2j * np.pi * (d - RADIUS_MM) / WAVELENGTH_MM) / d) @ weight
    return (np.abs(u) ** 2).reshape(len(y), len(x))


def test_float32_sum_matches_the_direct_float64_sum(monkeypatch):
    # many waves of phase across the window (d - R up to ~50 waves), an aberrated pupil, several kernel
    # launches and a pupil that is not a whole number of turns
    monkeypatch.setattr(huygens, "CHUNK", 256)
    n_x, n_y, _ = disc(41)
    assert len(n_x) % huygens.UNROLL and len(n_x) > 2 * huygens.CHUNK
    rng = np.random.default_rng(1)
    weight = np.exp(2j * np.pi * 3.0 * (n_x / NA) ** 3) * rng.uniform(0.5, 1.0, len(n_x))
    x = np.linspace(-0.03, 0.05, 17)
    y = np.linspace(-0.04, 0.04, 13)
    mine = huygens.huygens_intensity(n_x, n_y, weight, RADIUS_MM, WAVELENGTH_MM, x, y)
    want = direct(n_x, n_y, weight, x, y)
    assert np.abs(mine - want).max() <= 1e-4 * want.max()


def test_uniform_spherical_wave_gives_the_airy_pattern():
    scipy_special = pytest.importorskip("scipy.special")
    n_x, n_y, _ = disc(121)
    lam_n = WAVELENGTH_MM / (2 * NA)
    x = np.linspace(0.0, 4 * lam_n, 25)
    row = huygens.huygens_intensity(n_x, n_y, np.ones(len(n_x)), RADIUS_MM, WAVELENGTH_MM, x, np.zeros(1))[0]
    v = 2 * np.pi * NA * x[1:] / WAVELENGTH_MM
    airy = np.concatenate([[1.0], (2 * scipy_special.j1(v) / v) ** 2])
    # the disc's staircase rim and the sphere's obliquity (NA 0.25) leave about 1e-3 of the peak
    assert np.abs(row / row[0] - airy).max() < 3e-3
