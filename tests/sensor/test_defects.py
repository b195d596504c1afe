"""Defect pixels, a stage of the chain: a flat sensor file with a [sensor.defects] table; dead pixels read the
dark level whatever the light (EMVA 1288's μ_y.dark = black + K i_d t), hot pixels K i_hot t more than they
would, in the fractions asked, fixed by the seed; every other pixel reads what it read without defects, bit
for bit."""

import math
from dataclasses import replace

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.isp.pipeline import ISP, develop
from solas_mi.sensor.capture import capture
from solas_mi.sensor.defects import Defects
from solas_mi.sensor.files import PRESETS, load_sensor
from solas_mi.sensor.photons import PhotonConversion
from solas_mi.sensor.readout import Readout

SHAPE = (256, 256)
SECONDS = 0.01
DEFECTS = "\n[sensor.defects]\ndead_fraction = 0.005\nhot_fraction = 0.004\nhot_dark_current_e_s = 20000.0\n"


@pytest.fixture
def sensors(tmp_path):
    (tmp_path / "defects.toml").write_text(
        (PRESETS / "imx490.toml").read_text(encoding="utf-8") + DEFECTS, encoding="utf-8"
    )
    return load_sensor("imx490"), load_sensor(tmp_path / "defects.toml")


def test_a_flat_file_takes_a_defects_table(sensors):
    flat, defective = sensors
    assert [type(stage) for _, stage in defective.stages()] == [PhotonConversion, Defects, Readout]
    assert defective.readouts[0].full_well_e == flat.full_well_e and defective.defects == Defects(0.005, 0.004, 2e4)


def test_defects_read_their_dark_level_and_the_rest_is_unchanged(sensors):
    flat, defective = sensors
    image = np.full((*SHAPE, 3), 0.05)  # bright: ≈ 40 % of the full well on every filter
    dead, hot = defective.defects.pixel_map(SHAPE, 7)
    for frame in (0, 1):
        plain, raw = capture(flat, image, SECONDS, 7, frame), capture(defective, image, SECONDS, 7, frame)
        assert np.array_equal(plain[~dead & ~hot], raw[~dead & ~hot])
        k, black = flat.gain_dn_per_e, flat.black_level_dn
        dark_noise = k * math.sqrt(flat.read_noise_e**2 + flat.dsnu_e**2 + flat.dark_current_e_s * SECONDS) + 0.3
        assert raw[dead].mean() == pytest.approx(flat.dark_mean_dn(SECONDS), abs=4 * dark_noise / math.sqrt(dead.sum()))
        # a hot pixel collects the light and its own dark electrons (the same draws) plus i_hot t more
        extra = defective.defects.hot_dark_current_e_s * SECONDS
        excess = raw[hot].astype(float) - plain[hot]
        assert excess.mean() == pytest.approx(k * extra, abs=4 * (k * math.sqrt(extra) + 0.5) / math.sqrt(hot.sum()))
        assert plain[dead].mean() > black + 0.3 * flat.saturation_dn  # the same pixels see the light without


def test_the_defects_are_fixed_by_the_seed_in_the_fractions_asked(sensors):
    defects = sensors[1].defects
    dead, hot = defects.pixel_map(SHAPE, 7)
    n = SHAPE[0] * SHAPE[1]
    for found, fraction in ((dead, defects.dead_fraction), (hot, defects.hot_fraction)):
        assert abs(found.sum() - fraction * n) <= 5 * math.sqrt(n * fraction * (1 - fraction))
    assert not np.any(dead & hot)
    again, other = defects.pixel_map(SHAPE, 7), defects.pixel_map(SHAPE, 8)
    assert np.array_equal(again[0], dead) and np.array_equal(again[1], hot) and not np.array_equal(other[0], dead)


@pytest.mark.parametrize(
    "values, message",
    [
        (dict(dead_fraction=0.5), r"sensor defects dead_fraction = 0.5 must be a number in \[0, 0.01\]"),
        (
            dict(hot_dark_current_e_s=-1.0),
            r"sensor defects hot_dark_current_e_s = -1.0 must be a number in \[0, 1e\+09\]",
        ),
    ],
)
def test_bad_defects_are_refused_by_name(values, message):
    with pytest.raises(SolasError, match=message):
        Defects(**values)


def test_the_image_processor_replaces_the_defect_pixels(sensors, tmp_path):
    """Developed with the sensor's defect map, a flat field's dead and hot pixels take their same-filter
    neighbours' mean: within the shot noise of the flat field; without the correction the dead ones are black."""
    _, defective = sensors
    image = np.full((*SHAPE, 3), 0.05)
    raw = capture(defective, image, SECONDS, 7, 0)
    where = defective.defective_pixels(SHAPE, 7)
    plain = ISP(demosaic="none", ccm="none", white_balance="none", tone="none")
    fixed, meta = develop(raw, defective, plain, where)
    kept, _ = develop(raw, defective, replace(plain, defect_correction=False), where)
    assert meta["stages"]["black_level"]["defect_pixels_corrected"] == int(where.sum())
    assert np.count_nonzero(kept[where][:, 0] == 0) > 0.3 * where.sum()  # the dead ones, black
    grey = fixed[..., 0].astype(float)
    assert abs(grey[where].mean() - grey[~where].mean()) < 2.0  # the flat field's level, in 8-bit codes


def test_camera_corrects_the_defects_of_its_sensor(sensors, tmp_path):
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr, write_exr

    write_exr(tmp_path / "in.exr", {c: np.full(SHAPE, 0.05, np.float32) for c in "RGB"})
    assert (
        main(
            [
                "camera",
                str(tmp_path / "in.exr"),
                "--sensor-model",
                str(tmp_path / "defects.toml"),
                "--exposure-ms",
                "10",
                "--seed",
                "7",
                "--isp",
                "default",
                "-o",
                str(tmp_path / "raw.exr"),
            ]
        )
        == 0
    )
    _, meta = read_exr(tmp_path / "raw.exr")
    assert meta["stages"]["black_level"]["defect_pixels_corrected"] == int(sensors[1].defective_pixels(SHAPE, 7).sum())
    assert [s["stage"] for s in meta["sensor"]["stages"]][1] == "defects"
