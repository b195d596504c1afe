"""Synthetic slanted-edge targets: exact pixel integrals, analytic MTF50, options."""

import math

import numpy as np
import pytest
from scipy.special import ndtr

from solas_mi.errors import SolasError
from solas_mi.imageio import srgb_decode
from solas_mi.metrics.targets import Square, analytic_mtf, analytic_mtf50, slanted_edge, slanted_squares


@pytest.mark.parametrize("sigma, expected", [(0.5, 0.323111), (1.0, 0.179965), (2.0, 0.092732), (3.0, 0.062176)])
def test_analytic_mtf50_matches_spec_values_at_5_degrees(sigma, expected):
    assert analytic_mtf50(sigma, 5.0) == pytest.approx(expected, abs=1e-6)


def test_analytic_mtf50_is_a_root_of_the_mtf():
    f50 = analytic_mtf50(1.3, 17.0)
    assert float(analytic_mtf(f50, 1.3, 17.0)) == pytest.approx(0.5, abs=1e-9)
    # it is the first crossing: the MTF is above 0.5 everywhere below it
    assert np.all(analytic_mtf(np.linspace(0, f50 * 0.999, 200), 1.3, 17.0) > 0.5)


def brute_force(shape, angle_deg, sigma, sub=200):
    """Mean of the blurred step over each pixel by midpoint supersampling (sub² samples)."""
    rows, cols = shape
    t = math.radians(angle_deg)
    offs = (np.arange(sub) + 0.5) / sub - 0.5
    out = np.empty(shape)
    for i in range(rows):
        y = i + offs[:, None]
        for j in range(cols):
            x = j + offs[None, :]
            n = (x - (cols - 1) / 2) * math.cos(t) - (y - (rows - 1) / 2) * math.sin(t)
            out[i, j] = np.mean(ndtr(n / sigma) if sigma > 0 else (n > 0).astype(float))
    return out


@pytest.mark.parametrize("angle, sigma", [(5.0, 1.0), (33.0, 0.4), (0.0, 0.8), (90.0, 1.5), (12.0, 0.0)])
def test_pixel_values_are_exact_pixel_integrals(angle, sigma):
    exact = slanted_edge((12, 12), angle, sigma, low=0.0, high=1.0, clip=False)
    # midpoint rule with 200² samples: error well under 1e-4 except at the discontinuity (σ = 0)
    tol = 3e-3 if sigma == 0 else 1e-4
    assert np.max(np.abs(exact - brute_force((12, 12), angle, sigma))) < tol


def test_far_from_edge_is_exactly_the_levels_and_symmetric():
    img = slanted_edge((64, 64), 7.0, 1.0, low=0.0, high=1.0, clip=False)
    assert img[:, 0].max() < 1e-12 and img[:, -1].min() > 1 - 1e-12
    # point symmetry about the image centre: value(n) + value(−n) = 1
    assert np.max(np.abs(img + img[::-1, ::-1] - 1.0)) < 1e-12


def test_noise_level_and_seed():
    a = slanted_edge((128, 128), 5.0, 1.0, low=0.2, high=0.8, noise=0.05, seed=3)
    b = slanted_edge((128, 128), 5.0, 1.0, low=0.2, high=0.8, noise=0.05, seed=3)
    clean = slanted_edge((128, 128), 5.0, 1.0, low=0.2, high=0.8)
    assert np.array_equal(a, b)
    assert np.std(a - clean) == pytest.approx(0.05 * 0.6, rel=0.05)


def test_clipping_and_encoding_options():
    clipped = slanted_edge((32, 32), 5.0, 1.0, low=0.2, high=1.3)
    assert clipped.max() == 1.0 and np.mean(clipped == 1.0) > 0.3
    unclipped = slanted_edge((32, 32), 5.0, 1.0, low=0.2, high=1.3, clip=False)
    assert unclipped.max() == pytest.approx(1.3)
    lin = slanted_edge((32, 32), 5.0, 1.0)
    enc8 = slanted_edge((32, 32), 5.0, 1.0, encoding="srgb", bit_depth=8)
    assert enc8.dtype == np.uint8
    assert np.max(np.abs(srgb_decode(enc8 / 255.0) - lin)) < 0.01
    enc16 = slanted_edge((32, 32), 5.0, 1.0, encoding="srgb", bit_depth=16)
    assert enc16.dtype == np.uint16
    assert np.max(np.abs(srgb_decode(enc16 / 65535.0) - lin)) < 1e-4


def test_squares_levels_and_overlap_check():
    img = slanted_squares(
        (120, 160), [Square(50, 60, 40, 10, 1.0, 0.1), Square(115, 60, 30, -5, 2.0, 0.5)], background=0.7
    )
    assert img[60, 50] == pytest.approx(0.1, abs=1e-6)
    assert img[60, 115] == pytest.approx(0.5, abs=1e-6)
    assert img[5, 5] == pytest.approx(0.7, abs=1e-12)
    with pytest.raises(SolasError, match="overlap"):
        slanted_squares((100, 100), [Square(40, 50, 40, 0, 1, 0.1), Square(60, 50, 40, 0, 1, 0.1)])


@pytest.mark.parametrize(
    "kwargs",
    [
        {"shape": (4, 100)},
        {"sigma_px": -1.0},
        {"noise": -0.1},
        {"encoding": "gamma22"},
        {"bit_depth": 12},
    ],
)
def test_bad_parameters_raise(kwargs):
    with pytest.raises(SolasError):
        slanted_edge(**kwargs)
