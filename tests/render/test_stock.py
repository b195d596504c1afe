"""Scenes rendered with their own integrator in passes of bounded memory (`render.stock`)."""

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.render import stock


@pytest.fixture
def white_sky(mi):
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path"},
            "emitter": {"type": "constant"},
            "sensor": {"type": "perspective", "fov": 30, "film": {"type": "hdrfilm", "width": 32, "height": 24}},
        }
    )


def test_passes_average_to_the_radiance(white_sky, monkeypatch):
    """A constant white sky of radiance 1 reads 1 in every channel, however many passes the samples take."""
    monkeypatch.setattr(stock, "SAMPLES_PER_PASS", 32 * 24 * 5)  # 5 spp per pass: 13 spp in 3 passes
    seen = []
    r = stock.render_scene(white_sky, 13, seed=3, progress=lambda done, total: seen.append(done))
    assert seen == [5, 10, 13] and r.meta["passes"] == 3 and r.meta["integrator"] == "PathIntegrator"
    assert r.channels == ("R", "G", "B") and r.image.shape == (24, 32, 3)
    assert np.allclose(r.image.mean(axis=(0, 1)), 1.0, atol=0.01)


def test_spp_must_be_a_positive_integer(white_sky):
    with pytest.raises(SolasError, match="samples per pixel 0 must be a positive integer"):
        stock.render_scene(white_sky, 0)
