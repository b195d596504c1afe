"""Errors against the reference (`solas_mi.validation.scores`) and the annuli they are split into."""

import math

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.validation.scores import compare, denoise


def test_compare_known_errors_and_noise_removal():
    rng = np.random.default_rng(1)
    ref = 0.2 + rng.random((60, 80, 3))
    same = compare(ref, ref)
    assert same.rel_rmse == 0 and same.ssim == pytest.approx(1.0) and math.isinf(same.psnr_db)
    img = ref * 1.01
    e = compare(img, ref)
    assert e.rel_rmse == pytest.approx(0.01, rel=1e-9)
    assert e.psnr_db == pytest.approx(20 * math.log10(ref.max() / math.sqrt(np.mean((0.01 * ref) ** 2))))
    assert set(e.annuli) == {"centre", "middle", "edge"}
    assert all(v == pytest.approx(0.01, rel=1e-9) for v in e.annuli.values())
    # a noise level given for the reference is removed in quadrature
    rms = math.sqrt(np.mean(ref**2))
    assert compare(img, ref, ref_noise=0.006 * rms).rel_rmse_denoised == pytest.approx(0.008, rel=1e-6)
    assert denoise(0.01, 0.02) == 0.0
    with pytest.raises(SolasError, match="shape"):
        compare(ref[:10], ref)


@pytest.mark.parametrize(
    "odd, message",
    [
        (np.zeros((0, 0, 3)), "at least 7 px"),
        (np.ones((60, 80)), "H×W×C"),
        ("image", "array of numbers"),
        (np.full((60, 80, 3), np.nan), "NaN or infinite"),
        (None, "H×W×C"),
    ],
)
def test_odd_images_are_refused_by_name(odd, message):
    """An image SSIM cannot read (no channel axis: its width would be taken for channels, too small for
    its window, not numbers, not finite): a SolasError naming it, for either argument."""
    ref = 0.2 + np.random.default_rng(2).random((60, 80, 3))
    with pytest.raises(SolasError, match=message):
        compare(odd, ref)
    with pytest.raises(SolasError, match=message.replace("the image", "the reference")):
        compare(ref, odd)
