"""Photon transfer (EMVA 1288 release 4.0): flat fields at 20 levels through `capture`, against the
model's own predictions — temporal variance against mean (eq. 6), SNR against irradiance (eq. 15),
dark frames against dark current and read noise, and the collapse of the variance at the full well.
Temporal statistics come from the difference of two frames of one seed (the fixed pattern cancels).
The transfer runs for the scalar quantum efficiencies and for a QE curve with cross-talk (`sensor.qe`)."""

from dataclasses import replace

import numpy as np
import pytest

from solas_mi.sensor.capture import capture, mean_electrons
from solas_mi.sensor.emva import QUANTISATION_VARIANCE
from solas_mi.sensor.model import SensorModel
from solas_mi.sensor.qe import QECurve

SHAPE = (256, 512)
EXPOSURE = 0.01  # s
MODEL = SensorModel(
    dark_current_e_s=200.0,
    read_noise_e=5.0,
    prnu=0.01,
    dsnu_e=2.0,
    full_well_e=10000.0,
    gain_dn_per_e=0.25,
    bit_depth=12,
    black_level_dn=64,
    cfa="RGGB",
)
# the same sensor with filters that pass some of the neighbouring bands (cross-talk)
CURVE = replace(
    MODEL,
    qe_r=None,
    qe_g=None,
    qe_b=None,
    qe_c=None,
    wavelengths_nm=None,
    qe_curve=QECurve.from_table(
        {
            "wavelength_nm": [380, 480, 540, 620, 780],
            "R": [0.02, 0.03, 0.1, 0.6, 0.3],
            "G": [0.05, 0.3, 0.7, 0.2, 0.05],
            "B": [0.4, 0.6, 0.15, 0.03, 0.02],
        }
    ),
)
GREEN = np.zeros(SHAPE, dtype=bool)
GREEN[0::2, 1::2] = GREEN[1::2, 0::2] = True  # RGGB: the G sites


def flat(level: float) -> np.ndarray:
    """A flat field of `level` W/m² in every channel."""
    return np.full((*SHAPE, 3), level)


def electrons_per_unit(model: SensorModel = MODEL) -> float:
    """Photo-electrons of a G pixel per W/m² (through the model's own exposure and QE)."""
    return float(mean_electrons(model, np.ones((2, 2, 3)), EXPOSURE)[0, 1])


def temporal(
    level: float, exposure: float = EXPOSURE, seed: int = 7, model: SensorModel = MODEL
) -> tuple[float, float]:
    """Mean (DN) and temporal variance (DN², half the variance of the two frames' difference) of the G sites."""
    a = capture(model, flat(level), exposure, seed, frame=0)[GREEN].astype(np.float64)
    b = capture(model, flat(level), exposure, seed, frame=1)[GREEN].astype(np.float64)
    return 0.5 * (a.mean() + b.mean()), 0.5 * np.var(a - b)


LEVELS = np.linspace(0.01, 0.85, 20)  # fractions of the full well


@pytest.fixture(scope="module", params=[MODEL, CURVE], ids=["scalar", "curve"])
def transfer(request):
    model = request.param
    unit = electrons_per_unit(model)
    rows = []
    for fraction in LEVELS:
        level = fraction * model.full_well_e / unit
        rows.append((level * unit, *temporal(level, model=model)))
    return np.array(rows)  # electrons, mean DN, variance DN²


def test_variance_against_mean_follows_the_photon_transfer_line(transfer):
    electrons, mean, variance = transfer.T
    predicted = np.array([MODEL.temporal_variance_dn2(m, EXPOSURE) for m in mean])
    assert np.all(np.abs(variance / predicted - 1) < 0.02), np.abs(variance / predicted - 1).max()
    # and the mean itself is K μ_e above the dark level
    assert np.allclose(mean - MODEL.dark_mean_dn(EXPOSURE), MODEL.gain_dn_per_e * electrons, rtol=0.01, atol=0.1)


def test_snr_against_irradiance(transfer):
    electrons, mean, variance = transfer.T
    measured = (mean - MODEL.dark_mean_dn(EXPOSURE)) / np.sqrt(variance)
    predicted = np.array([MODEL.snr(e, EXPOSURE) for e in electrons])
    assert np.all(np.abs(measured / predicted - 1) < 0.02), np.abs(measured / predicted - 1).max()


@pytest.mark.parametrize("exposure", [0.001, 0.05, 0.2])
def test_dark_frames_match_dark_current_and_read_noise(exposure):
    mean, variance = temporal(0.0, exposure)
    assert abs(mean - MODEL.dark_mean_dn(exposure)) < 0.05  # black + K i_d t (i_d t = 0.2 to 40 e⁻)
    expected = (
        MODEL.gain_dn_per_e**2 * (MODEL.read_noise_e**2 + MODEL.dark_current_e_s * exposure) + QUANTISATION_VARIANCE
    )
    assert abs(variance / expected - 1) < 0.02


def test_saturation_at_the_full_well():
    level = 3 * MODEL.full_well_e / electrons_per_unit()
    mean, variance = temporal(level)
    assert abs(mean - (MODEL.black_level_dn + MODEL.gain_dn_per_e * MODEL.full_well_e)) < 0.1
    # the shot noise is gone: only read noise and rounding remain (DSNU is fixed and cancels)
    readout = MODEL.gain_dn_per_e**2 * MODEL.read_noise_e**2 + QUANTISATION_VARIANCE
    assert abs(variance / readout - 1) < 0.03
    assert variance < 0.01 * MODEL.temporal_variance_dn2(mean, EXPOSURE)
