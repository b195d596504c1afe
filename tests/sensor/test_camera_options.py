"""`solas-mi camera`'s frames, exposure and reading of its input: --frame (another frame of one sensor,
checked with photon statistics as EMVA 1288's photon transfer takes them), --exposure-ms auto, the
f-number a render states, the saturation warning, the memory estimate; and `sensors --json`."""

import re

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi.cli import main
from solas_mi.imageio import read_exr, write_exr
from solas_mi.sensor.capture import capture, fixed_pattern
from solas_mi.sensor.exposure import LIGHT_SPEED, PLANCK
from solas_mi.sensor.files import load_sensor
from solas_mi.sensor.readout import PATTERN_VALUES_PER_READOUT

# a sensor whose fixed pattern dwarfs its temporal noise (PRNU 5 %, DSNU 20 e⁻), so a frame difference that
# kept any of it would show
SENSOR = """[sensor]
pixel_pitch_um = 3.0
prnu = 0.05
dsnu_e = 20.0
read_noise_e = 5.0
dark_current_e_s = 200.0
full_well_e = 10000.0
gain_dn_per_e = 0.25
cfa = "RGGB"
"""
SHAPE = (128, 256)
EXPOSURE_MS = 10.0


def green(shape=SHAPE):
    sites = np.zeros(shape, dtype=bool)
    sites[0::2, 1::2] = sites[1::2, 0::2] = True
    return sites


@pytest.fixture
def flat(tmp_path):
    """A flat field putting the G sites at about 40 % of the full well (eq. 1 with the model's QE)."""
    (tmp_path / "sensor.toml").write_text(SENSOR)
    model = load_sensor(tmp_path / "sensor.toml")
    per_unit = (
        (model.pixel_pitch_um * 1e-6) ** 2
        * EXPOSURE_MS
        * 1e-3
        * model.wavelengths_nm[1]
        * 1e-9
        / (PLANCK * LIGHT_SPEED)
        * model.qe_g
    )  # G electrons per W/m²
    level = 0.4 * model.full_well_e / per_unit
    write_exr(tmp_path / "flat.exr", {c: np.full(SHAPE, level, np.float32) for c in "RGB"})
    return tmp_path, model


def _frame(folder, name, *extra):
    assert (
        main(
            [
                "camera",
                str(folder / "flat.exr"),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                str(EXPOSURE_MS),
                *extra,
                "-o",
                str(folder / name),
            ]
        )
        == 0
    )
    channels, meta = read_exr(folder / name)
    return channels["RAW"].astype(np.float64), meta


def test_two_frames_of_one_sensor_differ_by_temporal_noise_only(flat):
    """Frames 0 and 1 of seed 3: their difference has mean 0, variance 2 σ_y² (EMVA 1288 eq. 6 at their
    mean) and nothing of the fixed pattern; two seeds (two sensors) differ by the fixed pattern too; the
    same frame number gives the same frame, bit for bit."""
    folder, model = flat
    a, meta = _frame(folder, "a.exr", "--seed", "3", "--frame", "0")
    b, _ = _frame(folder, "b.exr", "--seed", "3", "--frame", "1")
    again, _ = _frame(folder, "c.exr", "--seed", "3", "--frame", "1")
    other, _ = _frame(folder, "d.exr", "--seed", "4", "--frame", "1")
    assert meta["frame"] == 0 and np.array_equal(b, again)
    g = green()
    mean = 0.5 * (a[g].mean() + b[g].mean())
    temporal = model.temporal_variance_dn2(mean, EXPOSURE_MS * 1e-3)
    diff = (a - b)[g]
    assert abs(diff.mean()) < 4 * np.sqrt(2 * temporal / diff.size)
    assert np.var(diff) == pytest.approx(2 * temporal, rel=0.05)
    gain, offset = fixed_pattern(model, SHAPE, 3)
    pattern = (model.gain_dn_per_e * (gain * (mean - model.black_level_dn) / model.gain_dn_per_e + offset))[g]
    assert abs(np.corrcoef(diff, pattern)[0, 1]) < 0.05  # one frame against the other: no fixed pattern left
    assert np.corrcoef(a[g], pattern)[0, 1] > 0.9  # while each frame holds it
    # two sensors: the fixed pattern of both in the difference, ≈ 2 (σ_y² + spatial variance)
    spatial = np.var(pattern)
    assert np.var((b - other)[g]) == pytest.approx(2 * (temporal + spatial), rel=0.05)
    assert spatial > 5 * temporal


def test_frame_numbers_from_python_are_the_commands(flat):
    folder, model = flat
    raw, _ = _frame(folder, "a.exr", "--seed", "5", "--frame", "7")
    image = read_exr(folder / "flat.exr")[0]
    irradiance = np.stack([image[c] for c in "RGB"], axis=-1).astype(np.float64)
    assert np.array_equal(raw, capture(model, irradiance, EXPOSURE_MS * 1e-3, 5, frame=7))


def test_a_negative_frame_number_is_refused(flat, capsys):
    folder, _ = flat
    code = main(
        [
            "camera",
            str(folder / "flat.exr"),
            "--sensor-model",
            str(folder / "sensor.toml"),
            "--exposure-ms",
            "1",
            "--frame",
            "-1",
            "-o",
            str(folder / "x.exr"),
        ]
    )
    assert code == 2 and "sensor frame -1 must be an integer >= 0" in capsys.readouterr().err
    assert not (folder / "x.exr").exists()


def test_auto_exposure_puts_the_percentile_at_its_fraction_of_saturation(tmp_path, capsys):
    """A frame lit 1 : 2 : 4 (R : G : B) left to right in three bands: auto:90,0.6 puts the 90th percentile
    pixel's mean signal at 0.6 of saturation. With RGGB and scalar QE the pixels' electron rates per second
    are eq. 1 times η_f; the chosen exposure, and the RAW's mean over the pixels at that rate, follow."""
    (tmp_path / "sensor.toml").write_text(SENSOR)
    model = load_sensor(tmp_path / "sensor.toml")
    image = np.zeros((64, 96, 3), np.float32)
    for band, level in enumerate((1.0, 2.0, 4.0)):
        image[:, 32 * band : 32 * band + 32] = level * 1e-3
    write_exr(tmp_path / "in.exr", dict(zip("RGB", np.moveaxis(image, -1, 0))))
    assert (
        main(
            [
                "camera",
                str(tmp_path / "in.exr"),
                "--sensor-model",
                str(tmp_path / "sensor.toml"),
                "--exposure-ms",
                "auto:90,0.6",
                "-o",
                str(tmp_path / "raw.exr"),
            ]
        )
        == 0
    )
    raw, meta = read_exr(tmp_path / "raw.exr")
    area = (model.pixel_pitch_um * 1e-6) ** 2
    rates = {}  # electrons per second of each (filter, band)
    for f, channel, qe in (("R", 0, model.qe_r), ("G", 1, model.qe_g), ("B", 2, model.qe_b)):
        for band, level in enumerate((1.0, 2.0, 4.0)):
            rates[f, band] = (
                float(np.float32(level * 1e-3))
                * area
                * model.wavelengths_nm[channel]
                * 1e-9
                / (PLANCK * LIGHT_SPEED)
                * qe
            )
    # the pixels sorted by rate: each (filter, band) holds 1/12 (R, B) or 1/6 (G) of them
    share = {k: (2 if k[0] == "G" else 1) / 12 for k in rates}
    ordered = sorted(rates, key=rates.get)
    cumulative = np.cumsum([share[k] for k in ordered])
    at = ordered[int(np.searchsorted(cumulative, 0.9))]
    saturation_e = model.saturation_dn / model.gain_dn_per_e
    expected_s = 0.6 * saturation_e / (rates[at] + model.dark_current_e_s)
    assert meta["exposure_ms"] == pytest.approx(expected_s * 1e3, rel=1e-9)
    assert meta["auto_exposure"]["percentile"] == 90 and meta["auto_exposure"]["fraction"] == 0.6
    sites = np.zeros(raw["RAW"].shape, dtype=bool)
    row, col = {"R": (0, 0), "G": (0, 1), "B": (1, 1)}[at[0]]
    sites[row::2, col::2] = True
    sites[:, : 32 * at[1]] = sites[:, 32 * at[1] + 32 :] = False
    signal = raw["RAW"][sites].mean() - model.black_level_dn
    assert signal == pytest.approx(0.6 * model.saturation_dn, rel=0.01)
    assert "exposure" in capsys.readouterr().out


@pytest.mark.parametrize(
    "value, says",
    [
        ("auto:99", "must be a time in ms, auto, or auto:P,F"),
        ("auto:0,0.5", "percentile 0.0 must be a number in \\(0, 100\\]"),
        ("auto:99,1.5", "fraction 1.5 must be a number in \\(0, 1\\]"),
        ("soon", "'soon' must be a time in ms"),
    ],
)
def test_bad_auto_exposures(flat, capsys, value, says):
    folder, _ = flat
    assert (
        main(
            [
                "camera",
                str(folder / "flat.exr"),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                value,
                "-o",
                str(folder / "x.exr"),
            ]
        )
        == 2
    )
    assert re.search(says, capsys.readouterr().err)


def test_auto_exposure_of_a_black_frame_is_refused(tmp_path, capsys):
    write_exr(tmp_path / "black.exr", {c: np.zeros((8, 8), np.float32) for c in "RGB"})
    assert (
        main(
            [
                "camera",
                str(tmp_path / "black.exr"),
                "--sensor-model",
                "imx490",
                "--exposure-ms",
                "auto",
                "-o",
                str(tmp_path / "x.exr"),
            ]
        )
        == 2
    )
    assert "gets no light" in capsys.readouterr().err and not (tmp_path / "x.exr").exists()


def _render_like(folder, f_number):
    """An EXR as a render through a lens writes it: radiance and its lens's f-number in the metadata."""
    image = np.random.default_rng(2).uniform(0.5, 1.5, (16, 24, 3)).astype(np.float32)
    write_exr(
        folder / "render.exr", dict(zip("RGB", np.moveaxis(image, -1, 0))), {"lens": "a-lens", "f_number": f_number}
    )
    return image.astype(np.float64)


def test_a_renders_own_f_number_is_read_and_a_given_one_wins(tmp_path, capsys):
    """No --f-number: the render's radiance through its own f/4 (E = π L / (4 · 16)), said on stderr and in
    the metadata; --f-number 2.8 is used instead, the disagreement stated."""
    radiance = _render_like(tmp_path, 4.0)
    model = load_sensor("imx490")
    argv = ["camera", str(tmp_path / "render.exr"), "--sensor-model", "imx490", "--exposure-ms", "5", "--seed", "2"]
    assert main([*argv, "-o", str(tmp_path / "own.exr")]) == 0
    err = capsys.readouterr().err
    assert "read as radiance through the camera equation at f/4" in err
    raw, meta = read_exr(tmp_path / "own.exr")
    assert np.array_equal(raw["RAW"], capture(model, np.pi * radiance / (4 * 4.0**2), 0.005, 2))
    assert meta["f_number"] == 4.0 and meta["f_number_source"] == "input metadata (lens a-lens)"
    assert main([*argv, "--f-number", "2.8", "-o", str(tmp_path / "given.exr")]) == 0
    assert "--f-number 2.8 differs from the image's own f/4" in capsys.readouterr().err
    raw, meta = read_exr(tmp_path / "given.exr")
    assert np.array_equal(raw["RAW"], capture(model, np.pi * radiance / (4 * 2.8**2), 0.005, 2))
    assert meta["f_number_source"] == "--f-number" and meta["f_number_of_input"] == 4.0


def test_a_renders_f_number_is_its_unit(doublet, tmp_path):
    """render-image writes the f-number N of its unit: a pixel value v is irradiance π v / (4 N²) per unit
    radiance, the ideal camera's π r_EP² / f'² (`illumination.ideal_irradiance`): N = f' / EPD."""
    from solas_mi.optics.paraxial import paraxial
    from solas_mi.render.image import render_image
    from solas_mi.render.spec import RenderSpec

    image = np.full((6, 8, 3), 0.5)
    result = render_image(doublet, image, RenderSpec(sensor=(6, 8), spp=1))
    epd = paraxial(doublet, doublet.primary_wavelength).entrance_pupil_diameter_mm
    assert result.meta["f_number"] == pytest.approx(result.meta["pinhole_focal_mm"] / epd, rel=1e-12)


def test_saturation_is_warned_of(flat, capsys):
    """At 10× the flat field's exposure every pixel clips: the warning names the fraction (from the RAW,
    `SensorModel.saturated`) and what to change; at the flat field's own exposure nothing is said."""
    folder, model = flat
    raw, meta = _frame(folder, "a.exr", "--exposure-ms", str(10 * EXPOSURE_MS))
    err = capsys.readouterr().err
    fraction = float(model.saturated(raw).mean())
    assert fraction > 0.5 and meta["saturated_fraction"] == fraction
    assert f"warning: {folder / 'a.exr'}: {100 * fraction:.1f} % of the RAW's pixels are saturated" in err
    assert "--exposure-ms auto" in err
    raw, meta = _frame(folder, "b.exr")
    assert "warning" not in capsys.readouterr().err and meta["saturated_fraction"] == 0.0


@pytest.mark.parametrize("isp", [None, "default"])
def test_memory_estimate_refuses_what_does_not_fit(flat, capsys, monkeypatch, isp):
    """With 64 MB free, a 256×128 frame is refused before it starts (the estimate from the measured bytes
    per pixel, `sensor.commands`, `isp.commands`), nothing written; --force runs it."""
    from solas_mi import budget
    from solas_mi.isp.commands import DEVELOP_BYTES_PER_PIXEL
    from solas_mi.sensor import commands

    folder, _ = flat
    monkeypatch.setattr(budget, "available_memory", lambda: 64e6)
    argv = [
        "camera",
        str(folder / "flat.exr"),
        "--sensor-model",
        str(folder / "sensor.toml"),
        "--exposure-ms",
        "1",
        *(["--isp", isp] if isp else []),
        "-o",
        str(folder / "x.exr"),
    ]
    assert main(argv) == 2
    per_pixel = max(
        commands.RAW_BYTES_PER_PIXEL,
        DEVELOP_BYTES_PER_PIXEL if isp else 0.0,
        3 * commands.READ_BYTES_PER_VALUE + commands.READ_BYTES_PER_PIXEL,
    )
    held = 8 * PATTERN_VALUES_PER_READOUT  # the fixed pattern held between frames
    need = commands.FIXED_BYTES + SHAPE[0] * SHAPE[1] * (per_pixel + held)
    assert f"camera 256x128 needs about {budget.size_text(need)} of memory and 64 MB is free" in capsys.readouterr().err
    assert not (folder / "x.exr").exists()
    assert main([*argv, "--force"]) == 0


def test_sensors_json_lists_every_preset(capsys):
    from solas_mi.sensor.files import describe, preset_names, preset_title

    assert main(["sensors", "--json"]) == 0
    listed = strict_loads(capsys.readouterr().out)
    assert [p["name"] for p in listed] == preset_names()
    for entry in listed:
        assert entry["title"] == preset_title(entry["name"])
        assert entry["sensor"] == describe(load_sensor(entry["name"]))


@pytest.mark.parametrize("own", ["x", 0.1, True])
def test_an_odd_f_number_in_the_metadata_is_named(tmp_path, capsys, own):
    """A header's f_number that no lens has is refused by name; a given --f-number reads the image anyway."""
    _render_like(tmp_path, own)
    argv = ["camera", str(tmp_path / "render.exr"), "--sensor-model", "imx490", "--exposure-ms", "5"]
    assert main([*argv, "-o", str(tmp_path / "a.exr")]) == 2
    err = capsys.readouterr().err
    assert f"the f_number in its metadata {own!r} must be a number from 0.5" in err and len(err.splitlines()) == 1
    assert main([*argv, "--f-number", "2", "-o", str(tmp_path / "b.exr")]) == 0
    assert "--f-number 2 differs from the image's own" in capsys.readouterr().err
