"""The cross-validation's input image (`solas_mi.validation.inputs`)."""

import math

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.validation.inputs import load_input, tangent_cos3


def test_tangent_cos3_matches_the_camera_tangents():
    c = tangent_cos3(4, 2, 2.0)
    t = math.tan(math.radians(2.0)) / 2
    assert c[0, 0] == pytest.approx((1 + (1.5 * t) ** 2 + (0.5 * t) ** 2) ** -1.5)
    assert np.allclose(c, c[::-1, ::-1])


def test_bad_input_is_a_solas_error(tmp_path):
    with pytest.raises(SolasError, match="image file .*missing.png. does not exist"):
        load_input(str(tmp_path / "missing.png"))
    with pytest.raises(SolasError, match="non-negative"):
        load_input(-np.ones((16, 16, 3)))
    with pytest.raises(SolasError, match="H×W"):
        load_input(np.ones((16, 16, 4)))
    with pytest.raises(SolasError, match="larger"):
        load_input(np.ones((16, 16, 3)), sensor=(32, 32))
    with pytest.raises(SolasError, match="scale"):
        load_input(np.ones((16, 16, 3)), scale=2.0)


def test_load_input_area_averages():
    img = np.arange(16 * 16 * 3, dtype=float).reshape(16, 16, 3)
    small = load_input(img, sensor=(8, 8))
    assert small.shape == (8, 8, 3)
    assert np.allclose(small[0, 0], img[:2, :2].mean(axis=(0, 1)))
    assert load_input(img[..., 0], scale=0.5).shape == (8, 8, 3)
