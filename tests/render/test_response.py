"""Camera spectral responses (`render.response`): channels, white balance, sampling, bad names."""
import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.render.response import parse


def test_lines_are_the_lens_wavelengths_longest_first(doublet):
    r = parse("lines", doublet.wavelengths_nm)
    assert r.channels == ("R", "G", "B") and r.lo_nm.tolist() == r.hi_nm.tolist() == [656.0, 531.0, 486.0]
    assert parse("lines:500,600", doublet.wavelengths_nm).channels == ("600nm", "500nm")


@pytest.mark.parametrize("name", ["lines", "srgb", "mono:531", "table"])
def test_a_flat_spectrum_is_white(doublet, name, tmp_path):
    """Radiance 1 at every wavelength gives 1 in every channel: Σ p_i × weight_i = 1."""
    if name == "table":
        lam = np.arange(400.0, 701.0, 10.0)
        rows = np.stack([lam, np.exp(-((lam - 600) / 40) ** 2), np.exp(-((lam - 530) / 40) ** 2),
                         np.exp(-((lam - 450) / 30) ** 2)], axis=-1)
        np.savetxt(tmp_path / "camera.csv", rows, delimiter=",")
        name = f"table:{tmp_path / 'camera.csv'}"
    r = parse(name, doublet.wavelengths_nm)
    assert r.probability.sum() == pytest.approx(1.0)
    assert np.allclose(r.probability @ r.weights, 1.0)


def test_samples_follow_the_bins():
    r = parse("srgb", ())
    lam, weights = r.sample((np.arange(4096) + 0.5) / 4096)
    assert 380.0 <= lam.min() and lam.max() <= 780.0
    assert np.allclose(weights.mean(axis=0), 1.0, atol=0.02)  # stratified estimate of the white balance


@pytest.mark.parametrize("name, message", [("infrared", "unknown response"), ("mono:x", "mono needs a wavelength"),
                                           ("mono:-5", "must be positive")])
def test_bad_names(doublet, name, message):
    with pytest.raises(SolasError, match=message):
        parse(name, doublet.wavelengths_nm)
