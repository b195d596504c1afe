"""Camera spectral responses (`render.response`): channels, white balance, sampling, bad names."""

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.render.response import parse


def test_lines_are_the_lens_wavelengths_longest_first(doublet):
    r = parse("lines", doublet.wavelengths_nm)
    assert r.channels == ("R", "G", "B") and r.lo_nm.tolist() == r.hi_nm.tolist() == [656.0, 531.0, 486.0]
    assert parse("lines:500,600", doublet.wavelengths_nm).channels == ("600nm", "500nm")


@pytest.mark.parametrize("name", ["lines", "mono:531"])
def test_a_flat_spectrum_is_white_in_lines(doublet, name):
    """Radiance 1 at every wavelength gives 1 in every channel: Σ p_i × weight_i = 1."""
    r = parse(name, doublet.wavelengths_nm)
    assert r.probability.sum() == pytest.approx(1.0)
    assert np.allclose(r.probability @ r.weights, 1.0)


def _d65_response(r, mi, n=8192):
    """Stratified estimate of the channels under D65 of luminance 1 (Mitsuba's `cie_d65`)."""
    lam, weights = r.sample((np.arange(n) + 0.5) / n)
    d65 = np.array(mi.cie_d65(mi.Float(lam)))
    return (weights * d65[:, None]).mean(axis=0)


def test_a_table_camera_is_balanced_for_d65(doublet, tmp_path, mi):
    """A camera's table is white-balanced as the srgb response is: D65 of luminance 1 gives (1, 1, 1)
    (it was balanced for a flat spectrum, which the image object no longer emits for white)."""
    lam = np.arange(400.0, 701.0, 10.0)
    rows = np.stack(
        [
            lam,
            np.exp(-(((lam - 600) / 40) ** 2)),
            np.exp(-(((lam - 530) / 40) ** 2)),
            np.exp(-(((lam - 450) / 30) ** 2)),
        ],
        axis=-1,
    )
    np.savetxt(tmp_path / "camera.csv", rows, delimiter=",")
    r = parse(f"table:{tmp_path / 'camera.csv'}", doublet.wavelengths_nm)
    assert r.probability.sum() == pytest.approx(1.0)
    assert _d65_response(r, mi) == pytest.approx([1.0, 1.0, 1.0], rel=2e-3)


def _hdrfilm(mi, radiance: dict) -> np.ndarray:
    """What Mitsuba's hdrfilm develops for a constant emitter of `radiance` (a perspective camera)."""
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path"},
            "light": {"type": "constant", "radiance": radiance},
            "sensor": {
                "type": "perspective",
                "film": {"type": "hdrfilm", "width": 4, "height": 4},
                "sampler": {"type": "independent", "sample_count": 4096},
            },
        }
    )
    return np.array(mi.render(scene, seed=3)).mean(axis=(0, 1))


@pytest.mark.parametrize("radiance", ["flat", "d65", "ramp"])
def test_srgb_develops_as_hdrfilm(mi, radiance):
    """The srgb response develops a spectrum as Mitsuba's hdrfilm does (CIE 1931 to linear sRGB, D65):
    a flat spectrum reads (1.206, 0.949, 0.910), D65 of luminance 1 (an RGB emitter of 1) reads white,
    a piecewise-linear spectrum as the film reads it; each within 0.3 %."""
    knots = ([400.0, 500.0, 600.0, 700.0], [0.2, 1.0, 0.5, 1.5])
    r = parse("srgb", ())
    n = 16384
    lam, weights = r.sample((np.arange(n) + 0.5) / n)
    if radiance == "flat":
        spectrum, given = np.ones_like(lam), {"type": "uniform", "value": 1.0}
    elif radiance == "d65":
        spectrum, given = np.array(mi.cie_d65(mi.Float(lam))), {"type": "rgb", "value": [1.0, 1.0, 1.0]}
    else:
        spectrum = np.interp(lam, *knots, left=0.0, right=0.0)
        given = {"type": "regular", "wavelength_min": 400.0, "wavelength_max": 700.0, "values": "0.2, 1.0, 0.5, 1.5"}
    ours = (weights * spectrum[:, None]).mean(axis=0)
    film = _hdrfilm(mi, given)
    assert ours == pytest.approx(film, rel=3e-3)
    if radiance == "flat":
        assert ours == pytest.approx([1.206, 0.949, 0.910], abs=2e-3)
    if radiance == "d65":
        assert ours == pytest.approx([1.0, 1.0, 1.0], rel=2e-3)


def test_samples_follow_the_bins(mi):
    r = parse("srgb", ())
    lam, _weights = r.sample((np.arange(4096) + 0.5) / 4096)
    assert lam.min() >= 380.0 and lam.max() <= 780.0
    assert _d65_response(r, mi, 4096) == pytest.approx([1.0, 1.0, 1.0], abs=0.02)  # stratified: D65 is white


@pytest.mark.parametrize(
    "name, message",
    [("infrared", "unknown response"), ("mono:x", "mono needs a wavelength"), ("mono:-5", "must be positive")],
)
def test_bad_names(doublet, name, message):
    with pytest.raises(SolasError, match=message):
        parse(name, doublet.wavelengths_nm)
