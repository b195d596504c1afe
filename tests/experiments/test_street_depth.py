"""Step (g) of the street experiment: the helpers whose results can be derived by hand."""
import math

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.experiments.street.depth import axial_depth, check_layers, denoised_errors


def test_axial_depth_is_ray_distance_times_cos():
    d = np.full((2, 4), 10.0)
    d[0, 0] = np.inf
    z = axial_depth(d, 45.0)  # 4 px span ±45°: the corner pixel's tangents (0.75, -0.25)
    assert math.isinf(z[0, 0])
    assert z[1, 3] == pytest.approx(10.0 / math.sqrt(1 + 0.75 ** 2 + 0.25 ** 2))


def test_render_noise_is_removed_in_quadrature():
    rng = np.random.default_rng(0)
    ref = rng.random((200, 200)) + 1
    n1, n2 = rng.normal(0, 0.05, (2, *ref.shape))  # two seeds: the mean's noise variance is 0.05² / 2
    near = np.zeros(ref.shape, bool)
    near[:50] = True
    e = denoised_errors(ref + 0.02 * rng.normal(size=ref.shape), (ref + n1, ref + n2), near, ~near)
    rms = math.sqrt(np.mean(ref ** 2))
    assert e["rel_rmse_all"] == pytest.approx(0.02 / rms, rel=0.05)  # the render noise is gone
    assert e["rel_rmse_all_raw"] == pytest.approx(math.sqrt(0.02 ** 2 + 0.05 ** 2 / 2) / rms, rel=0.05)
    assert e["near_pixels"] == 10000


def test_layer_counts_must_nest():
    assert check_layers((1, 2, 4, 8, 16)) == (1, 2, 4, 8, 16)
    for bad in ((3, 4), (), (2, 1), (0, 2)):
        with pytest.raises(SolasError, match="depth layers"):
            check_layers(bad)
