"""The reference render's noise and its storage (`solas_mi.validation.reference`)."""

import numpy as np
import pytest

from solas_mi.validation.reference import Reference, noise_variance_map, read_reference, write_reference


def test_noise_variance_map_is_the_variance_of_the_mean():
    a, b = np.full((20, 30, 3), 1.0), np.full((20, 30, 3), 1.2)
    var = noise_variance_map([a, b])
    assert var.shape == (20, 30)
    assert np.allclose(var, 0.1**2)  # per-render variance 2 · 0.1² / (2 − 1), the mean's half of it


def test_reference_is_reused_only_with_the_same_settings(tmp_path):
    rng = np.random.default_rng(3)
    renders = [rng.random((16, 24, 3)) for _ in range(2)]
    ref = Reference(np.mean(renders, axis=0), 0.01, 64, 2.5, renders)
    var = noise_variance_map(renders)
    settings = {"lens_hash": "abc", "sensor": [24, 16], "fov_deg": 2.0, "boundary": "edge"}
    path = tmp_path / "reference.exr"
    write_reference(path, ref, var, settings)
    expect = dict(settings, spp=64, seeds=2, response="lines", fresnel="off")
    stored, stored_var = read_reference(path, expect)
    assert np.allclose(stored.image, ref.image, atol=1e-6) and np.allclose(stored_var, var, rtol=1e-6)
    assert (stored.noise, stored.spp, stored.seconds) == (0.01, 64, 2.5)
    assert stored.rms == pytest.approx(ref.rms, rel=1e-6)
    assert read_reference(path, dict(expect, spp=128)) is None
    assert read_reference(tmp_path / "missing.exr", expect) is None
