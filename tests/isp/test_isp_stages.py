"""Each stage of the image processor against numbers derived by hand: black level, white-balance
gains, the sensor's colour correction matrix, the tone curves; the ISP's description and its errors."""

import numpy as np
import pytest
from isp_inputs import ideal_raw, unit_irradiance

from solas_mi.errors import SolasError
from solas_mi.isp import black, ccm, tone, white
from solas_mi.isp.camera import Camera
from solas_mi.isp.demosaic import METHODS, demosaic
from solas_mi.isp.pipeline import ISP, develop, load_isp
from solas_mi.sensor.model import SensorModel


def test_black_level_and_saturation():
    """(y − black) / y_sat with y_sat the well (K · FW = 2500 DN) or the ADC (4095 − 64), whichever is less."""
    model = SensorModel(black_level_dn=64, gain_dn_per_e=0.25, full_well_e=10000)
    raw = np.array([[64, 1314, 2564]], dtype=np.uint16)
    assert black.saturation_dn(model) == 2500
    assert np.allclose(black.subtract_black(raw, model), [[0.0, 0.5, 1.0]])
    assert np.allclose(black.subtract_black(raw, model, enabled=False), raw / 2500)
    adc = SensorModel(black_level_dn=95, gain_dn_per_e=1.0, full_well_e=10000)
    assert black.saturation_dn(adc) == 4000


def test_daylight_gains():
    """g_f = η_G λ_G / (η_f λ_f), and for the clear patterns the clear filter's η_C Σλ is the reference."""
    model = SensorModel(qe_r=0.5, qe_g=0.7, qe_b=0.35, qe_c=0.9, wavelengths_nm=(600, 540, 460))
    gains = white.daylight_gains(model)
    assert gains == pytest.approx({"R": 0.7 * 540 / (0.5 * 600), "G": 1.0, "B": 0.7 * 540 / (0.35 * 460)})
    rccb = white.daylight_gains(SensorModel(cfa="RCCB", qe_r=0.5, qe_b=0.35, qe_c=0.9, wavelengths_nm=(600, 540, 460)))
    assert rccb == pytest.approx({"R": 0.9 * 1600 / (0.5 * 600), "B": 0.9 * 1600 / (0.35 * 460), "C": 1.0})


def test_measured_gains_and_their_box():
    """Grey world of a mosaic whose R sites read 0.2, G 0.4, B 0.1: gains 2, 1, 4; a bad box is refused."""
    signal = np.tile(np.array([[0.2, 0.4], [0.4, 0.1]]), (4, 4))
    assert white.measured_gains(signal, "RGGB") == pytest.approx({"R": 2.0, "G": 1.0, "B": 4.0})
    assert np.allclose(white.apply_gains(signal, "RGGB", {"R": 2.0, "G": 1.0, "B": 4.0}), 0.4)
    with pytest.raises(SolasError, match=r"grey card box \(0, 0, 9, 4\) must be"):
        white.measured_gains(signal, "RGGB", (0, 0, 9, 4))


@pytest.mark.parametrize("cfa", ["RGGB", "BGGR"])
def test_sensor_ccm_is_identity_for_one_channel_filters(cfa):
    """Filters passing one channel each (any efficiencies): after daylight balance M = I."""
    model = SensorModel(cfa=cfa, qe_r=0.3, qe_g=0.8, qe_b=0.6)
    gains = white.channel_gains(cfa, white.daylight_gains(model))
    assert np.allclose(ccm.sensor_matrix(model, gains), np.eye(3), atol=1e-12)


def test_sensor_ccm_recovers_green_from_clear():
    """RCCB: M D S = w I (the image's channels back at the clear filter's white level w)."""
    model = SensorModel(cfa="RCCB", qe_r=0.5, qe_b=0.35, qe_c=0.9)
    gains = white.channel_gains("RCCB", white.daylight_gains(model))
    balanced = np.diag(gains) @ ccm.responses(model)
    w = 0.9 * sum(model.wavelengths_nm)
    assert np.allclose(ccm.sensor_matrix(model, gains) @ balanced, w * np.eye(3))


def test_rccc_gives_red_and_grey():
    """RCCC: red exact, green and blue both their mean; a grey stays grey."""
    model = SensorModel(cfa="RCCC")
    gains = white.channel_gains("RCCC", white.daylight_gains(model))
    m = ccm.sensor_matrix(model, gains) @ np.diag(gains) @ ccm.responses(model)
    w = model.qe_c * sum(model.wavelengths_nm)
    assert np.allclose(m @ np.array([0.2, 0.5, 0.5]), w * np.array([0.2, 0.5, 0.5]))
    assert np.allclose(m @ np.ones(3), w * np.ones(3))


def test_srgb_oetf_against_the_standard():
    """IEC 61966-2-1: 12.92 x up to 0.0031308, 1.055 x^(1/2.4) − 0.055 above; continuous at the knee."""
    x = np.array([0.0, 0.001, 0.0031308, 0.01, 0.18, 0.5, 1.0])
    expected = [0.0, 0.01292, 0.04044994, 0.09985282, 0.46135613, 0.73535698, 1.0]
    assert np.allclose(tone.encode(x, "srgb"), expected, atol=1e-7)
    assert np.allclose(tone.encode(x, "gamma", 2.2), x ** (1 / 2.2))
    assert np.array_equal(tone.to_8bit(tone.encode(np.array([-0.5, 0.5, 2.0]), "none")), [0, 128, 255])


@pytest.mark.parametrize("method", list(METHODS))
def test_demosaic_of_a_flat_mosaic(method):
    """A flat RGGB mosaic (R 0.2, G 0.5, B 0.1) demosaics to those three values inside the frame."""
    mosaic = np.tile(np.array([[0.2, 0.5], [0.5, 0.1]]), (16, 16))
    out = demosaic(mosaic, "RGGB", method)
    assert np.allclose(out[4:-4, 4:-4], [0.2, 0.5, 0.1], atol=1e-9)


def test_metadata_names_every_stage():
    model = SensorModel(qe_r=0.5)
    raw = ideal_raw(model, np.full((16, 16, 3), 0.5 * unit_irradiance(model)))
    frame, meta = develop(raw, model, ISP(tone="gamma", gamma=2.0))
    assert frame.dtype == np.uint8 and frame.shape == (16, 16, 3)
    assert list(meta["stages"]) == ["black_level", "white_balance", "demosaic", "ccm", "tone"]
    assert meta["stages"]["white_balance"]["gains"]["R"] == pytest.approx(0.7 * 540 / (0.5 * 610))
    assert meta["stages"]["tone"] == {"curve": "gamma", "gamma": 2.0, "values_clipped": 0, "bits": 8}
    assert np.all(np.abs(frame[4:-4, 4:-4].astype(int) - round(255 * 0.5**0.5)) <= 1)
    assert ISP.from_dict(meta["isp"]) == ISP(tone="gamma", gamma=2.0)


def test_isp_from_toml(tmp_path):
    path = tmp_path / "isp.toml"
    path.write_text(
        '[isp]\nwhite_balance = {R = 2.0, G = 1.0, B = 1.5}\ndemosaic = "Menon2007"\n'
        "demosaic_options = {refining_step = false}\nccm = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n"
    )
    isp = load_isp(path)
    assert isp.demosaic == "Menon2007" and isp.ccm == ((1, 0, 0), (0, 1, 0), (0, 0, 1))
    assert load_isp("default") == ISP()


@pytest.mark.parametrize(
    "values, message",
    [
        ({"demosaic": "AHD"}, "demosaicing method 'AHD' must be one of bilinear, Malvar2004, Menon2007"),
        ({"demosaic": "bilinear", "demosaic_options": {"refining_step": True}}, "takes no option refining_step"),
        ({"white_balance": "auto"}, "white_balance 'auto' must be one of"),
        ({"white_balance": "grey-card"}, "grey_card .* goes with"),
        ({"ccm": [[1, 0], [0, 1]]}, "must be 3 rows of 3 numbers"),
        ({"tone": "log"}, "tone curve 'log' must be one of srgb, gamma, none, reinhard"),
        ({"demosaic": "none"}, 'takes ccm = "none"'),
        ({"sharpen": 1}, "unknown isp option"),
    ],
)
def test_bad_isp_refused(values, message):
    with pytest.raises(SolasError, match=message):
        ISP.from_dict(values)


def test_given_gains_must_match_the_pattern():
    model = SensorModel(cfa="RCCB")
    isp = ISP(white_balance={"R": 1.0, "G": 1.0, "B": 1.0})
    with pytest.raises(SolasError, match="one for each filter of RCCB: R, B, C|each filter of RCCB"):
        develop(np.zeros((8, 8)), model, isp)
    with pytest.raises(SolasError, match="each filter of RCCB"):  # a camera refuses it before any frame
        Camera(model, 1.0, isp)
