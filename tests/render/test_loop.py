"""The path loop (`render.loop`): its checks on the samples per pixel, and the scalar reference
variant's per-sample loop against the JIT wavefront."""

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.render.image import render_image


def test_scalar_and_llvm_variants_agree(doublet):
    """A small render in the scalar reference variant matches llvm_ad_spectral within noise."""
    image = np.zeros((4, 6, 3))
    image[:, :3] = (0.2, 0.5, 1.0)
    image[:, 3:] = (1.0, 0.3, 0.1)
    runs = {
        v: render_image(doublet, image, sensor=(4, 6), spp=48, response="lines", variant=v, rings=16).image
        for v in ("scalar_spectral", "llvm_ad_spectral")
    }
    a, b = runs["scalar_spectral"], runs["llvm_ad_spectral"]
    assert np.abs(a.mean(axis=(0, 1)) - b.mean(axis=(0, 1))).max() < 0.02 * b.mean()
    assert np.sqrt(np.mean((a - b) ** 2)) < 0.05 * np.sqrt(np.mean(b**2))


def test_bad_samples_per_pixel(doublet):
    with pytest.raises(SolasError, match="samples per pixel"):
        render_image(doublet, np.ones((6, 8)), sensor=(6, 8), spp=0, variant="llvm_ad_spectral")
    with pytest.raises(SolasError, match="at least the response's 3 lines"):
        render_image(doublet, np.ones((6, 8)), sensor=(6, 8), spp=2, response="lines", variant="llvm_ad_spectral")
