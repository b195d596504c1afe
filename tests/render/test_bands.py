"""An image larger than one pass is traced in bands of rows (`render.loop`): the same estimate, with
progress inside a pass and memory bounded by the band."""

import numpy as np
import pytest

from solas_mi.render import loop
from solas_mi.render.image import render_image


def test_bands_give_the_same_image(doublet, monkeypatch):
    image = np.random.default_rng(3).uniform(0.2, 1.0, (24, 32, 3))
    whole = render_image(doublet, image, sensor=(24, 32), spp=12, response="lines", fresnel="off", seed=5)
    monkeypatch.setattr(loop, "_SAMPLES_PER_PASS", 32 * 12)  # one spp per pass, in bands of 12 rows
    seen = []
    banded = render_image(
        doublet,
        image,
        sensor=(24, 32),
        spp=12,
        response="lines",
        fresnel="off",
        seed=5,
        progress=lambda done, total: seen.append(done),
    )
    assert seen[:2] == pytest.approx([0.5, 1.0]) and seen[-1] == 12 and len(seen) == 24
    noise = np.sqrt(np.mean((whole.image - banded.image) ** 2)) / np.sqrt(np.mean(whole.image**2))
    assert noise < 0.1  # two independent 12-spp renders of the same pixels
    assert np.allclose(whole.image.mean(axis=(0, 1)), banded.image.mean(axis=(0, 1)), rtol=0.02)
