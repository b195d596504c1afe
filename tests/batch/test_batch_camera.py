"""Batches through a camera (`--sensor-model`, `--exposure-ms`, `--isp`): each item's RAW and developed
frame beside it, seeded by the batch's seed and the frame's name (not its place in the run), the camera
in the outputs, the manifest and the batch's identity; resume, Dask and the options' errors."""

from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi.batch import degrade_batch
from solas_mi.batch.render import render_batch
from solas_mi.cli import main
from solas_mi.convolution.spec import DegradeSpec
from solas_mi.imageio import read_exr
from solas_mi.isp.camera import Camera, frame_number, load_camera
from solas_mi.isp.pipeline import ISP, develop
from solas_mi.sensor.capture import capture
from solas_mi.sensor.commands import read_rgb
from solas_mi.sensor.model import SensorModel
from solas_mi.sensor.timing import SceneInTime

SENSOR = '[sensor]\ncfa = "RCCB"\npixel_pitch_um = 2.0\n'
EXPOSURE_MS = 0.25  # the frames' values (0…1) read as W/m²: 2300–3100 photons per channel at 1 (2 µm pixels)


def manifest(folder):
    return strict_loads((folder / "batch.json").read_text())


@pytest.fixture
def camera_inputs(batch_inputs):
    batch_inputs.write(3)
    (batch_inputs.root / "sensor.toml").write_text(SENSOR)
    return batch_inputs


def _argv(inputs, out, *extra):
    return [
        "batch",
        "degrade",
        str(inputs.images),
        "--psf-grid",
        str(inputs.grid),
        "-o",
        str(out),
        "--workers",
        "1",
        "--quiet",
        "--sensor-model",
        str(inputs.root / "sensor.toml"),
        "--exposure-ms",
        str(EXPOSURE_MS),
        *extra,
    ]


def test_degrade_batch_writes_each_frames_raw_and_developed_frame(camera_inputs):
    out = camera_inputs.root / "out"
    assert main(_argv(camera_inputs, out, "--isp", "default", "--seed", "5")) == 0
    m = manifest(out)
    model = SensorModel(cfa="RCCB", pixel_pitch_um=2.0)
    assert m["camera"]["seed"] == 5 and m["camera"]["isp"] == ISP().describe()
    assert SensorModel.from_dict(m["camera"]["sensor"]) == model
    for item in m["items"]:
        stem = item["output"][:-4]
        assert set(item["outputs"]) == {item["output"], item["png"], f"{stem}_raw.exr", f"{stem}_raw.png"}
        channels, meta = read_exr(f"{stem}_raw.exr")
        name = stem.rsplit("/", 1)[-1]
        expected = capture(model, read_rgb(item["output"]), EXPOSURE_MS * 1e-3, 5, frame_number(name))
        assert np.array_equal(channels["RAW"], expected) and 0 < expected.mean() < model.white_level_dn
        assert meta["frame"] == name and meta["batch"]["id"] == m["batch_id"]
        assert np.array_equal(iio.imread(f"{stem}_raw.png"), develop(expected, model, ISP())[0])
    # a re-run skips every item; a developed frame removed is made again
    assert main(_argv(camera_inputs, out, "--isp", "default", "--seed", "5")) == 0
    assert manifest(out)["summary"] == {"skipped": 3}
    (out / "frame001_raw.png").unlink()
    assert main(_argv(camera_inputs, out, "--isp", "default", "--seed", "5")) == 0
    assert manifest(out)["summary"] == {"skipped": 2, "done": 1}


def test_degrade_batch_with_a_flickering_box(camera_inputs):
    """--flicker in a batch: each frame's box is PWM-driven light over the exposure, as `camera --flicker` has it
    (`timing.SceneInTime`), recorded with the camera; at a phase off over the whole exposure the box reads dark."""
    out = camera_inputs.root / "out"
    # 90 Hz at 10 %, phase 0.5: on from 5.6 ms of each 11.1 ms period, off over the 0.25 ms exposure
    assert main(_argv(camera_inputs, out, "--flicker", "0,0,4,3,90,0.1,0.5")) == 0
    m = manifest(out)
    assert m["camera"]["flicker"] == {"box": [0, 0, 4, 3], "frequency_hz": 90.0, "duty_cycle": 0.1, "phase": 0.5}
    model = SensorModel(cfa="RCCB", pixel_pitch_um=2.0)
    for item in m["items"]:
        stem = item["output"][:-4]
        raw = read_exr(f"{stem}_raw.exr")[0]["RAW"]
        image = read_rgb(item["output"])
        dark = image.copy()
        dark[0:3, 0:4] = 0.0
        assert np.array_equal(raw, capture(model, dark, EXPOSURE_MS * 1e-3, 0, frame_number(stem.rsplit("/", 1)[-1])))


def test_frames_depend_on_seed_and_name_not_on_the_run(camera_inputs):
    """One input alone gives the frame it gave among three; another seed, another frame (and another
    batch identity); without the camera, yet another identity."""
    root = camera_inputs.root
    camera = load_camera(str(root / "sensor.toml"), EXPOSURE_MS, None, 2)
    all_three = degrade_batch(
        [camera_inputs.images],
        root / "all",
        psf_grid=camera_inputs.grid,
        workers=2,
        progress=False,
        spec=DegradeSpec(camera=camera),
    )
    alone = degrade_batch(
        [camera_inputs.images / "frame002.png"],
        root / "alone",
        psf_grid=camera_inputs.grid,
        workers=1,
        progress=False,
        spec=DegradeSpec(camera=camera),
    )
    other = degrade_batch(
        [camera_inputs.images / "frame002.png"],
        root / "other",
        psf_grid=camera_inputs.grid,
        workers=1,
        progress=False,
        spec=DegradeSpec(camera=Camera(camera.sensor, EXPOSURE_MS, None, 3)),
    )
    plain = degrade_batch(
        [camera_inputs.images / "frame002.png"], root / "plain", psf_grid=camera_inputs.grid, workers=1, progress=False
    )
    raw = {k: read_exr(root / k / "frame002_raw.exr")[0]["RAW"] for k in ("all", "alone", "other")}
    assert np.array_equal(raw["all"], raw["alone"]) and not np.array_equal(raw["alone"], raw["other"])
    assert not (root / "all" / "frame002_raw.png").exists()  # no isp: the RAW only
    assert len({manifest(r.manifest.parent)["batch_id"] for r in (all_three, alone, other, plain)}) == 3
    assert manifest(root / "all")["batch_id"] == manifest(root / "alone")["batch_id"]


@pytest.mark.slow
def test_dask_gives_the_same_frames(camera_inputs):
    camera = load_camera(str(camera_inputs.root / "sensor.toml"), EXPOSURE_MS, "default", 0)
    for where, dask in (("local", None), ("dask", "local")):
        degrade_batch(
            [camera_inputs.images],
            camera_inputs.root / where,
            psf_grid=camera_inputs.grid,
            workers=1,
            dask=dask,
            progress=False,
            spec=DegradeSpec(camera=camera),
        )
    for name in ("frame000_raw.exr", "frame000_raw.png", "frame002_raw.exr"):
        assert (camera_inputs.root / "local" / name).read_bytes() == (
            camera_inputs.root / "dask" / name
        ).read_bytes() or (
            name.endswith(".exr")
            and np.array_equal(
                read_exr(camera_inputs.root / "local" / name)[0]["RAW"],
                read_exr(camera_inputs.root / "dask" / name)[0]["RAW"],
            )
        )


def test_render_batch_through_the_camera(camera_inputs, tmp_path):
    camera = load_camera(str(camera_inputs.root / "sensor.toml"), EXPOSURE_MS, "default", 7)
    result = render_batch(
        [camera_inputs.images / "frame000.png"],
        tmp_path / "r",
        lens="solas-doublet",
        sensor="16x12",
        spp=1,
        workers=1,
        progress=False,
        camera=camera,
        seed=7,
    )
    (job,) = result.jobs
    assert job.status == "done", job.error
    channels, meta = read_exr(tmp_path / "r" / "frame000_raw.exr")
    assert channels["RAW"].shape == (12, 16) and meta["camera"]["seed"] == 7
    # one spectral sample per pixel: RGB outside the gamut, negative, read as no light and counted
    assert meta["negative_values_taken_as_zero"]["count"] >= 0
    # the render's radiance read through the f-number it states, as `solas-mi camera` reads it
    render, own = read_exr(tmp_path / "r" / "frame000.exr")
    radiance = np.maximum(np.stack([render[c] for c in "RGB"], axis=-1).astype(np.float64), 0.0)
    assert meta["f_number"] == own["f_number"] and meta["f_number_source"].startswith("input metadata")
    expected = capture(
        camera.sensor, np.pi * radiance / (4 * own["f_number"] ** 2), EXPOSURE_MS * 1e-3, 7, frame_number("frame000")
    )
    assert np.array_equal(channels["RAW"], expected)
    assert manifest(tmp_path / "r")["camera"] == camera.describe()
    assert iio.imread(tmp_path / "r" / "frame000_raw.png").shape == (12, 16, 3)


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--isp", "default"], "--isp go\\(es\\) with --sensor-model"),
        (["--sensor-model", "S"], "--sensor-model needs --exposure-ms"),
        (["--sensor-model", "S", "--exposure-ms", "1", "--format", "png16"], "not png16"),
        (["--sensor-model", "S", "--exposure-ms", "0"], "--exposure-ms 0.0 must be > 0"),
        (["--scale", "2"], "--scale go\\(es\\) with --sensor-model"),
        (["--flicker", "0,0,4,4,90,0.1"], "--flicker go\\(es\\) with --sensor-model"),
        (["--sensor-model", "S", "--exposure-ms", "1", "--image-motion", "1"], "--image-motion '1' must be VX,VY"),
        (["--sensor-model", "S", "--exposure-ms", "1", "--scale", "-1"], "scale -1.0 must be a finite number > 0"),
        (["--sensor-model", "S", "--exposure-ms", "auto:0,1"], "auto-exposure percentile 0.0 must be"),
        # gains for a sensor's filters the RCCB sensor lacks: each item failed after its work (exit 1)
        (["--sensor-model", "S", "--exposure-ms", "1", "--isp", "I"], "must give a number > 0 for each filter of RCCB"),
    ],
)
def test_camera_options_refused(camera_inputs, extra, message, capsys):
    (camera_inputs.root / "gains.toml").write_text("[isp]\nwhite_balance = {R = 1.9, G = 1, B = 1.5}\n")
    files = {"S": "sensor.toml", "I": "gains.toml"}
    extra = [str(camera_inputs.root / files[e]) if e in files else e for e in extra]
    argv = [
        "batch",
        "degrade",
        str(camera_inputs.images),
        "--psf-grid",
        str(camera_inputs.grid),
        "-o",
        str(camera_inputs.root / "never"),
        "--quiet",
        *extra,
    ]
    assert main(argv) == 2
    import re

    assert re.search(message, capsys.readouterr().err)
    assert not (camera_inputs.root / "never" / "frame000.exr").exists()


def test_a_preset_by_name_from_the_cli_and_python(camera_inputs, tmp_path):
    """`batch degrade ... --sensor-model imx490` (a shipped preset's name, not a file) from the command
    line, and `load_camera("imx490", ...)` from Python: the same RAW frames, the preset's model in the
    manifest."""
    from solas_mi.sensor.files import load_sensor

    argv = _argv(camera_inputs, tmp_path / "cli", "--seed", "3")
    argv[argv.index("--sensor-model") + 1] = "imx490"
    assert main(argv) == 0
    preset = load_sensor("imx490")
    assert SensorModel.from_dict(manifest(tmp_path / "cli")["camera"]["sensor"]) == preset
    camera = load_camera("imx490", EXPOSURE_MS, None, 3)
    assert camera.sensor == preset
    result = degrade_batch(
        [camera_inputs.images],
        tmp_path / "py",
        psf_grid=camera_inputs.grid,
        workers=1,
        progress=False,
        spec=DegradeSpec(camera=camera),
    )
    assert [job.status for job in result.jobs] == ["done"] * 3
    for name in ("frame000", "frame001", "frame002"):
        raw = read_exr(tmp_path / "cli" / f"{name}_raw.exr")[0]["RAW"]
        assert np.array_equal(raw, read_exr(tmp_path / "py" / f"{name}_raw.exr")[0]["RAW"])
        assert raw.mean() > preset.black_level_dn + 10  # light reached the sensor


def test_scale_auto_exposure_and_saturation_warnings(camera_inputs, capsys):
    """--scale reads each frame's values times the scale (the RAW is the capture of scale × the frame);
    at 100 × EXPOSURE_MS the frames clip and the batch warns, naming each RAW's saturated fraction and what
    to change (also in the manifest); --exposure-ms auto chooses each frame's exposure from its own light,
    stated in its metadata, and nothing clips past 1 %."""
    root = camera_inputs.root
    model = SensorModel(cfa="RCCB", pixel_pitch_um=2.0)
    assert main(_argv(camera_inputs, root / "scaled", "--scale", "0.5")) == 0
    item = manifest(root / "scaled")["items"][0]
    stem = item["output"][:-4]
    name = stem.rsplit("/", 1)[-1]
    channels, meta = read_exr(f"{stem}_raw.exr")
    expected = capture(model, 0.5 * read_rgb(item["output"]), EXPOSURE_MS * 1e-3, 0, frame_number(name))
    assert np.array_equal(channels["RAW"], expected) and meta["scale"] == 0.5 and meta["camera"]["scale"] == 0.5
    assert "warning" not in capsys.readouterr().err

    argv = _argv(camera_inputs, root / "bright")
    argv[argv.index("--exposure-ms") + 1] = str(100 * EXPOSURE_MS)
    assert main(argv) == 0
    err = capsys.readouterr().err
    for item in manifest(root / "bright")["items"]:
        raw_path = item["output"][:-4] + "_raw.exr"
        channels, meta = read_exr(raw_path)
        fraction = float(model.saturated(channels["RAW"]).mean())
        assert fraction > 0.5 and meta["saturated_fraction"] == fraction
        text = f"{raw_path.rsplit('/', 1)[-1]}: {100 * fraction:.1f} % of the RAW's pixels are saturated"
        assert text in err and item["warnings"] and text in item["warnings"][0]

    argv[argv.index("--exposure-ms") + 1] = "auto"
    assert main([*argv[: argv.index("-o") + 1], str(root / "auto"), *argv[argv.index("-o") + 2 :]]) == 0
    assert "warning" not in capsys.readouterr().err
    for item in manifest(root / "auto")["items"]:
        channels, meta = read_exr(item["output"][:-4] + "_raw.exr")
        assert meta["auto_exposure"]["percentile"] == 99 and meta["camera"]["exposure_ms"] == "auto"
        assert meta["exposure_ms"] == pytest.approx(meta["auto_exposure"]["exposure_ms"])
        assert model.saturated(channels["RAW"]).mean() <= 0.01


def test_the_estimate_counts_the_camera(camera_inputs, tmp_path):
    """A 2000×1500 render batch through the camera and processor: the camera's peak (its measured bytes per
    pixel, `sensor.commands.frame_bytes`) passes the render's own, and the estimate says it."""
    from solas_mi.batch.degrade import WORKER_BYTES
    from solas_mi.batch.render import estimate, plan_render
    from solas_mi.isp.commands import DEVELOP_BYTES_PER_PIXEL
    from solas_mi.sensor.commands import frame_bytes

    camera = load_camera(str(camera_inputs.root / "sensor.toml"), EXPOSURE_MS, "default", 0)
    p = plan_render(
        [camera_inputs.images / "frame000.png"],
        tmp_path / "r",
        lens="solas-doublet",
        camera=camera,
        sensor="2000x1500",
        spp=1,
    )
    assert estimate(p, 1)["peak_bytes"] == frame_bytes(1500, 2000, 3, DEVELOP_BYTES_PER_PIXEL) + WORKER_BYTES["render"]


@pytest.mark.parametrize("in_time", [None, SceneInTime(motion_px_s=(40.0, 0.0))])
def test_the_estimate_counts_hdr_readouts_and_a_scene_in_time(camera_inputs, tmp_path, in_time):
    """A 2000×1500 render batch through the four-readout imx490-hdr camera (with the image's motion, or still):
    the estimate is the camera's frame of four readouts (and the scene in time's images), more than one
    readout's — the camera command's own count (`sensor.commands.frame_bytes`)."""
    from solas_mi.batch.degrade import WORKER_BYTES
    from solas_mi.batch.render import estimate, plan_render
    from solas_mi.sensor.capture import as_chain
    from solas_mi.sensor.commands import frame_bytes

    camera = load_camera("imx490-hdr", EXPOSURE_MS, None, 0, scene_in_time=in_time)
    readouts = len(as_chain(camera.sensor).readouts)
    p = plan_render(
        [camera_inputs.images / "frame000.png"], tmp_path / "r", lens="solas-doublet", camera=camera, sensor="2000x1500"
    )
    single = frame_bytes(1500, 2000, 3, 0.0) + WORKER_BYTES["render"]
    expected = frame_bytes(1500, 2000, 3, 0.0, readouts, in_time is not None) + WORKER_BYTES["render"]
    assert readouts == 4 and expected > single
    assert estimate(p, 1)["peak_bytes"] == expected


def _in_process(jobs, todo, grid_path, settings, workers, on_done):
    """`runner.run_local` in this process (so that a test can count what an item does)."""
    from solas_mi.batch.work import run_job
    from solas_mi.psf.depth import read_grid

    grid = read_grid(grid_path)
    for i in todo:
        on_done(i, run_job(jobs[i], grid, grid_path, dict(settings)))


@pytest.mark.parametrize("output_format", ["exr", "exr-half"])
def test_the_camera_goes_on_from_the_degraded_image_not_its_file_read_back(camera_inputs, monkeypatch, output_format):
    """An item's camera takes the image the item just wrote (at the file's precision), not the EXR read back
    (a second read of every output: 0.18 CPU-s of a 1920×1080 frame's 2.1): no output is read, and the RAW
    is the one the file read back gives (`capture` of `read_rgb`, as `solas-mi camera` reads it)."""
    import solas_mi.imageio
    from solas_mi.batch import runner

    monkeypatch.setattr(runner, "run_local", _in_process)
    read = []
    real_read = solas_mi.imageio.read_exr
    monkeypatch.setattr(solas_mi.imageio, "read_exr", lambda path: read.append(str(path)) or real_read(path))
    out = camera_inputs.root / "out"
    camera = load_camera(str(camera_inputs.root / "sensor.toml"), EXPOSURE_MS, "default", 4)
    result = degrade_batch(
        [camera_inputs.images],
        out,
        DegradeSpec(camera=camera, output_format=output_format),
        psf_grid=camera_inputs.grid,
        workers=1,
        progress=False,
    )
    assert [job.status for job in result.jobs] == ["done"] * 3
    assert not {job.output for job in result.jobs} & set(read)
    monkeypatch.undo()
    for job in result.jobs:
        expected = capture(
            camera.sensor, read_rgb(job.output), EXPOSURE_MS * 1e-3, 4, frame_number(Path(job.output).stem)
        )
        assert np.array_equal(read_exr(job.extras[0])[0]["RAW"], expected) and expected.any()
        assert np.array_equal(iio.imread(job.extras[1]), develop(expected, camera.sensor, ISP())[0])
