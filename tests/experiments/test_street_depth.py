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
    assert z[1, 3] == pytest.approx(10.0 / math.sqrt(1 + 0.75**2 + 0.25**2))


def test_render_noise_is_removed_in_quadrature():
    rng = np.random.default_rng(0)
    ref = rng.random((200, 200)) + 1
    n1, n2 = rng.normal(0, 0.05, (2, *ref.shape))  # two seeds: the mean's noise variance is 0.05² / 2
    near = np.zeros(ref.shape, bool)
    near[:50] = True
    e = denoised_errors(ref + 0.02 * rng.normal(size=ref.shape), (ref + n1, ref + n2), near, ~near)
    rms = math.sqrt(np.mean(ref**2))
    assert e["rel_rmse_all"] == pytest.approx(0.02 / rms, rel=0.05)  # the render noise is gone
    assert e["rel_rmse_all_raw"] == pytest.approx(math.sqrt(0.02**2 + 0.05**2 / 2) / rms, rel=0.05)
    assert e["near_pixels"] == 10000


def test_layer_counts_must_nest():
    assert check_layers((1, 2, 4, 8, 16)) == (1, 2, 4, 8, 16)
    for bad in ((3, 4), (), (2, 1), (0, 2)):
        with pytest.raises(SolasError, match="depth layers"):
            check_layers(bad)


def test_a_refocused_render_is_in_its_own_focus_unit(doublet, variant_scalar_spectral):
    """The lens camera's unit is the lossless lens's on-axis irradiance at its focus (the exit pupil's
    solid angle seen from the film centre, integrated over the pupil): refocused at 20 m, the doublet's
    film lies 1.3 % further from the exit pupil and its unit is 2.5 % less, which the paraxial ratio
    (N/N')² gives to 1e-3 (the convolution divided by the file focus's unit came out 2.4 % dark)."""
    from solas_mi.plugins.lens_camera import on_axis_solid_angle
    from solas_mi.plugins.pupil_sampling import PupilSampler

    from solas_mi.experiments.street.depth import focus_unit
    from solas_mi.optics.focus import focused

    lenses = (doublet, focused(doublet, 20e3))
    omega = [on_axis_solid_angle(lens, PupilSampler(lens, 0.5, [531.0]), 531.0) for lens in lenses]
    assert focus_unit(*lenses, 531.0) == pytest.approx(omega[1] / omega[0], rel=1e-3)
    assert omega[1] / omega[0] < 0.98
