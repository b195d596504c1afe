"""ISO 12233 e-SFR: accuracy against the analytic MTF of synthetic edges, and the flags."""

import math

import imageio.v3 as iio
import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.imageio import read_image
from solas_mi.metrics.esfr import esfr, matlab_round
from solas_mi.metrics.targets import analytic_mtf, analytic_mtf50, slanted_edge

CRITICAL_DEG = (45.0, *(math.degrees(math.atan(t)) for t in (1 / 2, 1 / 3, 1 / 4)))


def roi_width(sigma: float, angle: float, rows: int = 128) -> int:
    """ROI width (px, ≥ 64, multiple of 32): the edge's run across the rows plus 16 LSF equivalent
    widths, so that the whole-ROI window biases MTF50 by < 0.5 % (±6 widths is the 1 % limit)."""
    w_eq = math.sqrt(2 * math.pi) * math.sqrt(sigma**2 + 1 / 12)
    t = math.radians(angle)
    return max(64, 32 * math.ceil((rows * math.tan(t) + 16 * w_eq / math.cos(t)) / 32))


def check_accuracy(sigma: float, angle: float, mode: str, rows: int = 128, offset: float = 0.0) -> float:
    """Measure a noiseless edge; assert the acceptance limits; return the MTF50 error in %."""
    img = slanted_edge((rows, roi_width(sigma, angle, rows)), angle, sigma, offset_px=offset)
    res = esfr(img, mode=mode)
    assert res.valid, res.reason
    assert not any("biased" in w for w in res.warnings)
    err = 100 * (res.mtf50 / analytic_mtf50(sigma, angle) - 1)
    assert abs(err) <= 1.0, f"σ={sigma} θ={angle} {mode}: MTF50 error {err:+.3f} %"
    upto = res.freq <= 0.5
    curve = np.max(np.abs(res.sfr[upto] - analytic_mtf(res.freq[upto], sigma, angle)))
    assert curve <= 0.01, f"σ={sigma} θ={angle} {mode}: SFR off by {curve:.4f}"
    assert abs(res.angle_deg - angle) <= 0.1
    return err


@pytest.mark.parametrize("mode", ["2023", "2017"])
@pytest.mark.parametrize("sigma", [0.7, 1.0, 2.0, 3.0])
@pytest.mark.parametrize("angle", [2.0, 5.0, 10.0, 22.0, 33.0, 40.0])
def test_mtf50_matches_analytic(sigma, angle, mode):
    check_accuracy(sigma, angle, mode)


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["2023", "2017"])
@pytest.mark.parametrize("sigma", [0.7, 1.0, 1.5, 2.0, 2.5, 3.0])
def test_mtf50_sweep(sigma, mode):
    angles = [a for a in np.arange(2.0, 40.01, 0.5) if min(abs(a - c) for c in CRITICAL_DEG) >= 1.0]
    for angle in angles:
        for rows, offset in ((64, 0.0), (128, 3.3)):
            check_accuracy(sigma, float(angle), mode, rows, offset)


@pytest.mark.parametrize("sigma, expected", [(0.5, 0.323111), (1.0, 0.179965), (2.0, 0.092732), (3.0, 0.062176)])
def test_spec_reference_values_at_5_degrees(sigma, expected):
    res = esfr(slanted_edge((128, roi_width(sigma, 5.0)), 5.0, sigma))
    assert res.mtf50 == pytest.approx(expected, rel=0.01)


def test_noise_mean_of_20_seeds_within_1_percent():
    ref = analytic_mtf50(1.0, 5.0)
    errs = [100 * (esfr(slanted_edge((128, 128), 5.0, 1.0, noise=0.01, seed=s)).mtf50 / ref - 1) for s in range(20)]
    assert abs(np.mean(errs)) <= 1.0
    assert np.std(errs) <= 1.5  # per-edge sd: sfrmat5 ≈ 1.1 %, MTF Mapper ≈ 0.6 %


def test_frequency_axis_is_scaled_by_cos_theta():
    res = esfr(slanted_edge((128, 128), 30.0, 1.0))
    theta = math.radians(res.angle_deg)
    assert np.allclose(np.diff(res.freq), 1 / (128 * math.cos(theta)))
    assert res.freq[-1] == pytest.approx(1 / math.cos(theta))


def test_horizontal_edge_and_reversed_polarity():
    ref = analytic_mtf50(1.2, 6.0)
    horizontal = esfr(slanted_edge((96, 128), 96.0, 1.2))
    assert horizontal.orientation == "horizontal"
    assert horizontal.angle_deg == pytest.approx(6.0, abs=0.1)
    assert horizontal.mtf50 == pytest.approx(ref, rel=0.01)
    reversed_ = esfr(slanted_edge((128, 96), -6.0, 1.2, low=0.8, high=0.2))
    assert reversed_.orientation == "vertical"
    assert reversed_.mtf50 == pytest.approx(ref, rel=0.01)


def test_colour_roi_uses_luminance_or_one_channel():
    edge = slanted_edge((100, 100), 5.0, 1.0)
    rgb = np.stack([edge, 0.5 * edge + 0.2, 0.9 * edge], axis=-1)
    assert esfr(rgb).mtf50 == pytest.approx(esfr(edge).mtf50, rel=1e-6)
    assert esfr(rgb, channel=1).mtf50 == pytest.approx(esfr(edge).mtf50, rel=1e-6)
    assert esfr(edge[..., None]).mtf50 == pytest.approx(esfr(edge).mtf50, rel=1e-6)


@pytest.mark.parametrize("shape", ["HxW", "HxWx1"])
def test_a_colour_channel_of_a_grey_roi_is_refused(shape):
    """A grey ROI has no red channel: measuring its grey values instead was silently wrong."""
    edge = slanted_edge((100, 100), 5.0, 1.0)
    with pytest.raises(SolasError, match="channel 0 asked of a grey image"):
        esfr(edge if shape == "HxW" else edge[..., None], channel=0)


def test_zero_degree_edge_is_invalid_without_a_number():
    for angle in (0.0, 0.3):
        res = esfr(slanted_edge((100, 100), angle, 1.0))
        assert not res.valid and "0°" in res.reason
        assert res.mtf50 is None and res.sfr.size == 0


@pytest.mark.parametrize("angle", CRITICAL_DEG)
def test_45_degrees_and_critical_angles_are_warned(angle):
    res = esfr(slanted_edge((128, 128), angle, 1.0))
    assert res.valid
    assert any("45°" in w or "critical angle" in w for w in res.warnings)


def test_ordinary_angle_has_no_warning():
    assert esfr(slanted_edge((128, 128), 10.0, 1.0)).warnings == []


def test_clipped_roi_is_rejected():
    res = esfr(slanted_edge((100, 100), 5.0, 1.0, high=1.4))
    assert not res.valid and "clipped" in res.reason and res.mtf50 is None
    # the same edge below full scale is measured; a higher full scale accepts the clipped values
    assert esfr(slanted_edge((100, 100), 5.0, 1.0, high=0.95)).valid
    assert esfr(slanted_edge((100, 100), 5.0, 1.0, high=1.4, clip=False), full_scale=None).valid


@pytest.mark.parametrize("bits", [8, 16])
def test_srgb_png_is_linearised(tmp_path, bits):
    sigma, angle = 1.0, 5.0
    img = slanted_edge((128, 128), angle, sigma, low=0.03, high=0.9, encoding="srgb", bit_depth=bits)
    path = tmp_path / f"edge{bits}.png"
    iio.imwrite(path, img)
    ref = analytic_mtf50(sigma, angle)
    linearised = esfr(read_image(path)).mtf50
    as_is = esfr(read_image(path, linearize=False)).mtf50
    assert linearised == pytest.approx(ref, rel=0.01)
    assert as_is < 0.97 * ref  # measuring the encoded values as linear biases MTF50 down


def test_two_edges_or_none_are_rejected():
    bar = slanted_edge((100, 100), 5.0, 1.0, offset_px=-15) - 0.6 * slanted_edge(
        (100, 100), 5.0, 1.0, offset_px=15, low=0.0, high=1.0
    )
    res = esfr(bar)
    assert not res.valid and "not one step edge" in res.reason
    noise = 0.5 + 0.01 * np.random.default_rng(0).normal(size=(100, 100))
    res = esfr(noise)
    assert not res.valid and "no edge" in res.reason
    assert not esfr(np.full((50, 50), 0.5)).valid


def test_noisy_edge_is_measured_and_reported():
    res = esfr(slanted_edge((128, 128), 5.0, 1.0, noise=0.1, seed=1))
    assert res.valid
    assert res.noise == pytest.approx(0.1, rel=0.15)
    assert any("noisy edge" in w for w in res.warnings)


def test_mtf50_not_found_above_nyquist():
    res = esfr(slanted_edge((100, 100), 5.0, 0.0))  # pixel aperture only: MTF50 ≈ 0.60 cy/px
    assert res.valid and res.mtf50 is None and res.mtf50_reason == "not found"


def test_narrow_roi_is_flagged():
    res = esfr(slanted_edge((128, 64), 5.0, 3.0))
    assert any("biased upward" in w for w in res.warnings)


def test_matlab_rounding():
    assert [matlab_round(x) for x in (0.5, 1.5, 2.5, -0.5, -2.5, 2.4999)] == [1, 2, 3, -1, -3, 2]


def test_user_errors():
    with pytest.raises(SolasError, match="mode"):
        esfr(slanted_edge(), mode="2000")
    bad = slanted_edge()
    bad[3, 3] = np.nan
    with pytest.raises(SolasError, match="NaN"):
        esfr(bad)
    for odd, message in [
        (np.zeros((0, 0)), "too small"),
        (np.zeros((1, 1)), "too small"),
        ([], "too small"),
        ("roi", "pass linear floats"),
        (None, "pass linear floats"),
        (np.full((16, 16), np.inf), "NaN or infinite"),
    ]:
        with pytest.raises(SolasError, match=message):
            esfr(odd)
