"""`solas-mi camera`: an EXR of irradiance (or radiance with --f-number) → the RAW frame, the sensor
described in a TOML file, the model and seed in the metadata, bad input refused with nothing written."""

import re

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.imageio import read_exr, write_exr
from solas_mi.sensor.capture import capture
from solas_mi.sensor.files import load_sensor
from solas_mi.sensor.model import SensorModel

TOML = """[sensor]
pixel_pitch_um = 2.0
cfa = "RCCB"
read_noise_e = 2.0
wavelengths_nm = [600, 530, 460]
"""


@pytest.fixture
def inputs(tmp_path):
    image = np.empty((24, 32, 3), dtype=np.float32)
    image[...] = (0.02, 0.03, 0.01)
    write_exr(tmp_path / "in.exr", dict(zip("RGB", np.moveaxis(image, -1, 0))))
    (tmp_path / "sensor.toml").write_text(TOML)
    return tmp_path, image.astype(np.float64)


def test_raw_with_model_and_seed(inputs):
    folder, image = inputs
    assert (
        main(
            [
                "camera",
                str(folder / "in.exr"),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                "5",
                "--seed",
                "11",
                "-o",
                str(folder / "raw.exr"),
            ]
        )
        == 0
    )
    channels, meta = read_exr(folder / "raw.exr")
    model = SensorModel(pixel_pitch_um=2.0, cfa="RCCB", read_noise_e=2.0, wavelengths_nm=(600, 530, 460))
    assert list(channels) == ["RAW"] and np.array_equal(channels["RAW"], capture(model, image, 0.005, 11))
    assert meta["seed"] == 11 and meta["exposure_ms"] == 5 and meta["unit"] == "DN"
    assert SensorModel.from_dict(meta["sensor"]) == model


def test_radiance_through_the_camera_equation(inputs):
    """With --f-number the image is radiance: the RAW equals the capture of π T L / (4 N²)."""
    folder, image = inputs
    assert (
        main(
            [
                "camera",
                str(folder / "in.exr"),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                "5",
                "--f-number",
                "2.8",
                "--transmission",
                "0.9",
                "--scale",
                "100",
                "-o",
                str(folder / "raw.exr"),
            ]
        )
        == 0
    )
    expected = capture(load_sensor(folder / "sensor.toml"), np.pi * 0.9 * 100 * image / (4 * 2.8**2), 0.005, 0)
    assert np.array_equal(read_exr(folder / "raw.exr")[0]["RAW"], expected)


@pytest.mark.parametrize(
    "toml, extra, message",
    [
        ("[sensor]\nfull_wel = 10\n", [], "unknown sensor parameter.*full_wel"),
        ("[sensor]\nbit_depth = 20\n", [], "bit_depth = 20 must be an integer from 8 to 16"),
        ("[sensors]\n", [], "must hold one \\[sensor\\] table"),
        ("[sensor\n", [], "is not valid TOML"),
        (TOML, ["--exposure-ms", "0"], "--exposure-ms 0.0 must be > 0"),
        (TOML, ["--transmission", "0.5"], "--transmission applies with --f-number"),
        (TOML, ["--f-number", "0"], "f-number 0.0 must be"),
        (TOML, ["--seed", "-1"], "sensor seed -1 must be an integer >= 0"),
        (TOML, ["--exposure-ms", "inf"], "--exposure-ms inf must be > 0 and finite"),
        (TOML, ["--seed", "2147483648"], "sensor seed 2147483648 must be an integer >= 0 and at most 2\\^31 - 1"),
        (TOML, ["--exposure-ms", "nan"], "--exposure-ms nan must be > 0 and finite"),
        (TOML, ["--scale", "inf"], "--scale inf must be > 0 and finite"),
        (TOML, ["--scale", "-2"], "--scale -2.0 must be > 0"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(inputs, capsys, toml, extra, message):
    folder, _ = inputs
    (folder / "sensor.toml").write_text(toml)
    argv = [
        "camera",
        str(folder / "in.exr"),
        "--sensor-model",
        str(folder / "sensor.toml"),
        "--exposure-ms",
        "5",
        *extra,
        "-o",
        str(folder / "raw.exr"),
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert re.search(message, err), err
    assert sorted(p.name for p in folder.iterdir()) == ["in.exr", "sensor.toml"]


def test_output_may_not_be_the_input(inputs, capsys):
    folder, _ = inputs
    assert (
        main(
            [
                "camera",
                str(folder / "in.exr"),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                "5",
                "-o",
                str(folder / "in.exr"),
            ]
        )
        == 2
    )
    assert "is an input" in capsys.readouterr().err


def test_developed_frame_beside_the_raw(inputs, tmp_path):
    """--isp default: the RAW EXR as without it, the developed frame OUT.png beside it equals `develop`
    of that RAW, and the metadata names every stage."""
    import imageio.v3 as iio

    from solas_mi.isp.pipeline import develop

    folder, _image = inputs
    args = ["camera", str(folder / "in.exr"), "--sensor-model", str(folder / "sensor.toml"), "--exposure-ms", "5"]
    assert main([*args, "-o", str(folder / "raw.exr")]) == 0
    assert main([*args, "--isp", "default", "-o", str(folder / "cam.exr")]) == 0
    channels, meta = read_exr(folder / "cam.exr")
    assert np.array_equal(channels["RAW"], read_exr(folder / "raw.exr")[0]["RAW"])
    frame, developed = develop(channels["RAW"], load_sensor(folder / "sensor.toml"))
    assert np.array_equal(iio.imread(folder / "cam.png"), frame)
    assert meta["developed_frame"] == "cam.png" and meta["stages"] == developed["stages"]
    assert list(meta["stages"]) == ["black_level", "white_balance", "demosaic", "ccm", "tone"]


def test_bad_isp_writes_nothing(inputs, capsys):
    folder, _ = inputs
    code = main(
        [
            "camera",
            str(folder / "in.exr"),
            "--sensor-model",
            str(folder / "sensor.toml"),
            "--exposure-ms",
            "5",
            "--isp",
            str(folder / "missing.toml"),
            "-o",
            str(folder / "cam.exr"),
        ]
    )
    assert code == 2 and "must be 'default' or a TOML file" in capsys.readouterr().err
    assert not (folder / "cam.exr").exists() and not (folder / "cam.png").exists()


def test_negative_values_are_no_light_as_in_a_batch(inputs, capsys):
    """A spectral render's RGB is negative outside the gamut: `camera` reads those values as no light
    (as a batch's camera does, one rule: `exposure.negatives_as_no_light`), the RAW equals the capture
    of the image with them at 0, their count in the metadata and a one-line notice on stderr."""
    folder, image = inputs
    image[3, 4, 2] = -0.004
    image[5, 6, 0] = -1e-8  # round-off: counted, no notice of its own
    write_exr(folder / "neg.exr", dict(zip("RGB", np.moveaxis(image.astype(np.float32), -1, 0))))
    assert (
        main(
            [
                "camera",
                str(folder / "neg.exr"),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                "5",
                "-o",
                str(folder / "raw.exr"),
            ]
        )
        == 0
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search("1 values below zero \\(least -0.004.*read as no light", err[0]), err
    channels, meta = read_exr(folder / "raw.exr")
    expected = capture(load_sensor(folder / "sensor.toml"), np.maximum(image.astype(np.float32), 0.0), 0.005, 0)
    assert np.array_equal(channels["RAW"], expected)
    negative = meta["negative_values_taken_as_zero"]
    assert negative["count"] == 2 and negative["beyond_round_off"] == 1
    assert negative["least"] == pytest.approx(-0.004)


def _odd_inputs(folder):
    """Inputs a newcomer may give `camera`: a PNG, a grey one-channel EXR, an EXR with a NaN."""
    import OpenEXR

    grey = np.full((6, 8), 0.5, np.float32)
    write_exr(folder / "grey.exr", {"Y": grey})
    nan = grey.copy()
    nan[2, 3] = np.nan  # our writer refuses NaN: written with OpenEXR itself, as another tool would
    OpenEXR.File(
        {"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION}, {"R": grey, "G": nan, "B": grey}
    ).write(str(folder / "nan.exr"))
    (folder / "photo.png").write_bytes(b"\x89PNG\r\n\x1a\n")


@pytest.mark.parametrize(
    "image, output, message",
    [
        (
            "photo.png",
            "raw.exr",
            "photo.png: the sensor reads an OpenEXR image of linear irradiance .*not a .png file; "
            "give the EXR of a render",
        ),
        ("grey.exr", "raw.exr", "channels R, G, B missing; the sensor needs R, G and B \\(found Y\\)"),
        ("nan.exr", "raw.exr", "1 values are NaN or infinite \\(the first at row 2, column 3, channel 1\\)"),
        ("in.exr", "raw.png", "raw.png' must end in .exr"),
    ],
)
def test_odd_inputs_are_one_line_and_write_nothing(inputs, capsys, image, output, message):
    """Without --isp too, the RAW goes to an .exr (a .png name held EXR data); a PNG input is named as
    such, not as an unreadable EXR."""
    folder, _ = inputs
    _odd_inputs(folder)
    before = sorted(p.name for p in folder.iterdir())
    assert (
        main(
            [
                "camera",
                str(folder / image),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                "5",
                "-o",
                str(folder / output),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and re.search(message, err), err
    assert sorted(p.name for p in folder.iterdir()) == before


def test_huge_exposure_saturates(inputs, capsys):
    """An exposure of 10⁶ s fills every well (here below the ADC's white level: 10000 e⁻ × 0.25 DN/e⁻ +
    64): the RAW at the full well, every pixel reported saturated (not "0 at the white level")."""
    folder, _ = inputs
    assert (
        main(
            [
                "camera",
                str(folder / "in.exr"),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                "1e9",
                "-o",
                str(folder / "raw.exr"),
            ]
        )
        == 0
    )
    raw = read_exr(folder / "raw.exr")[0]["RAW"]
    assert np.abs(raw - (64 + 2500)).max() <= 3
    assert f"{raw.size} pixels saturated" in capsys.readouterr().out
    assert (
        main(
            [
                "camera",
                str(folder / "in.exr"),
                "--sensor-model",
                str(folder / "sensor.toml"),
                "--exposure-ms",
                "5",
                "-o",
                str(folder / "dim.exr"),
            ]
        )
        == 0
    )
    assert " 0 pixels saturated" in capsys.readouterr().out


def test_labelled_render_with_a_preset(inputs):
    """An EXR with label layers beside R, G, B (as `render --labels` writes): `camera --sensor-model
    PRESET --exposure-ms T --isp default --seed S` reads R, G, B only; the RAW holds one channel (the
    labels stay in the render's EXR, not carried over)."""
    folder, image = inputs
    layers = {
        "depth.Z": np.full(image.shape[:2], 12.5, np.float32),
        "instance.id": np.full(image.shape[:2], 7.0, np.float32),
        "labels.valid": np.ones(image.shape[:2], np.float32),
    }
    write_exr(
        folder / "labelled.exr",
        {**dict(zip("RGB", np.moveaxis(image.astype(np.float32), -1, 0))), **layers},
        {"labels": {"kinds": ["depth", "instance"]}},
    )
    assert (
        main(
            [
                "camera",
                str(folder / "labelled.exr"),
                "--sensor-model",
                "imx490",
                "--exposure-ms",
                "2",
                "--isp",
                "default",
                "--seed",
                "4",
                "-o",
                str(folder / "out.exr"),
            ]
        )
        == 0
    )
    channels, meta = read_exr(folder / "out.exr")
    assert list(channels) == ["RAW"] and meta["sensor_model"] == "imx490" and meta["seed"] == 4
    assert np.array_equal(channels["RAW"], capture(load_sensor("imx490"), image, 0.002, 4))
    assert (folder / "out.png").is_file()
