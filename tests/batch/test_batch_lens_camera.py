"""A degrade batch says its camera (`convolution.camera`): the manifest holds the camera block of each
frame size, each degraded frame the block of its own size, fitted once per size in the batch's process
(a fit takes seconds: never once per frame)."""

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.convolution.camera import frame_camera
from solas_mi.imageio import read_exr, write_png
from solas_mi.psf.grid import psf_grid
from solas_mi.psf.spec import GridSpec


@pytest.fixture(scope="module")
def wide_grid(tmp_path_factory):
    lens = Lens.load("wide-angle-22mm")
    grid = psf_grid(
        lens,
        GridSpec(
            grid=(9, 7),
            size=21,
            method="geometric",
            rays=16,
            field_sampling="edges",
            wavelengths_nm=(lens.primary_wavelength,),
            field_range_deg=(40.0, 29.0),
            pitch_um=8.0,
        ),
    )
    path = tmp_path_factory.mktemp("grid") / "wide.exr"
    grid.write(str(path))
    return path, grid


def test_a_batch_records_its_camera_fitted_once_per_frame_size(tmp_path, wide_grid, monkeypatch, fresh_cache):
    from solas_mi.optics.calibration import fit as fitting

    path, grid = wide_grid
    frames = tmp_path / "frames"
    frames.mkdir()
    sizes = {"a": (96, 64), "b": (96, 64), "c": (96, 64), "d": (72, 48)}  # (columns, rows)
    for stem, (w, h) in sizes.items():
        write_png(frames / f"{stem}.png", np.random.default_rng(0).random((h, w, 3)))
    fits = []
    real = fitting.fit
    monkeypatch.setattr(fitting, "fit", lambda cmap, name: fits.append(name) or real(cmap, name))
    out = tmp_path / "out"
    assert (
        main(
            [
                "batch",
                "degrade",
                str(frames),
                "--psf-grid",
                str(path),
                "--calibration-model",
                "woodscape",
                "-o",
                str(out),
                "--workers",
                "2",
                "--quiet",
            ]
        )
        == 0
    )
    assert fits == ["woodscape", "woodscape"]  # two frame sizes, four frames
    manifest = strict_loads((out / "batch.json").read_text())
    cameras = manifest["cameras"]
    assert sorted(cameras) == ["72x48", "96x64"] and manifest["calibration_model"] == "woodscape"
    for stem, (w, h) in sizes.items():
        camera = read_exr(out / f"{stem}.exr")[1]["camera"]  # the block beside the convolution's own camera
        assert {k: camera[k] for k in cameras[f"{w}x{h}"]} == cameras[f"{w}x{h}"] and camera["sensor_px"] == [w, h]
        assert camera["calibration"]["model"] == "woodscape" and camera["sensor"] == [w, h]
    expected = frame_camera(grid, 72, 48, None, "woodscape")  # what one frame of that size says
    assert cameras["72x48"]["calibration"]["parameters"] == pytest.approx(expected["calibration"]["parameters"])


def test_the_degrade_command_records_its_camera(tmp_path, wide_grid):
    """`degrade` writes the block of its frame, with the default model (`MODELS.default`)."""
    from solas_mi.optics.calibration import MODELS

    path, grid = wide_grid
    write_png(tmp_path / "f.png", np.full((64, 96, 3), 0.5))
    out = tmp_path / "o.exr"
    assert main(["degrade", str(tmp_path / "f.png"), "--psf-grid", str(path), "-o", str(out)]) == 0
    camera, block = read_exr(out)[1]["camera"], frame_camera(grid, 96, 64, None, MODELS.default)
    assert {k: camera[k] for k in block} == block and camera["projection"].startswith("rectilinear")


def test_a_render_batch_records_each_sensors_camera_fitted_once(tmp_path, monkeypatch, fresh_cache):
    """`batch render --calibration-model`: the image items of one lens and sensor share one fit (two spp values,
    two items), made before any item; each output's camera block is its sensor's, as `render-image` writes it."""
    from solas_mi.batch.render import render_batch
    from solas_mi.optics.calibration import fit as fitting
    from solas_mi.optics.camera import camera_for
    from solas_mi.render.image import image_camera
    from solas_mi.render.response import parse

    image = tmp_path / "photo.png"
    write_png(image, np.full((24, 32, 3), 0.5))
    fits = []
    real = fitting.fit
    monkeypatch.setattr(fitting, "fit", lambda cmap, name: fits.append(name) or real(cmap, name))
    result = render_batch(
        [image],
        tmp_path / "r",
        lens="cooke-triplet",
        sensor="16x12",
        spp=[1, 2],
        workers=1,
        progress=False,
        calibration_model="opencv-pinhole",
    )
    assert [j.status for j in result.jobs] == ["done", "done"] and fits == ["opencv-pinhole"]
    manifest = strict_loads((tmp_path / "r" / "batch.json").read_text())
    (block,) = manifest["cameras"].values()
    lens = Lens.load("cooke-triplet")
    assert block == image_camera(
        lens, camera_for(lens, (12, 16), None, None), parse("srgb", lens.wavelengths_nm), "opencv-pinhole"
    )
    for job in result.jobs:
        assert read_exr(job.output)[1]["camera"] == block
