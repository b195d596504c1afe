"""Fault injection: what happens when things go wrong — interruptions during computing and during
writing, a full disk, a read-only folder, outputs that would replace inputs or special files,
concurrent writers, bad image data, runaway jobs. Each case asserts the outcome: a clear error (one
line, exit 2), or a correct result, and in every case nothing half-written left behind."""

import hashlib
import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.imageio import read_exr, read_image, write_exr
from solas_mi.resources import resource_dir

PHOTO = resource_dir("scenes") / "images" / "rocket.png"


def solas(*args, cwd, env=None) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "solas_mi", *map(str, args)],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@contextmanager
def tmpfs(path: Path, options: str):
    path.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)], capture_output=True).returncode:
        pytest.skip("cannot mount a tmpfs here")
    try:
        yield path
    finally:
        subprocess.run(["umount", str(path)], capture_output=True)


def foreign_exr(path: Path, channels: dict) -> None:
    """An EXR as other tools write it, NaN and infinities included (ours refuse to write those)."""
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in channels.items()}) as f:
        f.write(str(path))


def one_line_error(capsys, argv) -> str:
    capsys.readouterr()  # what fixtures printed
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


# -------------------------------------------------------------------------------------------- interrupts


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_interrupt_during_compute_leaves_nothing(tmp_path, sig, code):
    p = solas("psf-grid", "solas-doublet", "--grid", "64x64", "-o", "grid.exr", cwd=tmp_path)
    time.sleep(3.0)  # well into the computation (the first progress line comes within a second)
    start = time.perf_counter()
    p.send_signal(sig)
    _, err = p.communicate(timeout=60)
    assert p.returncode == code and "no output was left half-written" in err
    assert time.perf_counter() - start < 3.0  # honoured between batches, within a second or two
    assert list(tmp_path.iterdir()) == []


def test_terminated_during_the_write_keeps_the_old_files(tmp_path):
    """SIGTERM arriving while the EXR is being written: the old EXR and PNG stay as they were and no
    temporary file is left."""
    for name in ("psf.exr", "psf.png"):
        (tmp_path / name).write_bytes(b"old " + name.encode())
    code = (
        "import os, signal, sys\n"
        "import solas_mi.imageio as io\n"
        "real = io.write_exr\n"
        "def dying(path, *a, **k):\n"
        "    real(path, *a, **k)\n"
        "    os.kill(os.getpid(), signal.SIGTERM)\n"
        "io.write_exr = dying\n"
        "from solas_mi.cli import main\n"
        "sys.exit(main(['psf', 'solas-doublet', '--field-deg', '0,2', '--wavelengths-nm', '531', '--size', '32',"
        " '-o', 'psf.exr']))\n"
    )
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert p.returncode == 143, p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == ["psf.exr", "psf.png"]
    assert (tmp_path / "psf.exr").read_bytes() == b"old psf.exr" and (
        tmp_path / "psf.png"
    ).read_bytes() == b"old psf.png"


def test_terminated_render_leaves_no_scene_folder(tmp_path):
    env = dict(os.environ, TMPDIR=str(tmp_path))
    p = solas(
        "render-image",
        "solas-doublet",
        PHOTO,
        "--spp",
        "96",
        "--sensor",
        "640x480",
        "-o",
        "r.exr",
        cwd=tmp_path,
        env=env,
    )
    time.sleep(4.0)
    p.send_signal(signal.SIGTERM)
    p.communicate(timeout=60)
    assert p.returncode == 143
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------------ disks


def test_full_disk_is_a_clear_error(tmp_path, capsys):
    with tmpfs(tmp_path / "small", "size=64k") as disk:
        err = one_line_error(
            capsys,
            [
                "psf",
                "solas-doublet",
                "--field-deg",
                "0,2",
                "--wavelengths-nm",
                "531",
                "--size",
                "200",
                "-o",
                disk / "p.exr",
            ],
        )
        assert f"cannot write {disk / 'p.exr'}: No space left on device" in err
        assert list(disk.iterdir()) == []


def test_read_only_folder_fails_before_computing(tmp_path, capsys):
    with tmpfs(tmp_path / "ro", "ro,size=64k") as disk:
        start = time.perf_counter()
        err = one_line_error(capsys, ["psf-grid", "solas-doublet", "--grid", "32x32", "-o", disk / "g.exr"])
        assert "is not writable" in err and time.perf_counter() - start < 1.0


# ---------------------------------------------------------------------------------------------- outputs


@pytest.fixture
def grid(tmp_path):
    path = tmp_path / "grid.exr"
    assert main(["psf-grid", "solas-doublet", "--grid", "4x4", "--size", "32", "--pitch-um", "2", "-o", str(path)]) == 0
    return path


def test_output_never_replaces_an_input(tmp_path, capsys, grid):
    photo = tmp_path / "photo.png"
    photo.write_bytes(PHOTO.read_bytes())
    before = digest(photo)
    err = one_line_error(capsys, ["degrade", photo, "--psf-grid", grid, "-o", tmp_path / "photo.exr"])
    assert "'" + str(photo) + "' is an input of this command" in err
    err = one_line_error(capsys, ["degrade", photo, "--psf-grid", grid, "-o", grid])
    assert "is an input of this command" in err
    assert digest(photo) == before and not (tmp_path / "photo.exr").exists()


def test_data_is_always_exr(tmp_path, capsys):
    err = one_line_error(
        capsys, ["psf", "solas-doublet", "--field-deg", "0,2", "--wavelengths-nm", "531", "-o", tmp_path / "x.png"]
    )
    assert "must end in .exr" in err and "x.exr (a PNG preview is written beside it)" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kind", ["folder", "symlink", "fifo"])
def test_special_outputs_are_refused(tmp_path, capsys, kind):
    target = tmp_path / f"{kind}.exr"
    if kind == "folder":
        target.mkdir()
    if kind == "fifo":
        os.mkfifo(target)
    if kind == "symlink":
        (tmp_path / "real.exr").write_bytes(b"keep")
        target.symlink_to(tmp_path / "real.exr")
    err = one_line_error(
        capsys, ["psf", "solas-doublet", "--field-deg", "0,2", "--wavelengths-nm", "531", "-o", target]
    )
    assert {"folder": "is a folder", "symlink": "is a symbolic link", "fifo": "is not a regular file"}[kind] in err
    if kind == "symlink":
        assert target.is_symlink() and (tmp_path / "real.exr").read_bytes() == b"keep"


def test_concurrent_writers_leave_one_whole_file(tmp_path):
    args = ["psf", "solas-doublet", "--field-deg", "0,2", "--wavelengths-nm", "531", "--size", "64", "-o", "p.exr"]
    procs = [solas(*args, cwd=tmp_path) for _ in range(2)]
    assert [p.wait(timeout=120) for p in procs] == [0, 0]
    assert sorted(f.name for f in tmp_path.iterdir()) == ["p.exr", "p.png"]
    channels, meta = read_exr(tmp_path / "p.exr")
    assert channels["Y"].shape == (64, 64) and meta["method"] == "fraunhofer"


# ------------------------------------------------------------------------------------------------ inputs


def test_nan_pixels_are_refused_with_count_and_position(tmp_path, capsys, grid):
    image = np.full((96, 128, 3), 0.5)
    image[10, 20, 1] = np.nan
    image[50, 60, 0] = np.inf
    foreign_exr(tmp_path / "nan.exr", {"R": image[..., 0], "G": image[..., 1], "B": image[..., 2]})
    err = one_line_error(capsys, ["degrade", tmp_path / "nan.exr", "--psf-grid", grid, "-o", tmp_path / "o.exr"])
    assert "2 values are NaN or infinite (the first at row 10, column 20, channel 1)" in err


@pytest.mark.parametrize(
    "names, expect",
    [
        (("R", "G", "B"), [0.1, 0.2, 0.3]),
        (("r", "g", "b"), [0.1, 0.2, 0.3]),
        (("beauty.R", "beauty.G", "beauty.B"), [0.1, 0.2, 0.3]),
    ],
)
def test_exr_channels_are_read_by_name(tmp_path, names, expect):
    values = dict(zip(names, (0.1, 0.2, 0.3)))
    write_exr(
        tmp_path / "c.exr", {n: np.full((2, 3), values[n]) for n in reversed(names)} | {"depth.Z": np.ones((2, 3))}
    )
    assert np.allclose(read_image(tmp_path / "c.exr")[0, 0], expect)


def test_unknown_exr_channels_are_named(tmp_path, capsys, grid):
    write_exr(tmp_path / "xy.exr", {"X": np.ones((8, 8)), "Z": np.ones((8, 8))})
    err = one_line_error(capsys, ["degrade", tmp_path / "xy.exr", "--psf-grid", grid, "-o", tmp_path / "o.exr"])
    assert "channels X, Z" in err and "R, G, B" in err


def test_16_bit_png_keeps_its_depth(tmp_path):
    import png

    levels = (np.arange(4 * 5 * 3).reshape(4, 5, 3) * 1000 + 7).astype(np.uint16)
    with open(tmp_path / "deep.png", "wb") as f:
        png.Writer(5, 4, bitdepth=16, greyscale=False).write(f, levels.reshape(4, -1))
    assert np.array_equal(np.round(read_image(tmp_path / "deep.png", linearize=False) * 65535), levels)


def test_plugin_errors_reach_the_user_as_one_line(tmp_path, capsys):
    assert main(["scene", "solas-doublet", "-o", str(tmp_path / "s"), "--sensor", "16x12", "--rings", "8"]) == 0
    err = one_line_error(
        capsys,
        [
            "render",
            tmp_path / "s" / "scene.xml",
            "--integrator",
            "solas",
            "--set",
            "response=bogus",
            "-o",
            tmp_path / "r.exr",
        ],
    )
    assert "camera response 'bogus': unknown response; allowed: lines, srgb" in err


# ------------------------------------------------------------------------------------------ runaway jobs


@pytest.mark.parametrize(
    "argv, message",
    [
        (["psf-grid", "solas-doublet", "--grid", "512x512", "--size", "512"], "needs about"),
        (["render-image", "solas-doublet", str(PHOTO), "--sensor", "40000x30000"], "needs about"),
        (["render-image", "solas-doublet", str(PHOTO), "--spp", "2147483648"], "must be an integer from 1 to 1048576"),
    ],
)
def test_runaway_jobs_are_refused_before_they_start(tmp_path, capsys, argv, message):
    start = time.perf_counter()
    assert message in one_line_error(capsys, [*argv, "-o", tmp_path / "x.exr"])
    assert time.perf_counter() - start < 2.0 and list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ odd values the probe of every command found


@pytest.mark.parametrize(
    "argv, says",
    [
        (["sfr-target", "--size", "64x64", "--noise", "nan"], "noise nan must be a finite number"),
        (["sfr-target", "--size", "64x64", "--noise", "inf"], "noise inf must be a finite number"),
        (["sfr-target", "--size", "64x64", "--sigma-px", "inf"], "--sigma-px inf must be a finite number"),
        (["sfr-target", "--size", "64x64", "--angle-deg", "nan"], "--angle-deg nan must be a finite angle"),
        (["scene", "solas-doublet", "--sensor", "0x0"], "--sensor '0x0' must look like 32x24"),
        (["psf-grid", "solas-doublet", "--wavelengths-nm", "531,531"], "must differ from each other"),
    ],
)
def test_odd_values_are_one_clear_line(tmp_path, capsys, argv, says):
    out = tmp_path / ("t.png" if argv[0] == "sfr-target" else "scene" if argv[0] == "scene" else "g.exr")
    err = one_line_error(capsys, [*argv, "-o", out])
    assert says in err
    assert not out.exists()


def test_a_damaged_grid_field_is_named_without_its_whole_value(tmp_path, capsys):
    from solas_mi.psf.grid import psf_grid

    grid = tmp_path / "grid.exr"
    psf_grid(_doublet(), grid=(3, 3), size=32).write(str(grid))
    channels, meta = read_exr(grid)
    meta["grid"] = [4, 4]  # the PSF mosaics and the arrays of the metadata are 3x3
    write_exr(grid, channels, meta)
    err = one_line_error(capsys, ["degrade", PHOTO, "--psf-grid", grid, "-o", tmp_path / "d.exr"])
    assert "metadata field" in err and len(err) < 400, err
    assert "the fields grid, size and wavelengths_nm give" in err  # why a sound array's shape is wrong


def _doublet():
    from solas_mi.optics.lens import Lens

    return Lens.load("solas-doublet")
