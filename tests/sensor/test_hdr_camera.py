"""An HDR sensor through the whole chain: `solas-mi camera` writes its merged (or companded) RAW with every
stage named in the metadata, auto-exposure meters it, the image processor decompands and develops it, and a
batch's camera takes it."""

import json
import math

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.imageio import read_exr, srgb_encode, write_exr
from solas_mi.isp.camera import Camera
from solas_mi.isp.pipeline import ISP, develop
from solas_mi.isp.tone import LOG_FLOOR, encode
from solas_mi.sensor.auto_exposure import AutoExposure
from solas_mi.sensor.capture import capture
from solas_mi.sensor.chain import STAGES
from solas_mi.sensor.files import PRESETS, load_sensor

KNEES = [[0, 0], [4096, 2048], [65536, 3072], [16777215, 3927]]  # 3927 + black 168 = 4095


def scene(tmp_path):
    """A ramp over five decades of irradiance (W/m²)."""
    ramp = np.geomspace(1e-3, 1e2, 64, dtype=np.float32)
    image = np.broadcast_to(ramp[None, :, None], (16, 64, 3)).copy()
    write_exr(tmp_path / "in.exr", dict(zip("RGB", np.moveaxis(image, -1, 0))))
    return image.astype(np.float64)


def companded(tmp_path):
    """The IMX490-class preset with a compander after its merge, as a file."""
    text = (PRESETS / "imx490-hdr.toml").read_text(encoding="utf-8")
    text += f"\n[sensor.compander]\nknees = {json.dumps(KNEES)}\nbit_depth = 12\nblack_level_dn = 168\n"
    (tmp_path / "hdr.toml").write_text(text, encoding="utf-8")
    return tmp_path / "hdr.toml"


def test_camera_writes_the_merged_raw_and_names_the_stages(tmp_path, capsys):
    image = scene(tmp_path)
    assert (
        main(
            [
                "camera",
                str(tmp_path / "in.exr"),
                "--sensor-model",
                "imx490-hdr",
                "--exposure-ms",
                "10",
                "--seed",
                "4",
                "-o",
                str(tmp_path / "raw.exr"),
            ]
        )
        == 0
    )
    channels, meta = read_exr(tmp_path / "raw.exr")
    sensor = load_sensor("imx490-hdr")
    assert np.array_equal(channels["RAW"], capture(sensor, image, 0.01, 4).astype(np.float32))
    assert channels["RAW"].max() > 4095  # past the 12 bits of one readout: the merged signal
    stages = [s["stage"] for s in meta["sensor"]["stages"]]
    assert stages == ["photons", *["readout"] * 4, "merge"] and set(stages) <= set(STAGES)
    assert [s["name"] for s in meta["sensor"]["stages"] if s["stage"] == "readout"] == [
        "large-HCG",
        "large-LCG",
        "small-HCG",
        "small-LCG",
    ]
    assert "24 bit" in capsys.readouterr().out


def test_auto_exposure_meters_the_reference_photodiode(tmp_path):
    """auto:99,0.8 puts the 99th percentile at 80 % of the merged signal's saturation."""
    scene(tmp_path)
    assert (
        main(
            [
                "camera",
                str(tmp_path / "in.exr"),
                "--sensor-model",
                "imx490-hdr",
                "--exposure-ms",
                "auto",
                "-o",
                str(tmp_path / "raw.exr"),
            ]
        )
        == 0
    )
    _, meta = read_exr(tmp_path / "raw.exr")
    chosen = meta["auto_exposure"]
    assert chosen["saturation_e"] == load_sensor("imx490-hdr").saturation_e == 79000.0
    assert chosen["exposure_ms"] * 1e-3 == 0.8 * 79000.0 / (chosen["percentile_e_per_s"] + 25.6)


def test_the_image_processor_decompands_a_companded_raw(tmp_path):
    """The developed frame of the companded RAW is that of the merged one (the same readouts), within the
    companding step: decompanding undoes it."""
    path = companded(tmp_path)
    image = scene(tmp_path)
    sensor = load_sensor(path)
    merged_sensor = load_sensor("imx490-hdr")
    raw = capture(sensor, image, 0.01, 2)
    assert raw.dtype == np.uint16 and raw.min() >= 168 and raw.max() <= 4095
    frame, developed = develop(raw, sensor, ISP(tone="none"))
    reference, _ = develop(capture(merged_sensor, image, 0.01, 2), merged_sensor, ISP(tone="none"))
    assert developed["stages"]["black_level"]["decompanded_through"] == KNEES
    assert developed["stages"]["black_level"]["black_dn"] == 64  # the merged signal's, before companding
    assert np.abs(frame.astype(int) - reference).max() <= 1
    assert (
        main(
            [
                "camera",
                str(tmp_path / "in.exr"),
                "--sensor-model",
                str(path),
                "--exposure-ms",
                "10",
                "--isp",
                "default",
                "-o",
                str(tmp_path / "raw.exr"),
            ]
        )
        == 0
    )
    assert (tmp_path / "raw.png").exists()


def test_a_batch_camera_takes_an_hdr_sensor(tmp_path):
    image = scene(tmp_path)
    camera = Camera(load_sensor("imx490-hdr"), 10.0, ISP(), seed=3)
    raw, frame, meta = camera.shoot(image, "frame000")
    assert raw.dtype == np.uint32 and frame.shape == (16, 64, 3)
    assert meta["camera"]["sensor"]["stages"][-1] == {
        "stage": "merge",
        "bits": 24,
        "threshold": 0.9,
        "blend": 0.0,
        "black_level_dn": 64,
    }


def test_reinhard_tone_maps_by_its_formula():
    """Two grey levels a and b, half the frame each: log-average Ȳ = sqrt((a + δ)(b + δ)), L = 0.18 Y / Ȳ, the
    brighter at L_w maps to 1."""
    a, b = 1e-4, 0.4
    image = np.concatenate([np.full((4, 4, 3), a), np.full((4, 4, 3), b)])
    got = encode(image, "reinhard")
    mean = math.sqrt((a + LOG_FLOOR) * (b + LOG_FLOOR))
    low, high = 0.18 * a / mean, 0.18 * b / mean
    expected = low * (1 + low / high**2) / (1 + low)
    assert got[0, 0, 0] == pytest.approx(float(srgb_encode(np.array(expected))), rel=1e-9)
    assert np.allclose(got[-1], 1.0)


def test_an_hdr_frame_keeps_its_shadows_through_reinhard():
    """A ramp over five decades exposed so that its top sits at 80 % of the merged signal's saturation: the
    sRGB curve crushes its lower decades to black (codes <= 5), Reinhard's operator keeps them."""
    sensor = load_sensor("imx490-hdr")
    ramp = np.broadcast_to(np.geomspace(1e-3, 1e2, 256)[None, :, None], (8, 256, 3))
    seconds, _ = AutoExposure(100.0, 0.8).choose(sensor, ramp)
    raw = capture(sensor, ramp, seconds, 1)
    crushed = {}
    for curve in ("srgb", "reinhard"):
        frame, meta = develop(raw, sensor, ISP(tone=curve, demosaic="none", ccm="none", white_balance="none"))
        crushed[curve] = int(np.count_nonzero(frame[4, :, 1] <= 5))
        assert meta["stages"]["tone"]["curve"] == curve
    assert crushed["srgb"] > 100 and crushed["reinhard"] < crushed["srgb"] / 4


def test_the_memory_check_counts_the_readouts(tmp_path, monkeypatch, capsys):
    """An HDR sensor's chain holds more per pixel than one readout's: its merge and each further readout."""
    from solas_mi import budget
    from solas_mi.sensor import commands
    from solas_mi.sensor.readout import PATTERN_VALUES_PER_READOUT

    write_exr(tmp_path / "big.exr", {c: np.full((1000, 1000), 0.01, dtype=np.float32) for c in "RGB"})
    monkeypatch.setattr(budget, "available_memory", lambda: 64e6)
    assert (
        main(
            [
                "camera",
                str(tmp_path / "big.exr"),
                "--sensor-model",
                "imx490-hdr",
                "--exposure-ms",
                "1",
                "-o",
                str(tmp_path / "x.exr"),
            ]
        )
        == 2
    )
    held = 8 * PATTERN_VALUES_PER_READOUT  # the fixed pattern held between frames, per readout
    per_pixel = commands.RAW_BYTES_PER_PIXEL + commands.MERGE_BYTES_PER_PIXEL + 3 * commands.READOUT_BYTES_PER_PIXEL
    flat = commands.RAW_BYTES_PER_PIXEL + held
    need, flat = (commands.FIXED_BYTES + 1e6 * bytes_ for bytes_ in (per_pixel + 4 * held, flat))
    assert budget.size_text(need) != budget.size_text(flat)
    assert f"camera 1000x1000 needs about {budget.size_text(need)} of memory" in capsys.readouterr().err
