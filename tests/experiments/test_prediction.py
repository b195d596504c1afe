"""The MTF50 predicted from a PSF along an edge normal against closed forms: a Gaussian PSF seen
through a Gaussian film filter (MTF exp(−2π²σ²f²), σ² the sum of both variances in px²), a point PSF
through a square pixel (sinc), and an elliptical Gaussian whose width depends on the direction."""

import math

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.experiments.street.prediction import edge_normal_deg
from solas_mi.metrics.mtf import aperture_mtf, mtf50, mtf_along


def gaussian_psf(sigma_x_um: float, sigma_y_um: float, pitch_um: float = 0.25, size: int = 241) -> np.ndarray:
    c = (np.arange(size) - (size - 1) / 2) * pitch_um
    return np.exp(-0.5 * (c[None, :] / sigma_x_um) ** 2 - 0.5 * (c[:, None] / sigma_y_um) ** 2)


def gaussian_mtf50(sigma_px: float) -> float:
    """f where exp(−2π²σ²f²) = 1/2 (cy/px)."""
    return math.sqrt(math.log(2) / (2 * math.pi**2 * sigma_px**2))


@pytest.mark.parametrize("normal_deg", [0.0, 5.0, 37.0, 95.0])
def test_a_gaussian_psf_through_the_gaussian_filter(normal_deg):
    pixel, sigma = 5.0, 3.0  # µm: 0.6 px
    mtf = mtf_along(gaussian_psf(sigma, sigma), 0.25, pixel, normal_deg, "gaussian")
    expected = gaussian_mtf50(math.hypot(sigma / pixel, 0.5))
    assert mtf50(mtf) == pytest.approx(expected, rel=1e-3)


def test_a_point_through_a_square_pixel_is_a_sinc():
    point = np.zeros((9, 9))
    point[4, 4] = 1.0
    f = mtf50(mtf_along(point, 0.5, 5.0, 0.0, "box"))
    assert np.sinc(f) == pytest.approx(0.5, abs=1e-4)
    assert f == pytest.approx(0.6034, abs=1e-3)
    # along the diagonal the pixel is wider: sinc(f/√2)² = 1/2
    diagonal = mtf50(mtf_along(point, 0.5, 5.0, 45.0, "box"))
    assert np.sinc(diagonal / math.sqrt(2)) ** 2 == pytest.approx(0.5, abs=1e-4)


def test_an_elliptical_psf_is_sharper_across_its_narrow_axis():
    pixel = 5.0
    psf = gaussian_psf(2.0, 6.0)  # narrow in x, wide in y
    along_x = mtf50(mtf_along(psf, 0.25, pixel, 0.0, "gaussian"))
    along_y = mtf50(mtf_along(psf, 0.25, pixel, 90.0, "gaussian"))
    assert along_x == pytest.approx(gaussian_mtf50(math.hypot(2.0 / pixel, 0.5)), rel=1e-3)
    assert along_y == pytest.approx(gaussian_mtf50(math.hypot(6.0 / pixel, 0.5)), rel=1e-3)
    # at 30°: the projected variance σx²cos² + σy²sin²
    s30 = math.sqrt(2.0**2 * math.cos(math.radians(30)) ** 2 + 6.0**2 * math.sin(math.radians(30)) ** 2)
    at30 = mtf50(mtf_along(psf, 0.25, pixel, 30.0, "gaussian"))
    assert at30 == pytest.approx(gaussian_mtf50(math.hypot(s30 / pixel, 0.5)), rel=1e-3)


def test_edge_normals_and_bad_input():
    assert edge_normal_deg("vertical", 5.0) == 5.0
    assert edge_normal_deg("horizontal", 5.0) == 95.0
    assert mtf50(np.ones(10), np.linspace(0, 1, 10)) is None
    with pytest.raises(SolasError, match="aperture 'round'"):
        aperture_mtf(np.linspace(0, 1, 5), 0.0, "round")
    with pytest.raises(SolasError, match="positive sum"):
        mtf_along(np.zeros((5, 5)), 0.5, 5.0, 0.0)
