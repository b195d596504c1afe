"""The sensor's CFA sites, its determinism for a seed and its checks of bad values."""

import re

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.sensor.capture import capture, fixed_pattern, mean_electrons
from solas_mi.sensor.cfa import PATTERNS
from solas_mi.sensor.exposure import LIGHT_SPEED, PLANCK, image_irradiance, photons
from solas_mi.sensor.limits import ELECTRONS_MAX
from solas_mi.sensor.model import SensorModel


@pytest.mark.parametrize("pattern", PATTERNS)
def test_each_site_samples_its_filter(pattern):
    """Channels of distinct irradiance (1, 10, 100 W/m²): each site holds its filter's QE times the photons
    of the channel(s) it collects, computed here from the pattern's letters and eq. 1 directly."""
    model = SensorModel(cfa=pattern, qe_r=0.3, qe_g=0.5, qe_b=0.7, qe_c=0.9)
    shape = (5, 7)  # odd: the tile is cut at the edges
    image = np.broadcast_to(np.array([1.0, 10.0, 100.0]), (*shape, 3))
    got = mean_electrons(model, image, 0.002)
    area = (model.pixel_pitch_um * 1e-6) ** 2
    per_channel = [
        e * area * 0.002 * (w * 1e-9) / (PLANCK * LIGHT_SPEED) for e, w in zip((1.0, 10.0, 100.0), model.wavelengths_nm)
    ]
    expected = {
        "R": 0.3 * per_channel[0],
        "G": 0.5 * per_channel[1],
        "B": 0.7 * per_channel[2],
        "C": 0.9 * sum(per_channel),
    }
    for i in range(shape[0]):
        for j in range(shape[1]):
            letter = pattern[2 * (i % 2) + (j % 2)]
            assert got[i, j] == pytest.approx(expected[letter], rel=1e-12), (i, j, letter)


def test_camera_equation():
    assert image_irradiance(np.array([4.0]), 2.0, 0.5)[0] == pytest.approx(np.pi * 0.5 * 4.0 / 16.0)


def test_same_seed_same_frame_and_frames_share_the_fixed_pattern():
    model = SensorModel(prnu=0.05, dsnu_e=20.0, read_noise_e=0.0, dark_current_e_s=0.0)
    image = np.full((64, 64, 3), 2e-3)
    first = capture(model, image, 0.01, seed=3)
    assert np.array_equal(first, capture(model, image, 0.01, seed=3))
    assert not np.array_equal(first, capture(model, image, 0.01, seed=4))
    assert not np.array_equal(first, capture(model, image, 0.01, seed=3, frame=1))
    gain, offset = fixed_pattern(model, (64, 64), 3)
    again = fixed_pattern(model, (64, 64), 3)
    assert np.array_equal(gain, again[0]) and np.array_equal(offset, again[1])
    assert gain.std() == pytest.approx(0.05, rel=0.1) and offset.std() == pytest.approx(20.0, rel=0.1)
    # the offset is seen in a dark frame with no temporal noise: y = round(K offset + black)
    dark = capture(model, np.zeros((64, 64, 3)), 0.01, seed=3)
    assert np.array_equal(dark, np.clip(np.rint(model.gain_dn_per_e * offset + model.black_level_dn), 0, None))


def test_raw_is_one_channel_within_the_adc():
    model = SensorModel(bit_depth=10, black_level_dn=16)
    raw = capture(model, np.full((8, 6, 3), 10.0), 1.0, seed=0)  # far past the full well
    assert raw.shape == (8, 6) and raw.dtype == np.uint16 and raw.max() <= 1023


def test_light_far_past_the_full_well_saturates():
    """Irradiance of 1e12 W/m² (about 1e21 photons, past NumPy's Poisson range) and the largest dark current
    allowed fill the well."""
    model = SensorModel(read_noise_e=0.0, dsnu_e=0.0, dark_current_e_s=ELECTRONS_MAX)
    raw = capture(model, np.full((4, 4, 3), 1e12), 1.0, seed=0)
    assert np.all(raw == model.black_level_dn + round(model.gain_dn_per_e * model.full_well_e))


@pytest.mark.parametrize("name, value", [("seed", -1), ("frame", -2), ("seed", 1.5)])
def test_bad_seed_or_frame(name, value):
    with pytest.raises(SolasError, match=f"sensor {name} {value} must be an integer >= 0"):
        capture(SensorModel(), np.zeros((2, 2, 3)), 0.01, **{"seed": 0, name: value})


@pytest.mark.parametrize(
    "field, value, allowed",
    [
        ("pixel_pitch_um", 0.0, r"in \[0.1, 1000\]"),
        ("pixel_pitch_um", float("nan"), r"in \[0.1, 1000\]"),
        ("qe_g", 1.2, r"\(0, 1\]"),
        ("qe_c", -0.1, r"\(0, 1\]"),
        ("read_noise_e", -1.0, r"\[0, 1e\+09\]"),
        ("dark_current_e_s", float("inf"), r"\[0, 1e\+09\]"),
        ("prnu", 1.0, r"\[0, 1\)"),
        ("dsnu_e", -2.0, r"\[0, 1e\+09\]"),
        ("full_well_e", 0, r"\[1, 1e\+09\]"),
        ("gain_dn_per_e", -0.1, r"\(0, 4095\]"),
        ("bit_depth", 20, "from 8 to 16"),
        ("bit_depth", 12.0, "integer"),
        ("black_level_dn", 4095, "from 0 to 4094"),
        ("black_level_dn", -1, "from 0"),
        ("cfa", "RGBW", "RGGB"),
        ("wavelengths_nm", (500.0, 600.0), "three wavelengths"),
        ("wavelengths_nm", (500.0, 0.0, 600.0), r"\[380, 780\]"),
    ],
)
def test_bad_values_name_the_field_and_what_is_allowed(field, value, allowed):
    with pytest.raises(SolasError, match=field if field != "cfa" else "colour filter array") as caught:
        SensorModel(**{field: value})
    assert re.search(allowed, str(caught.value)), str(caught.value)


def test_from_dict_refuses_unknown_names():
    assert SensorModel.from_dict({"cfa": "RCCB", "wavelengths_nm": [600, 530, 460]}).wavelengths_nm == (
        600.0,
        530.0,
        460.0,
    )
    with pytest.raises(SolasError, match="unknown sensor parameter.*full_wel\\b.*allowed: .*full_well_e"):
        SensorModel.from_dict({"full_wel": 100})


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: photons(np.ones((2, 2)), 1.0, 3.0, (500.0, 500.0, 500.0)), "must be \\(height, width, 3\\)"),
        (lambda: photons(np.full((2, 2, 3), np.nan), 1.0, 3.0, (500.0,) * 3), "12 non-finite values"),
        (
            lambda: photons(
                np.stack([np.full((2, 2), -1e-3), np.ones((2, 2)), np.ones((2, 2))], -1), 1.0, 3.0, (500.0,) * 3
            ),
            "4 values below zero \\(least -0.001\\)",
        ),
        (lambda: photons(np.ones((2, 2, 3)), -1.0, 3.0, (500.0,) * 3), "exposure time -1.0 s"),
        (lambda: image_irradiance(np.ones(2), 0.0), "f-number 0.0"),
        (lambda: image_irradiance(np.ones(2), 2.0, 1.5), "transmission 1.5"),
    ],
)
def test_bad_inputs(call, match):
    with pytest.raises(SolasError, match=match):
        call()


def test_round_off_below_zero_reads_as_no_light():
    """An FFT convolution's output holds round-off around zero in dark regions (down to -1e-5 of its
    largest value): read as 0 photons, not refused."""
    image = np.ones((2, 2, 3))
    image[0, 0, 1] = -3e-6
    out = photons(image, 1.0, 3.0, (500.0,) * 3)
    assert out[0, 0, 1] == 0.0 and out[1, 1, 1] > 0.0
