"""Sensor presets from public data sheets: each loads by name, each value says where it comes from
(data sheet / source, derived, assumption), the derived values reproduce the published figures through
the EMVA 1288 model, and the CLI takes a preset name and lists the presets."""

import math
import re
import tomllib

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.errors import SolasError
from solas_mi.imageio import read_exr, write_exr
from solas_mi.sensor.files import PRESETS, load_sensor, preset_names

KINDS = ("data sheet", "source", "derived", "assumption")
# the figures each preset's source publishes (its file's header), which the derived values must reproduce:
# SNR_max (dB) = 10 log10(full well), dynamic range (dB) = 20 log10(full well / read noise); an HDR sensor's
# dynamic range (`hdr_dynamic_range_db`) is its chain's, EMVA 1288's μ_e.sat / μ_e.min (at `DR_EXPOSURE_S`)
PUBLISHED = {
    "ar0132at": {"snr_max_db": 43.9},
    "ar0132at-hdr": {"snr_max_db": 43.9, "hdr_dynamic_range_db": 115.0},
    "imx255": {"snr_max_db": 40.3, "dynamic_range_db": 71.3},
    "mt9p001": {"snr_max_db": 38.1, "dynamic_range_db": 70.1},
    "kac12040": {"dynamic_range_db": 73.0},
}
DR_EXPOSURE_S = 0.01


def test_the_presets_shipped():
    assert preset_names() == ["ar0132at", "ar0132at-hdr", "imx255", "imx490", "imx490-hdr", "kac12040", "mt9p001"]


def leaves(table: dict) -> list[str]:
    """The keys of every value of a TOML table, its stages' tables (and arrays of them) included."""
    out = []
    for key, value in table.items():
        items = value if isinstance(value, list) and value and isinstance(value[0], dict) else [value]
        out += [k for item in items for k in (leaves(item) if isinstance(item, dict) and key != "qe_curve" else [key])]
    return out


@pytest.mark.parametrize("name", preset_names())
def test_every_value_says_where_it_comes_from(name):
    text = (PRESETS / f"{name}.toml").read_text(encoding="utf-8")
    assert re.search(r"^# Source: .+", text, re.M) and "https://" in text
    keys = leaves(tomllib.loads(text)["sensor"])
    lines = [(line.split("=")[0].strip(), line) for line in text.splitlines() if re.match(r"^\w+ *=", line)]
    assert sorted(key for key, _ in lines) == sorted(keys)
    for key, line in lines:
        comment = line.partition("#")[2].strip()
        assert comment.startswith(KINDS), f"{name}: {key} has no 'data sheet/source/derived/assumption' comment"


@pytest.mark.parametrize("name", preset_names())
def test_derived_values_reproduce_the_published_figures(name):
    sensor = load_sensor(name)
    for model in getattr(sensor, "readouts", [sensor]):
        check_derived(name, model)
    if "hdr_dynamic_range_db" in PUBLISHED.get(name, {}):  # the 1 dB
        assert sensor.dynamic_range_db(DR_EXPOSURE_S) == pytest.approx(PUBLISHED[name]["hdr_dynamic_range_db"], abs=1.0)


def check_derived(name, model):
    figures = PUBLISHED.get(name, {})
    if "snr_max_db" in figures:
        assert 10 * math.log10(model.full_well_e) == pytest.approx(figures["snr_max_db"], abs=0.01)
    if "dynamic_range_db" in figures:
        assert 20 * math.log10(model.full_well_e / model.read_noise_e) == pytest.approx(
            figures["dynamic_range_db"], abs=0.5
        )
    # the ADC's range above black spans the (large photodiode's) full well: it neither clips before the well
    # fills nor wastes codes
    if getattr(model, "photodiode", "large") != "large":
        return
    span = model.gain_dn_per_e * model.full_well_e
    assert 0.999 * (model.white_level_dn - model.black_level_dn) <= span <= model.white_level_dn - model.black_level_dn


LOW_GAIN, HIGH_GAIN = 49.0, 200.0  # µV/e-, the IMX490's conversion gains (its preset's source)


def test_the_imx490_readouts_share_one_adc():
    """The high gain's DN/e- is the low gain's times the ratio of conversion gains (one ADC); the low gain
    alone is the `imx490` preset."""
    hcg, lcg, small_hcg, small_lcg = load_sensor("imx490-hdr").readouts
    assert hcg.gain_dn_per_e == pytest.approx(lcg.gain_dn_per_e * HIGH_GAIN / LOW_GAIN, rel=1e-4)
    assert small_hcg.gain_dn_per_e == hcg.gain_dn_per_e and small_lcg.gain_dn_per_e == lcg.gain_dn_per_e
    assert hcg.full_well_e == pytest.approx(lcg.full_well_e * LOW_GAIN / HIGH_GAIN)
    assert small_hcg.full_well_e == pytest.approx(small_lcg.full_well_e * LOW_GAIN / HIGH_GAIN)
    flat = load_sensor("imx490")
    assert all(
        getattr(lcg, k) == getattr(flat, k)
        for k in ("full_well_e", "read_noise_e", "dark_current_e_s", "gain_dn_per_e", "bit_depth", "black_level_dn")
    )


def test_a_preset_name_or_a_file(tmp_path):
    (tmp_path / "mine.toml").write_text((PRESETS / "imx490.toml").read_text().replace('cfa = "RGGB"', 'cfa = "RCCB"'))
    mine = load_sensor(tmp_path / "mine.toml")
    assert mine.cfa == "RCCB" and mine.full_well_e == load_sensor("imx490").full_well_e == 22000
    with pytest.raises(SolasError, match=re.escape(f"'imx999' is neither a preset ({', '.join(preset_names())})")):
        load_sensor("imx999")
    with pytest.raises(SolasError, match="sensor model .imx999.toml. does not exist"):
        load_sensor("imx999.toml")


def test_camera_with_a_preset_and_the_listing(tmp_path, capsys):
    write_exr(tmp_path / "in.exr", {c: np.full((8, 12), 0.01, dtype=np.float32) for c in "RGB"})
    assert (
        main(
            [
                "camera",
                str(tmp_path / "in.exr"),
                "--sensor-model",
                "kac12040",
                "--exposure-ms",
                "2",
                "-o",
                str(tmp_path / "raw.exr"),
            ]
        )
        == 0
    )
    channels, meta = read_exr(tmp_path / "raw.exr")
    assert meta["sensor_model"] == "kac12040" and meta["sensor"]["pixel_pitch_um"] == 4.7
    assert channels["RAW"].shape == (8, 12)
    capsys.readouterr()
    assert main(["sensors"]) == 0
    listing = capsys.readouterr().out
    assert all(re.search(rf"^{name} +\S", listing, re.M) for name in preset_names())
