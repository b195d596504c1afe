"""`solas-mi batch degrade` and `degrade_batch`: failures reported per item, resuming, interruption,
local processes against Dask, the PSF-grid cache, argument errors."""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi.cli import main
from solas_mi.convolution.spec import DegradeSpec


def manifest(folder):
    return strict_loads((folder / "batch.json").read_text())


def test_one_corrupt_item_is_reported_and_a_rerun_skips_the_rest(batch_inputs, capsys):
    batch_inputs.write(19)
    (batch_inputs.images / "frame007b.png").write_bytes(b"not a png at all")
    out = batch_inputs.root / "out"
    argv = [
        "batch",
        "degrade",
        str(batch_inputs.images),
        "--psf-grid",
        str(batch_inputs.grid),
        "-o",
        str(out),
        "--workers",
        "2",
        "--quiet",
    ]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "frame007b.png" in err and "cannot read image" in err
    m = manifest(out)
    assert m["summary"] == {"done": 19, "failed": 1} and m["grid_source"] == "given"
    (bad,) = [i for i in m["items"] if i["status"] == "failed"]
    assert bad["input"].endswith("frame007b.png") and "cannot read image" in bad["error"]
    assert all(i["seconds"] > 0 and i["seed"] is None for i in m["items"])
    assert len(list(out.glob("*.exr"))) == 19 and len(list(out.glob("*.png"))) == 19
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
    from solas_mi.imageio import read_exr

    meta = read_exr(out / "frame000.exr")[1]
    assert meta["batch"]["id"] == m["batch_id"] and meta["batch"]["grid_hash"] == m["grid_hash"]
    times = {p.name: p.stat().st_mtime_ns for p in out.glob("frame*")}
    assert main(argv) == 1  # the corrupt one fails again; the others are not touched
    assert {p.name: p.stat().st_mtime_ns for p in out.glob("frame*")} == times
    assert manifest(out)["summary"] == {"skipped": 19, "failed": 1}
    # a finished output changed since: done again
    os.utime(out / "frame003.exr", ns=(1, 1))
    assert main(argv) == 1
    assert manifest(out)["summary"] == {"skipped": 18, "done": 1, "failed": 1}


def test_sigterm_midway_leaves_only_finished_items(batch_inputs):
    batch_inputs.write(40, shape=(480, 640))
    out = batch_inputs.root / "out"
    p = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "solas_mi",
            "batch",
            "degrade",
            str(batch_inputs.images),
            "--psf-grid",
            str(batch_inputs.grid),
            "-o",
            str(out),
            "--workers",
            "2",
            "--quiet",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while len(list(out.glob("[!.]*.exr"))) < 3 and time.monotonic() < deadline:  # not the temporary files
        time.sleep(0.05)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 143, err
    m = manifest(out)  # valid JSON
    done = {i["output"] for i in m["items"] if i["status"] == "done"}
    written = {str(f) for f in out.glob("*.exr")}
    assert len(done) >= 1 and done <= written and len(written) < 40
    # an item finished while the signal came may be written and not yet recorded: it is done again on a re-run
    assert len(written - done) <= 2
    assert not [f for f in out.iterdir() if f.name.startswith(".")]  # no temporary file left
    from solas_mi.imageio import read_image

    for f in out.glob("*.exr"):
        assert read_image(f).shape == (480, 640, 3)


def test_dask_local_and_local_processes_give_identical_outputs(batch_inputs):
    from solas_mi.batch import degrade_batch
    from solas_mi.imageio import read_exr

    batch_inputs.write(4)
    a = degrade_batch(
        [batch_inputs.images], batch_inputs.root / "local", psf_grid=batch_inputs.grid, workers=2, progress=False
    )
    b = degrade_batch(
        [str(batch_inputs.images / "*.png")],
        batch_inputs.root / "dask",
        psf_grid=batch_inputs.grid,
        dask="local",
        workers=2,
        progress=False,
    )
    assert a.count("done") == b.count("done") == 4 and not b.failed
    assert manifest(batch_inputs.root / "dask")["runner"] == {"dask": "local"}
    for job in a.jobs:
        name = os.path.basename(job.output)
        x, y = read_exr(job.output)[0], read_exr(batch_inputs.root / "dask" / name)[0]
        assert list(x) == list(y) and all(np.array_equal(x[k], y[k]) for k in x)
        png = name.replace(".exr", ".png")
        assert (batch_inputs.root / "local" / png).read_bytes() == (batch_inputs.root / "dask" / png).read_bytes()


def test_the_grid_is_computed_once_and_cached(batch_inputs, doublet):
    from solas_mi.batch import GridCache, degrade_batch
    from solas_mi.psf.spec import GridSpec

    batch_inputs.write(3)
    cache = GridCache(batch_inputs.root / "cache")
    options = {"grid": (4, 4), "size": 32, "pupil_samples": 32}
    first = degrade_batch(
        [batch_inputs.images],
        batch_inputs.root / "a",
        DegradeSpec(grid_spec=GridSpec(**options)),
        lens=doublet,
        cache=cache,
        workers=2,
        progress=False,
    )
    assert (cache.misses, cache.hits) == (1, 0) and first.grid_source == "computed" and not first.failed
    second = degrade_batch(
        [batch_inputs.images],
        batch_inputs.root / "b",
        DegradeSpec(grid_spec=GridSpec(**options, method="fraunhofer")),
        lens="solas-doublet",
        cache=cache,
        workers=1,
        progress=False,
    )
    assert (cache.misses, cache.hits) == (1, 1) and second.grid_source == "cache hit"
    assert len(list(cache.folder.glob("*.exr"))) == 1 and len(list(cache.folder.iterdir())) == 2  # + its record
    m = manifest(batch_inputs.root / "b")
    assert m["lens_hash"] == doublet.hash and m["grid_spec"] == GridSpec(**options).canonical()
    assert m["grid_spec"]["grid"] == [4, 4]
    degrade_batch(
        [batch_inputs.images],
        batch_inputs.root / "c",
        DegradeSpec(grid_spec=GridSpec(**{**options, "size": 48})),
        lens=doublet,
        cache=cache,
        workers=1,
        progress=False,
    )
    assert (cache.misses, cache.hits) == (2, 1)  # another sampling option: another grid


def test_the_lens_scaled_to_the_frames_camera_is_stated(batch_inputs, doublet, capsys):
    """--scale-lens 5: the doublet scaled so that its focal length is fx × 5 µm; its grid, the pixel pitch of
    every output and the metadata follow (the scaling laws: tests/convolution/test_scale_lens.py)."""
    from solas_mi.batch import GridCache, degrade_batch
    from solas_mi.imageio import read_exr
    from solas_mi.optics.frame import FrameCamera
    from solas_mi.psf.spec import GridSpec

    batch_inputs.write(1)
    fx = 32 / np.tan(np.radians(1.5))  # the 64-px frames span ±1.5°
    frame = FrameCamera("pinhole", intrinsics=(fx, fx, 31.5, 23.5))
    spec = GridSpec(grid=(3, 3), size=32, method="geometric", rays=32, pitch_um=0.5)
    out = degrade_batch(
        [batch_inputs.images],
        batch_inputs.root / "s",
        DegradeSpec(grid_spec=spec, frame=frame, scale_lens=5.0),
        lens=doublet,
        cache=GridCache(batch_inputs.root / "cache"),
        workers=1,
        progress=False,
    )
    assert not out.failed
    scale = manifest(batch_inputs.root / "s")["lens_scale"]
    # the doublet's pinhole focal length meeting its real chief ray at its 2° field: 99.50 mm
    assert scale["factor"] == pytest.approx(fx * 5e-3 / 99.499, rel=1e-4) and scale["pixel_um"] == 5.0
    assert manifest(batch_inputs.root / "s")["lens_hash"] != doublet.hash
    _, meta = read_exr(batch_inputs.root / "s" / "frame000.exr")
    assert meta["camera"]["pitch_um"] == pytest.approx(5.0, rel=1e-3) and meta["batch"]["lens_scale"] == scale
    argv = ["batch", "degrade", str(batch_inputs.images), "-o", str(batch_inputs.root / "t"), "--scale-lens", "5"]
    for extra, what in (
        (["--psf-grid", str(batch_inputs.grid), "--intrinsics", "1000,1000,31.5,23.5"], "give --lens"),
        (["--lens", "solas-doublet", "--fov-deg", "1.5"], "give --intrinsics"),
        (["--lens", "solas-doublet"], "frames' camera"),
    ):
        assert main([*argv, *extra]) == 2
        assert what in capsys.readouterr().err


def test_dry_run_says_what_is_reused_and_does_nothing(batch_inputs, capsys):
    batch_inputs.write(3)
    out = batch_inputs.root / "out"
    argv = ["batch", "degrade", str(batch_inputs.images), "--psf-grid", str(batch_inputs.grid), "-o", str(out)]
    assert main([*argv, "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert "degrade 3 of 3 images (0 already finished" in text and "estimate" in text and not out.exists()
    assert main([*argv, "--quiet"]) == 0
    capsys.readouterr()
    assert main([*argv, "--dry-run"]) == 0
    assert "degrade 0 of 3 images (3 already finished" in capsys.readouterr().out


def test_a_dead_worker_loses_only_its_item(batch_inputs):
    """SIGKILL one worker process holding an item: the item is retried in a fresh process."""
    import psutil

    from solas_mi.batch.jobs import expand_inputs, plan
    from solas_mi.batch.runner import run_local
    from solas_mi.outputs import remove_temporaries

    batch_inputs.write(12, shape=(240, 320))
    jobs = plan(expand_inputs([batch_inputs.images]), batch_inputs.root / "out")
    killed = []

    def is_worker(process):
        try:
            return "resource_tracker" not in " ".join(process.cmdline())
        except psutil.Error:  # a process ending just now
            return False

    def on_done(i, job):
        jobs[i] = job
        if not killed:
            victim = next(p for p in psutil.Process().children() if is_worker(p))
            victim.kill()
            killed.append(victim.pid)

    settings = {"spec": DegradeSpec(), "force": False, "batch": {}}
    run_local(jobs, list(range(len(jobs))), str(batch_inputs.grid), settings, 2, on_done)
    assert killed and all(job.status == "done" for job in jobs), [job.error for job in jobs]
    assert max(job.attempts for job in jobs) == 2  # the item the killed process held, done again
    remove_temporaries(batch_inputs.root / "out")  # as degrade_batch does before and after every run
    assert not [f for f in (batch_inputs.root / "out").iterdir() if f.name.startswith(".")]


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--workers", "0"], "--workers '0' must be a whole number >= 1"),
        (["--psf-grid", "{tmp}/nothing.exr"], "PSF grid '{tmp}/nothing.exr' is not a file"),
        (["--lens", "solas-doublet", "--grid", "4by4"], "--grid '4by4' must look like 32x24"),
        (["--lens", "no-such-lens"], "no-such-lens"),
        (["--psf-grid", "{tmp}/grid.exr", "--dask", " "], "must be a scheduler address"),
    ],
)
def test_bad_arguments_are_one_line(batch_inputs, capsys, extra, message):
    batch_inputs.write(2)
    tmp = str(batch_inputs.root)
    extra = [e.replace("{tmp}", tmp) for e in extra]
    if not any(e in ("--psf-grid", "--lens") for e in extra):
        extra += ["--psf-grid", str(batch_inputs.grid)]
    argv = ["batch", "degrade", str(batch_inputs.images), "-o", f"{tmp}/out", "--quiet", *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message.replace("{tmp}", tmp) in err and err.count("\n") == 1, err
    assert not (batch_inputs.root / "out").exists()


def test_inputs_that_match_nothing_or_collide(batch_inputs, capsys):
    batch_inputs.write(1)
    (batch_inputs.root / "other").mkdir()
    (batch_inputs.root / "other" / "frame000.png").write_bytes((batch_inputs.images / "frame000.png").read_bytes())
    for inputs, message in (
        ([f"{batch_inputs.root}/nope*.png"], "holds no input files"),
        ([str(batch_inputs.images), str(batch_inputs.root / "other")], "would both write"),
    ):
        argv = ["batch", "degrade", *inputs, "--psf-grid", str(batch_inputs.grid), "-o", str(batch_inputs.root / "o")]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err


def test_temporary_files_of_killed_workers_are_removed(batch_inputs):
    from solas_mi.batch import degrade_batch

    batch_inputs.write(2)
    out = batch_inputs.root / "out"
    out.mkdir()
    (out / ".frame001.exr.k1lled00.exr").write_bytes(b"half an EXR")  # as `imageio.atomic_path` names them
    (out / ".notes.txt").write_text("not ours")
    result = degrade_batch([batch_inputs.images], out, psf_grid=batch_inputs.grid, workers=1, progress=False)
    assert result.count("done") == 2
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == [".notes.txt"]


def test_dry_run_estimates_the_grid_and_says_whether_it_is_reused(batch_inputs, capsys):
    """The grid is most of a batch's time: the dry run estimates it (it said only the degrading's) from
    PSFs of this grid timed now, counting the PSFs to compute: a 4×4 grid of centred nodes has 3
    distinct |x|, |y| pairs up to a swap ((1, 1), (1, 3), (3, 3) quarter-cells), so 3 × 3 wavelengths of
    its 48 PSFs are computed; a second dry run after the batch says the cached grid is reused."""
    batch_inputs.write(1)
    argv = [
        "batch",
        "degrade",
        str(batch_inputs.images),
        "--lens",
        "solas-doublet",
        "--grid",
        "4x4",
        "--size",
        "32",
        "-o",
        str(batch_inputs.root / "out"),
        "--cache",
        str(batch_inputs.root / "cache"),
    ]
    assert main([*argv, "--dry-run"]) == 0
    first, *_, estimate = capsys.readouterr().out.splitlines()
    assert "(not in the cache: computed once, about " in first and "9 PSFs to compute of its 48" in first, first
    assert re.search(r"as timed now on \d+ of its PSFs; then cached\)$", first), first
    grid_s = float(re.search(r"about ([\d.e+-]+) s: ", first)[1])
    total, of_grid, degrading = map(
        float,
        re.match(
            r"estimate: about ([\d.e+-]+) s \(([\d.e+-]+) s for the grid, "
            r"([\d.e+-]+) s of degrading\)",
            estimate,
        ).groups(),
    )
    assert of_grid == pytest.approx(grid_s, rel=1e-2) and total == pytest.approx(grid_s + degrading, rel=1e-2)
    assert main([*argv, "--quiet"]) == 0
    capsys.readouterr()
    assert main([*argv, "--dry-run"]) == 0
    first, *_, estimate = capsys.readouterr().out.splitlines()
    assert first.endswith("(in the cache: reused, nothing to compute)") and "(0 s for the grid, " in estimate


def _planned_grid(capsys, argv) -> str:
    """The grid file `batch degrade --dry-run` plans (its stage 1 line)."""
    assert main([*argv, "--dry-run"]) == 0
    (line,) = [t for t in capsys.readouterr().out.splitlines() if t.startswith("1. PSF grid: ")]
    return line.split(": ", 1)[1].split(" (")[0]


def test_a_fisheye_sensor_layout_is_not_dropped_by_the_batch(batch_inputs, capsys):
    """--layout/--sensor-mm used to be parsed and dropped: the batch planned the field-layout grid."""
    batch_inputs.write(1)
    argv = [
        "batch",
        "degrade",
        str(batch_inputs.images),
        "--lens",
        "nikkor-fisheye",
        "--grid",
        "3x3",
        "-o",
        str(batch_inputs.root / "out"),
        "--cache",
        str(batch_inputs.root / "cache"),
    ]
    plain = _planned_grid(capsys, [*argv, "--field-range-deg", "60"])  # ±90°, its field, has no pinhole image
    sensor = _planned_grid(capsys, [*argv, "--layout", "sensor", "--sensor-mm", "19x19"])
    assert sensor != plain
    assert sensor != _planned_grid(capsys, [*argv, "--layout", "sensor"])  # the sensor size counts too


# per flag of `psf-grid`: the options it needs to matter, and a value other than the default
FLAG_VARIANTS = {
    "--grid": ([], "2x1"),
    "--wavelengths-nm": ([], "486"),
    "--layout": ([], "sensor"),
    "--field-range-deg": ([], "1,0.5"),
    "--field-sampling": ([], "edges"),
    "--sensor-mm": (["--layout", "sensor"], "3x2"),
    "--pitch-um": ([], "3"),
    "--size": ([], "20"),
    "--psf-method": ([], "geometric"),
    "--pupil-samples": ([], "24"),
    "--rays": (["--psf-method", "geometric"], "12"),
    "--normalize": ([], "peak"),
    "--auto-window": ([], None),
    "--distances-m": ([], "inf,10"),
}
# the lens's own options (--temperature-c, ... move the lens: test_the_batch_grid_is_the_lens_at_its_temperature)
NOT_GRID_OPTIONS = {"lens", "output", "mosaic", "force", "help", "temperature-c", "pressure-kpa", "mount"}


def test_every_psf_grid_flag_reaches_the_cache_key_and_the_grid(batch_inputs, capsys, doublet):
    """Each option `psf-grid` defines (read from its parser) changes the grid file a batch plans, and
    the grid computed from the batch's spec."""
    import argparse

    from solas_mi.cli import build_parser
    from solas_mi.psf.depth import make_grid
    from solas_mi.psf.spec import GridSpec

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    flags = {max(a.option_strings, key=len) if a.option_strings else a.dest for a in sub.choices["psf-grid"]._actions}
    flags = {f for f in flags if f.lstrip("-") not in NOT_GRID_OPTIONS}
    assert flags == set(FLAG_VARIANTS), "a psf-grid flag without a variant here (or a variant of no flag)"
    batch_inputs.write(1)
    base = [
        "--grid",
        "1x2",
        "--wavelengths-nm",
        "531",
        "--size",
        "16",
        "--pitch-um",
        "2",
        "--pupil-samples",
        "16",
        "--rays",
        "8",
    ]
    argv = [
        "batch",
        "degrade",
        str(batch_inputs.images),
        "--lens",
        "solas-doublet",
        "-o",
        str(batch_inputs.root / "out"),
        "--cache",
        str(batch_inputs.root / "cache"),
    ]

    def spec_of(options):
        args = sub.choices["batch"].parse_args(["degrade", "x", "--lens", "l", "-o", "o", *options])
        return GridSpec.from_args(args)

    for flag, (context, value) in sorted(FLAG_VARIANTS.items()):
        before = [*base, *context]
        after = [*before, flag] + ([] if value is None else [value])
        assert _planned_grid(capsys, [*argv, *before]) != _planned_grid(capsys, [*argv, *after]), flag
        a, b = make_grid(doublet, spec_of(before)), make_grid(doublet, spec_of(after))
        assert b.meta["grid_spec"] == spec_of(after).canonical() != a.meta["grid_spec"], flag
        a, b = _psfs(a), _psfs(b)
        assert a.shape != b.shape or not np.array_equal(a, b), flag
        assert a.sum() > 0 and b.sum() > 0, flag


def _psfs(grid) -> np.ndarray:
    """A grid's PSFs, those of every object distance of a grid over distance."""
    return np.stack([g.data for g in grid.layers]) if hasattr(grid, "layers") else grid.data


def test_a_folder_tree_keeps_its_structure_and_half_floats_halve_the_output(batch_inputs):
    from solas_mi.batch.degrade import degrade_batch
    from solas_mi.imageio import read_exr, read_image

    batch_inputs.write(1)
    sub = batch_inputs.images / "cam_left" / "seq1"
    sub.mkdir(parents=True)
    (sub / "frame000.png").write_bytes((batch_inputs.images / "frame000.png").read_bytes())
    out = batch_inputs.root / "out"
    degrade_batch([batch_inputs.images], out, psf_grid=batch_inputs.grid, workers=1, progress=False)
    full = out / "frame000.exr"
    nested = out / "cam_left" / "seq1" / "frame000.exr"
    assert full.is_file() and nested.is_file() and nested.with_suffix(".png").is_file()
    assert np.array_equal(read_image(full), read_image(nested))  # same input, same output, its own folder
    half = batch_inputs.root / "half"
    degrade_batch(
        [batch_inputs.images],
        half,
        DegradeSpec(output_format="exr-half"),
        psf_grid=batch_inputs.grid,
        workers=1,
        progress=False,
    )
    channels, meta = read_exr(half / "frame000.exr")
    assert channels["R"].dtype == np.float16 and meta["output_format"] == "exr-half"
    assert np.allclose(read_image(half / "frame000.exr"), read_image(full), rtol=1e-3, atol=1e-4)
    from solas_mi import SolasError

    with pytest.raises(SolasError, match="output format"):
        degrade_batch(
            [batch_inputs.images], half, DegradeSpec(output_format="png8"), psf_grid=batch_inputs.grid, workers=1
        )


def test_a_batch_from_a_lens_defaults_to_the_accuracy_tables_grid():
    """The grid a batch computes without --grid is the accuracy tables' interp grid, and its help says
    so: the default shown is the one the batch's spec takes."""
    import argparse

    from solas_mi.batch.commands import _degrade_spec
    from solas_mi.cli import build_parser

    def subparsers(parser):
        return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices

    batch = subparsers(build_parser())["batch"]
    args = batch.parse_args(["degrade", "x", "--lens", "solas-doublet", "-o", "o"])
    rows, cols = _degrade_spec(args).grid_spec.grid
    assert (rows, cols) == (32, 32)
    shown = " ".join(subparsers(batch)["degrade"].format_help().split())
    assert f"--grid GRID COLSxROWS field nodes (default: {cols}x{rows})" in shown
    args = batch.parse_args(["degrade", "x", "--lens", "solas-doublet", "-o", "o", "--grid", "8x6"])
    assert _degrade_spec(args).grid_spec.grid == (6, 8)


def test_a_batch_with_depth_maps_by_name_pattern(tmp_path, doublet):
    from solas_mi.batch.degrade import degrade_batch
    from solas_mi.convolution.depth import degrade_depth
    from solas_mi.imageio import image_channels, read_image, write_exr
    from solas_mi.psf.depth import depth_grid
    from solas_mi.psf.spec import GridSpec

    g = depth_grid(
        doublet,
        GridSpec(
            grid=(3, 4),
            wavelengths_nm=[531.0],
            size=32,
            pitch_um=4.0,
            method="geometric",
            rays=32,
            distances_m=(float("inf"), 10.0),
        ),
    )
    g.write(str(tmp_path / "g.exr"))
    folder = tmp_path / "frames"
    folder.mkdir()
    img = np.random.default_rng(0).random((48, 64))
    depth = np.where(np.arange(64)[None, :] < 32, 10.0, np.inf) * np.ones((48, 1))
    write_exr(folder / "a.exr", image_channels(img), {})
    write_exr(folder / "a_depth.exr", {"Z": depth.astype(np.float32)}, {}, infinite=True)  # the sky: inf
    result = degrade_batch(
        [folder],
        tmp_path / "out",
        DegradeSpec(depth_pattern="{stem}_depth.exr"),
        psf_grid=tmp_path / "g.exr",
        workers=1,
        progress=False,
    )
    assert [j.status for j in result.jobs] == ["done"]  # the depth map is not an input of its own
    out = read_image(tmp_path / "out" / "a.exr")
    assert np.allclose(out, degrade_depth(read_image(folder / "a.exr"), depth, g), atol=1e-6)
    again = degrade_batch(
        [folder],
        tmp_path / "out",
        DegradeSpec(depth_pattern="{stem}_depth.exr", occlusion="none"),
        psf_grid=tmp_path / "g.exr",
        workers=1,
        progress=False,
    )
    assert [j.status for j in again.jobs] == ["done"]  # another occlusion rule: not the former run's items
    assert np.allclose(
        read_image(tmp_path / "out" / "a.exr"),
        degrade_depth(read_image(folder / "a.exr"), depth, g, occlusion="none"),
        atol=1e-6,
    )
    (folder / "b.exr").write_bytes((folder / "a.exr").read_bytes())
    with pytest.raises(__import__("solas_mi").SolasError, match="no depth map"):
        degrade_batch(
            [folder],
            tmp_path / "out2",
            DegradeSpec(depth_pattern="{stem}_depth.exr"),
            psf_grid=tmp_path / "g.exr",
            workers=1,
        )


def test_the_frames_camera_applies_to_every_item(batch_inputs, capsys):
    """`batch degrade` takes `degrade`'s frame-camera options: each item comes out as `degrade` makes it
    with the same camera (a ±1° frame on the ±2° grid: larger blur per pixel), its metadata says so;
    a frame wider than the lens's field fails every item with the numbers."""
    from solas_mi.imageio import read_exr

    (first, *_) = batch_inputs.write(2)
    out, narrow = batch_inputs.root / "out", ["--fov-deg", "1", "--fov-axis", "x"]
    base = ["--psf-grid", str(batch_inputs.grid), "--workers", "1", "--quiet"]
    assert main(["batch", "degrade", str(batch_inputs.images), "-o", str(out), *base, *narrow]) == 0
    assert (
        main(
            [
                "degrade",
                str(first),
                "--psf-grid",
                str(batch_inputs.grid),
                "-o",
                str(batch_inputs.root / "one.exr"),
                *narrow,
            ]
        )
        == 0
    )
    assert main(["batch", "degrade", str(batch_inputs.images), "-o", str(batch_inputs.root / "plain"), *base]) == 0
    ch, meta = read_exr(out / "frame000.exr")
    one, plain = read_exr(batch_inputs.root / "one.exr")[0], read_exr(batch_inputs.root / "plain" / "frame000.exr")[0]
    assert all(np.array_equal(ch[c], one[c]) for c in "RGB")
    assert not np.allclose(ch["G"], plain["G"], atol=1e-4)
    assert meta["frame_camera"]["fov_deg"] == 1.0 and manifest(out)["frame_camera"]["model"] == "fov"
    capsys.readouterr()
    wide = batch_inputs.root / "wide"
    assert main(["batch", "degrade", str(batch_inputs.images), "-o", str(wide), *base, "--fov-deg", "5"]) == 1
    assert "does not cover this frame" in capsys.readouterr().err
    assert manifest(wide)["summary"] == {"failed": 2}


def test_16_bit_png_output(batch_inputs):
    """--format png16: each item a 16-bit sRGB PNG (no 8-bit preview beside it) that reads back as the
    float EXR's values clipped to [0, 1], to within 2e-5, and its metadata in a JSON file."""
    from solas_mi.imageio import read_exr, read_image

    batch_inputs.write(2)
    base = [str(batch_inputs.images), "--psf-grid", str(batch_inputs.grid), "--workers", "1", "--quiet"]
    out, exr = batch_inputs.root / "png16", batch_inputs.root / "exr"
    assert main(["batch", "degrade", *base, "-o", str(out), "--format", "png16"]) == 0
    assert main(["batch", "degrade", *base, "-o", str(exr)]) == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "batch.json",
        "frame000.json",
        "frame000.png",
        "frame001.json",
        "frame001.png",
    ]
    with open(out / "frame000.png", "rb") as f:
        assert f.read(25)[24] == 16  # the IHDR's bit depth
    ch = read_exr(exr / "frame000.exr")[0]
    want = np.clip(np.stack([ch[c] for c in "RGB"], axis=-1), 0, 1)
    assert np.abs(read_image(out / "frame000.png") - want).max() < 2e-5
    meta = strict_loads((out / "frame000.json").read_text())
    assert meta["output_format"] == "png16" and meta["png16"]["clipped_values"] == int(
        np.sum(want != np.stack([ch[c] for c in "RGB"], axis=-1))
    )
    assert main(["batch", "degrade", *base, "-o", str(out), "--format", "png16"]) == 0  # finished: skipped
    assert manifest(out)["summary"] == {"skipped": 2}


def test_one_frame_with_its_intrinsics_and_a_scaled_lens_is_a_batch_of_one(batch_inputs, doublet, capsys):
    """`degrade` takes a computed grid; the path it names for one frame and a lens scaled to the frame's
    intrinsics (`batch degrade FRAME --lens … --intrinsics … --scale-lens …`) takes a single file and writes
    that frame's output with the scaling stated."""
    from solas_mi.imageio import read_exr

    with pytest.raises(SystemExit):
        main(["degrade", "--help"])
    helptext = " ".join(capsys.readouterr().out.split())
    assert "solas-mi batch degrade FRAME --lens LENS --intrinsics FX,FY,CX,CY --scale-lens PIXEL_UM" in helptext
    frame = batch_inputs.write(1)[0]
    fx = 32 / np.tan(np.radians(1.5))
    out = batch_inputs.root / "one"
    argv = [
        "batch",
        "degrade",
        str(frame),
        "--lens",
        "solas-doublet",
        "--intrinsics",
        f"{fx},{fx},31.5,23.5",
        "--scale-lens",
        "5",
        "--grid",
        "3x3",
        "--size",
        "32",
        "--psf-method",
        "geometric",
        "--rays",
        "32",
        "--pitch-um",
        "0.5",
        "--cache",
        str(batch_inputs.root / "cache"),
        "--workers",
        "1",
        "--quiet",
        "-o",
        str(out),
    ]
    assert main(argv) == 0, capsys.readouterr().err
    channels, meta = read_exr(out / "frame000.exr")
    assert all(c.shape == (48, 64) and np.isfinite(c).all() for c in channels.values())
    assert meta["batch"]["lens_scale"]["pixel_um"] == 5.0
    assert meta["batch"]["lens_scale"]["factor"] == pytest.approx(fx * 5e-3 / 99.499, rel=1e-4)
    assert sorted(p.name for p in out.iterdir() if p.suffix in (".exr", ".png")) == ["frame000.exr", "frame000.png"]


def test_label_layers_beside_frames_are_skipped_and_named(batch_inputs, capsys):
    """A frames folder as simulators write it: each frame's depth map (sky at infinity), segmentation and
    normals beside it, and an EXR holding only a depth channel or only label layers. Without
    --depth-pattern the depth maps were degraded as frames and failed (exit 1): now no label layer is
    an input, each is named on stderr with why."""
    from solas_mi.imageio import write_exr, write_png

    (frame,) = batch_inputs.write(1)
    folder = batch_inputs.images
    depth = np.where(np.arange(64)[None, :] < 32, 10.0, np.inf) * np.ones((48, 1))
    write_exr(folder / "frame000_depth.exr", {"Z": depth}, infinite=True)
    write_png(folder / "frame000_seg.png", np.zeros((48, 64, 3)))
    write_png(folder / "normal_0000.png", np.full((48, 64, 3), 0.5))  # the layer first, then the frame number
    write_exr(folder / "z.exr", {"depth": np.ones((48, 64))})
    write_exr(folder / "render.exr", {"depth.Z": np.ones((48, 64)), "labels.valid": np.ones((48, 64))})
    out = batch_inputs.root / "out"
    assert main(["batch", "degrade", str(folder), "--psf-grid", str(batch_inputs.grid), "-o", str(out), "--quiet"]) == 0
    items = strict_loads((out / "batch.json").read_text())["items"]
    assert [(Path(i["input"]).name, i["status"]) for i in items] == [(frame.name, "done")]
    err = capsys.readouterr().err
    assert "skipped 5 label layer(s)" in err and "not frames" in err
    for says in (
        "frame000_depth.exr (its name ends in 'depth')",
        "frame000_seg.png (its name ends in 'seg')",
        "normal_0000.png (its name ends in 'normal')",
        "z.exr (its channels (depth) are labels, no image)",
        "render.exr (its channels (depth.Z, labels.valid) are labels, no image)",
    ):
        assert says in err, err


def test_a_folder_of_label_layers_only_is_refused(batch_inputs, capsys):
    from solas_mi.imageio import write_exr

    write_exr(batch_inputs.images / "a_depth.exr", {"Z": np.ones((48, 64))})
    argv = [
        "batch",
        "degrade",
        str(batch_inputs.images),
        "--psf-grid",
        str(batch_inputs.grid),
        "-o",
        str(batch_inputs.root / "out"),
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "holds only label layers, no frames (a_depth.exr: its name ends in 'depth')" in err, err


def test_depth_maps_by_the_pattern_are_used_not_skipped(batch_inputs, capsys, monkeypatch):
    """With --depth-pattern the frames' depth maps are theirs (not named as skipped); other label layers are."""
    from solas_mi.batch.degrade import plan_batch
    from solas_mi.imageio import write_exr

    (frame,) = batch_inputs.write(1)
    write_exr(frame.with_name("frame000_depth.exr"), {"Z": np.ones((48, 64))})
    write_exr(
        frame.with_name("frame000_flow.exr"), {"R": np.ones((48, 64)), "G": np.ones((48, 64)), "B": np.ones((48, 64))}
    )
    monkeypatch.chdir(batch_inputs.root)  # the folder given as a relative path
    p = plan_batch(["images"], "out", DegradeSpec(depth_pattern="{stem}_depth.exr"), psf_grid=batch_inputs.grid)
    assert [Path(j.params["depth"]).name for j in p.jobs] == ["frame000_depth.exr"]
    err = capsys.readouterr().err
    assert "skipped 1 label layer(s)" in err and "frame000_flow.exr (its name ends in 'flow')" in err, err


def test_the_batch_grid_is_the_lens_at_its_temperature(batch_inputs, capsys):
    """`batch degrade --lens L --temperature-c 60` plans the grid of `Lens.at(60)` (its own cache file, by the
    lens's hash), the plain batch that of the lens as loaded."""
    from solas_mi import Lens
    from solas_mi.batch.cache import GridCache
    from solas_mi.batch.commands import BATCH_GRID_DEFAULTS
    from solas_mi.psf.spec import GridSpec

    batch_inputs.write(1)
    cache = batch_inputs.root / "cache"
    argv = [
        "batch",
        "degrade",
        str(batch_inputs.images),
        "--lens",
        "solas-doublet",
        "--grid",
        "3x3",
        "-o",
        str(batch_inputs.root / "out"),
        "--cache",
        str(cache),
    ]
    plain, hot = _planned_grid(capsys, argv), _planned_grid(capsys, [*argv, "--temperature-c", "60"])
    spec = GridSpec(**{**BATCH_GRID_DEFAULTS, "grid": (3, 3)})
    lens = Lens.load("solas-doublet")
    assert plain == str(GridCache(cache).path(lens, spec)) and hot == str(GridCache(cache).path(lens.at(60.0), spec))
    assert hot != plain
