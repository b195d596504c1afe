"""`solas-mi batch render` and `render_batch`: images and scene files through a lens, a failed item
reported, resuming, the sweep's product, seeds, local processes against Dask. Tiny sensors, few spp."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi.batch.render import plan_render, render_batch, seed_of
from solas_mi.cli import main
from solas_mi.errors import SolasError
from solas_mi.imageio import read_exr

SCENE = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="4"/>
        <transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="16"/></film>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    </sensor>
    <shape type="sphere"/>
    <emitter type="constant"/>
</scene>"""


def manifest(folder):
    return strict_loads((folder / "batch.json").read_text())


@pytest.fixture
def render_inputs(batch_inputs):
    """Three 24×32 images, one corrupt image and one scene file."""
    batch_inputs.write(3, shape=(24, 32))
    (batch_inputs.images / "broken.png").write_bytes(b"not a png")
    (batch_inputs.images / "sphere.xml").write_text(SCENE)
    return batch_inputs


def channels(path):
    data, meta = read_exr(path)
    return np.stack([data[c] for c in sorted(data)]), meta


def test_images_and_a_scene_one_corrupt_reported_and_a_rerun_skips(render_inputs, capsys):
    out = render_inputs.root / "out"
    argv = [
        "batch",
        "render",
        str(render_inputs.images),
        "--lens",
        "solas-doublet",
        "--sensor",
        "32x24",
        "--spp",
        "4",
        "-o",
        str(out),
        "--workers",
        "2",
        "--quiet",
    ]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "broken.png" in err and "cannot read image" in err
    m = manifest(out)
    assert m["kind"] == "render" and m["summary"] == {"done": 4, "failed": 1}
    (bad,) = [i for i in m["items"] if i["status"] == "failed"]
    assert bad["input"].endswith("broken.png") and "cannot read image" in bad["error"]
    assert sorted(p.name for p in out.glob("*.exr")) == ["frame000.exr", "frame001.exr", "frame002.exr", "sphere.exr"]
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
    # the scene file went through the lens camera, at its film's size; the images onto the sensor
    image, meta = channels(out / "sphere.exr")
    assert image.shape[1:] == (16, 24) and meta["sensor"].startswith("LensCamera") and np.all(np.isfinite(image))
    assert image.mean() > 0
    image, meta = channels(out / "frame001.exr")
    assert image.shape == (3, 24, 32) and meta["variant"] == m["variant"]
    item = next(i for i in m["items"] if i["output"].endswith("frame001.exr"))
    assert meta["batch"]["seed"] == item["seed"] == seed_of("frame001", 0)
    assert meta["batch"]["params"]["lens_hash"] == item["params"]["lens_hash"]
    times = {p.name: p.stat().st_mtime_ns for p in out.glob("[!b]*")}
    assert main(argv) == 1  # the corrupt one fails again; nothing else is touched
    assert {p.name: p.stat().st_mtime_ns for p in out.glob("[!b]*")} == times
    assert manifest(out)["summary"] == {"skipped": 4, "failed": 1}


def test_a_sweep_renders_the_product_and_names_its_parameters(render_inputs, tmp_path):
    image = render_inputs.images / "frame000.png"
    result = render_batch(
        [image],
        tmp_path / "sweep",
        lens=["solas-doublet", "cooke-triplet"],
        sensor=["16x12", "24x8"],
        spp=[1, 2],
        workers=1,
        progress=False,
    )
    assert [j.status for j in result.jobs] == ["done"] * 8
    m = manifest(tmp_path / "sweep")
    assert set(m["sweep"]) == {"lens", "sensor", "spp"}
    names = sorted(p.stem for p in (tmp_path / "sweep").glob("*.exr"))
    assert names == sorted(
        f"frame000_{lens}_{sensor}_spp{spp}"
        for lens in ("solas-doublet", "cooke-triplet")
        for sensor in ("16x12", "24x8")
        for spp in (1, 2)
    )
    for item in m["items"]:
        rows, cols = item["params"]["sensor"]
        data, meta = channels(item["output"])
        assert data.shape[1:] == (rows, cols)  # the sensor of its sweep point
        assert meta["lens"] == item["params"]["lens_name"] and meta["spp"] == item["params"]["spp"]
    assert len({i["seed"] for i in m["items"]}) > 1
    # the sweep grown by a value: only the new sweep points are rendered, the eight finished ones skipped
    grown = render_batch(
        [image],
        tmp_path / "sweep",
        lens=["solas-doublet", "cooke-triplet"],
        sensor=["16x12", "24x8"],
        spp=[1, 2, 3],
        workers=1,
        progress=False,
    )
    statuses = {Path(j.output).stem: j.status for j in grown.jobs}
    assert sorted(k for k, v in statuses.items() if v == "done") == sorted(
        f"frame000_{lens}_{sensor}_spp3" for lens in ("solas-doublet", "cooke-triplet") for sensor in ("16x12", "24x8")
    )
    assert sum(v == "skipped" for v in statuses.values()) == 8


def test_focus_sweep_of_a_scene_and_its_limits(render_inputs, tmp_path):
    scene = render_inputs.images / "sphere.xml"
    result = render_batch(
        [scene], tmp_path / "focus", lens="solas-doublet", focus_distance=[5.0, "inf"], spp=2, workers=1, progress=False
    )
    assert [j.status for j in result.jobs] == ["done", "done"]
    assert sorted(p.name for p in (tmp_path / "focus").glob("*.exr")) == ["sphere_focus5.exr", "sphere_focusinf.exr"]
    near, _ = channels(tmp_path / "focus" / "sphere_focus5.exr")
    far, _ = channels(tmp_path / "focus" / "sphere_focusinf.exr")
    assert not np.array_equal(near, far)  # refocusing moved the lens: another image
    with pytest.raises(SolasError, match="focus distance"):  # images lie on the object plane
        plan_render([render_inputs.images / "frame000.png"], tmp_path / "x", lens="solas-doublet", focus_distance=[5.0])
    with pytest.raises(SolasError, match="film sets its sensor"):
        plan_render([scene], tmp_path / "x", lens="solas-doublet", sensor=["8x8", "16x16"])
    with pytest.raises(SolasError, match="samples per pixel"):
        plan_render([scene], tmp_path / "x", lens="solas-doublet", spp=[0])
    assert main(["batch", "render", str(scene), "--lens", "solas-doublet", "--spp", "2,x", "-o", str(tmp_path)]) == 2


def test_dask_local_and_local_processes_are_bit_identical(render_inputs, tmp_path):
    inputs = [render_inputs.images / "frame000.png", render_inputs.images / "sphere.xml"]
    common = dict(lens="solas-doublet", sensor="32x24", spp=4, progress=False, workers=2)
    local = render_batch(inputs, tmp_path / "local", **common)
    dask = render_batch(inputs, tmp_path / "dask", dask="local", **common)
    assert [j.status for j in local.jobs] == [j.status for j in dask.jobs] == ["done", "done"]
    assert manifest(tmp_path / "dask")["runner"] == {"dask": "local"}
    for name in ("frame000.exr", "sphere.exr"):
        a, _ = channels(tmp_path / "local" / name)
        b, _ = channels(tmp_path / "dask" / name)
        assert np.array_equal(a, b)
    # another base seed: other samples, another image
    other = render_batch(inputs[:1], tmp_path / "seed", seed=1, **common)
    assert other.jobs[0].seed == seed_of("frame000", 1) != local.jobs[0].seed
    assert not np.array_equal(
        channels(tmp_path / "seed" / "frame000.exr")[0], channels(tmp_path / "local" / "frame000.exr")[0]
    )


def test_one_wavelength_renders_in_the_spectral_variant(render_inputs, tmp_path):
    """A mono:λ response cannot use a mono variant (module docstring of batch.render: the lens camera
    needs each path's wavelength); the spectral variant renders it, recorded. Every path carries
    550 nm, so the scene's RGB film sees one colour: its pixels are multiples of one RGB vector, far
    from white (a flat spectrum's colour)."""
    result = render_batch(
        [render_inputs.images / "sphere.xml"],
        tmp_path / "mono",
        lens="solas-doublet",
        spp=2,
        response="mono:550",
        workers=1,
        progress=False,
    )
    assert result.jobs[0].status == "done", result.jobs[0].error
    data, meta = read_exr(result.jobs[0].output)
    assert meta["variant"].endswith("_spectral") and manifest(tmp_path / "mono")["variant"] == meta["variant"]
    rgb = np.stack([data[c].ravel() for c in "RGB"], axis=1)
    s = np.linalg.svd(rgb, compute_uv=False)
    assert s[1] < 1e-4 * s[0]
    colour = np.linalg.svd(rgb)[2][0]
    assert abs(colour @ np.ones(3) / np.sqrt(3)) < 0.9


def test_sigterm_midway_leaves_no_partial_render(batch_inputs):
    batch_inputs.write(12, shape=(48, 64))
    out = batch_inputs.root / "out"
    p = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "solas_mi",
            "batch",
            "render",
            str(batch_inputs.images),
            "--lens",
            "solas-doublet",
            "--sensor",
            "64x48",
            "--spp",
            "64",
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
    while len(list(out.glob("[!.]*.exr"))) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 143, err
    m = manifest(out)
    done = {i["output"] for i in m["items"] if i["status"] == "done"}
    written = {str(f) for f in out.glob("*.exr")}
    assert len(done) >= 1 and done <= written and len(written) < 12 and len(written - done) <= 2
    assert not [f for f in out.iterdir() if f.name.startswith(".")]
    # an item its worker held is recorded as interrupted (done again on a re-run), never as failed
    assert {i["status"] for i in m["items"]} <= {"done", "pending", "interrupted"}, m["items"]
    for f in written:
        data, meta = read_exr(f)
        assert data["R"].shape == (48, 64) and meta["spp"] == 64 and Path(f).with_suffix(".png").is_file()


def test_dry_run_names_the_stages_and_what_is_finished(render_inputs, tmp_path, capsys):
    image = render_inputs.images / "frame000.png"
    argv = [
        "batch",
        "render",
        str(image),
        "--lens",
        "solas-doublet",
        "--sensor",
        "16x12",
        "--spp",
        "1,2",
        "-o",
        str(tmp_path / "d"),
        "--workers",
        "1",
    ]
    assert main(argv + ["--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "no PSF grid" in out and "render 2 of 2 items (0 already finished" in out and "spp (2 values)" in out
    assert not (tmp_path / "d").exists()  # nothing done
    assert main(argv + ["--quiet"]) == 0
    capsys.readouterr()
    assert main(argv + ["--dry-run"]) == 0
    assert "render 0 of 2 items (2 already finished" in capsys.readouterr().out


@pytest.mark.parametrize(
    "address",
    ["not a url", "http://host:8786", "tcp://host", "tcp://host:99999", "host:port", "", "tcp://host:8786/path"],
)
def test_a_bad_dask_address_is_refused_before_any_work(render_inputs, tmp_path, address):
    """Named with the forms allowed, before the plan (nothing written) rather than as a traceback
    from the scheduler client once the items start."""
    from solas_mi.batch.runner import check_dask

    with pytest.raises(SolasError, match=r"must be a scheduler address, tcp://HOST:PORT .* or local"):
        render_batch(
            [render_inputs.images / "frame000.png"], tmp_path / "never", lens="solas-doublet", spp=1, dask=address
        )
    assert not (tmp_path / "never").exists()
    for good in ("local", "tcp://127.0.0.1:8786", "tls://scheduler.example:8786", "10.0.0.5:8786", None):
        check_dask(good)


def test_labels_of_a_scene_batch_are_layers_recorded_in_the_manifest(render_inputs, tmp_path):
    """`--labels depth,instance`: each scene item's EXR holds the layers beside its image (the sphere 4 m
    in front of the camera: the depth at the centre from the lens's entrance pupil), the option is in
    the manifest's settings and its items, and part of the batch's identity; image inputs are refused."""
    from solas_mi import Lens, paraxial

    scene = render_inputs.images / "sphere.xml"
    out = tmp_path / "labels"
    argv = [
        "batch",
        "render",
        str(scene),
        "--lens",
        "solas-doublet",
        "--spp",
        "2",
        "--labels",
        "instance,depth",
        "-o",
        str(out),
        "--workers",
        "1",
        "--quiet",
    ]
    assert main(argv) == 0
    data, meta = read_exr(out / "sphere.exr")
    assert {"depth.Z", "instance.id", "labels.valid"} <= set(data) and "normal.X" not in data
    lens = Lens.load("solas-doublet")
    expected = 4.0 + (paraxial(lens).entrance_pupil_z_mm - lens.vertex_z[0]) * 1e-3
    assert abs(data["depth.Z"][8, 12] / expected - 1.0) < 1e-3
    assert meta["labels"]["kinds"] == ["depth", "instance"] and meta["batch"]["params"]["labels"] == "depth,instance"
    m = manifest(out)
    assert m["settings"]["labels"] == "depth,instance" and m["items"][0]["params"]["labels"] == "depth,instance"
    plain = plan_render([scene], tmp_path / "plain", lens="solas-doublet", spp=2)
    assert plain.key != m["batch_id"]
    with pytest.raises(SolasError, match="labels are traced through the lens camera of scene files"):
        plan_render([render_inputs.images / "frame000.png"], tmp_path / "x", lens="solas-doublet", labels="depth")
