"""`solas-mi degrade` (convolution.commands)."""

import argparse

import numpy as np
import pytest

from solas_mi.convolution.commands import register
from solas_mi.errors import SolasError


def parser():
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="command"))
    return p


def test_command_line(tmp_path, synthetic):
    from solas_mi.imageio import read_exr, read_image, write_png

    g = synthetic.make_grid(
        np.broadcast_to(synthetic.gaussian(15, 8.0, 2.0), (3, 4, 4, 15, 15)), 2.0, wavelengths=(656, 531, 486)
    )
    g.write(str(tmp_path / "grid.exr"))
    img = np.zeros((48, 64, 3))
    img[:, :32] = [0.2, 0.5, 0.8]
    img[:, 32:] = 0.6
    write_png(tmp_path / "in.png", img)
    args = parser().parse_args(
        [
            "degrade",
            str(tmp_path / "in.png"),
            "--psf-grid",
            str(tmp_path / "grid.exr"),
            "--method",
            "patch",
            "-o",
            str(tmp_path / "out.exr"),
        ]
    )
    assert args.run(args) == 0
    _, meta = read_exr(tmp_path / "out.exr")
    out = read_image(tmp_path / "out.exr")
    assert out.shape == (48, 64, 3)
    assert meta["method"] == "patch" and meta["boundary"] == "edge" and meta["blocks"] == [4, 4]  # 8, 16, 16, 8 rows
    assert meta["channel_wavelengths_nm"] == [656, 531, 486] and "camera" in meta and meta["seconds"] >= 0
    linear_in = read_image(tmp_path / "in.png")  # sRGB decoded
    # far from the edge the output equals the linearised input; the PNG re-encodes it
    assert np.abs(out[:, :20] - linear_in[:, :20]).max() < 1e-5
    assert (
        np.abs(
            read_image(tmp_path / "out.png", linearize=False)[:, :20]
            - read_image(tmp_path / "in.png", linearize=False)[:, :20]
        ).max()
        <= 1 / 255 + 1e-9
    )
    # default: interp
    args = parser().parse_args(
        [
            "degrade",
            str(tmp_path / "out.exr"),
            "--psf-grid",
            str(tmp_path / "grid.exr"),
            "-o",
            str(tmp_path / "twice.exr"),
            "--boundary",
            "reflect",
        ]
    )
    assert args.run(args) == 0
    assert read_exr(tmp_path / "twice.exr")[1]["method"] == "interp"
    assert (tmp_path / "twice.png").is_file()


def test_command_line_errors_leave_nothing(tmp_path, synthetic):
    g = synthetic.small_grid()
    del g.meta["pinhole_focal_mm"]
    g.write(str(tmp_path / "old.exr"))
    write = tmp_path / "in.exr"
    from solas_mi.imageio import write_exr

    write_exr(write, {"Y": np.zeros((30, 40), np.float32)})
    for extra, message in (
        (["--psf-grid", str(tmp_path / "old.exr"), "-o", str(tmp_path / "o.exr")], "psf-grid"),
        (["--psf-grid", str(tmp_path / "old.exr"), "-o", str(tmp_path / "o.png")], ".exr"),
    ):
        args = parser().parse_args(["degrade", str(write), *extra])
        with pytest.raises(SolasError, match=message):
            args.run(args)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.exr", "old.exr"]
    with pytest.raises(SystemExit):
        parser().parse_args(["degrade", str(write), "--psf-grid", "g.exr", "-o", "o.exr", "--method", "fft"])


def test_a_missing_or_broken_image_is_named_not_called_0x0(tmp_path, synthetic):
    """An input whose header cannot be read (missing, a folder, not an image) was refused as "image size 0x0"
    by the frame fit's estimate; the reader's own message names the file and why, and nothing is written."""
    synthetic.small_grid().write(str(tmp_path / "grid.exr"))
    (tmp_path / "broken.exr").write_text("not an image")
    (tmp_path / "folder.exr").mkdir()
    for name, message in (("missing.exr", "does not exist"), ("broken.exr", "cannot read"), ("folder.exr", "folder")):
        args = parser().parse_args(
            ["degrade", str(tmp_path / name), "--psf-grid", str(tmp_path / "grid.exr"), "-o", str(tmp_path / "o.exr")]
        )
        with pytest.raises(SolasError, match=message) as refused:
            args.run(args)
        assert name in str(refused.value) and "0x0" not in str(refused.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.exr", "folder.exr", "grid.exr"]
