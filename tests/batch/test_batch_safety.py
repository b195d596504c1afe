"""Names from user data are never paths: a lens name, an input's name or a sweep value cannot make a
batch or the PSF-grid cache write outside its folder (`outputs.safe_name`, `outputs.inside`)."""

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest

from solas_mi.batch.cache import GridCache
from solas_mi.batch.jobs import expand_inputs, plan
from solas_mi.batch.render import plan_render
from solas_mi.errors import SolasError
from solas_mi.optics.lens import Lens
from solas_mi.outputs import hold_folder, inside, safe_name
from solas_mi.psf.grid import PSFGrid
from solas_mi.psf.spec import GridSpec

HOSTILE = ["../../escape", "/etc/passwd", "a/b\\c", "nul\0byte", "new\nline", "..", ".hidden", "", "x" * 400]


@pytest.mark.parametrize("text", HOSTILE)
def test_a_safe_name_is_one_plain_component(text, tmp_path):
    name = safe_name(text)
    assert name and len(name) <= 120 and not name.startswith(".")
    assert not set(name) & set("/\\\0\n\r ")
    assert inside(tmp_path, name + ".exr").parent == tmp_path.resolve()


@pytest.mark.parametrize(
    "text, name",
    [("ïrr ä", "ïrr_ä"), ("東京", "東京"), ("e\u0301te\u0301", "été"), ("é" * 100, "é" * 60)],
    ids=["latin", "cjk", "decomposed", "long"],
)
def test_a_safe_name_keeps_the_letters_of_every_script(text, name):
    """Letters and digits of any script stay (they became "_", and a name of none "item": "ïrr ä.exr"
    gave rr.exr, two CJK names one output, refused), within NAME_MAX bytes of UTF-8."""
    assert safe_name(text) == name and len(name.encode()) <= 120


def test_inputs_named_in_other_scripts_keep_their_names(tmp_path):
    jobs = plan([tmp_path / "東京.png", tmp_path / "大阪.png", tmp_path / "café 1.png"], tmp_path / "out")
    assert [Path(job.output).name for job in jobs] == ["東京.exr", "大阪.exr", "café_1.exr"]


@pytest.mark.parametrize("name", ["../x", "/abs/x", "a/../../x"])
def test_inside_refuses_a_path_leaving_its_folder(name, tmp_path):
    with pytest.raises(SolasError, match="outside the folder"):
        inside(tmp_path, name)


# A name with a control character (NUL, a line break) is refused when the lens is made (tests/optics/test_bad_input.py).
HOSTILE_NAMES = ["../../escaped", "/tmp/abs", "sub/dir", "..", "a\\..\\b"]


def hostile_lens(doublet, folder: Path, name: str, file: str) -> Path:
    return dataclasses.replace(doublet, name=name).save(folder / file)


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_a_lens_name_cannot_lead_batch_render_outputs_out(name, doublet, batch_inputs):
    batch_inputs.write(1, shape=(24, 32))
    a = hostile_lens(doublet, batch_inputs.root, name, "a.toml")
    assert Lens.load(a).name == name  # the name survives the file (escaped), and is still hostile
    out = batch_inputs.root / "deep" / "out"
    p = plan_render([batch_inputs.images], out, lens=[str(a), "solas-doublet"], sensor=(24, 32), spp=1)
    for job in p.jobs:
        for target in (job.output, job.png):
            assert Path(target).parent == out.resolve() and "\n" not in target and "\0" not in target


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_a_lens_name_cannot_lead_the_cache_out(name, doublet, tmp_path):
    lens = Lens.load(hostile_lens(doublet, tmp_path, name, "a.toml"))
    cache = GridCache(tmp_path / "cache")
    path = cache.path(lens, GridSpec())
    assert path.parent == cache.folder and not set(path.name) & set("/\0\n")


def test_an_input_named_with_a_newline_gives_a_plain_output_name(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    (src / "a\nb.png").write_bytes(b"x")
    (job,) = plan(expand_inputs([src]), tmp_path / "out")
    assert Path(job.output).name == "a_b.exr" and Path(job.output).parent == tmp_path / "out"


def test_a_cache_entry_is_reused_only_when_it_is_the_lens_grid_whole(doublet, triplet, tmp_path, capsys):
    import shutil

    from strict_json import strict_loads

    cache = GridCache(tmp_path / "cache")
    spec = GridSpec(grid=(2, 2), size=16, pupil_samples=16)
    a, hit, _ = cache.get(doublet, spec)
    b, _, _ = cache.get(triplet, spec)
    assert not hit and cache.get(doublet, spec)[1] and (cache.hits, cache.misses) == (1, 2)
    good = PSFGrid.read(str(a)).data
    assert strict_loads(Path(f"{a}.json").read_text())["key"]["lens_hash"] == doublet.hash  # its record

    def same(path):
        return np.array_equal(PSFGrid.read(str(path)).data, good)

    shutil.copy(b, a)  # another lens's grid in the doublet's place
    path, hit, _ = cache.get(doublet, spec)
    assert not hit and "not reused" in capsys.readouterr().err and same(path)
    shutil.copy(b, a)
    shutil.copy(f"{b}.json", f"{a}.json")  # both the grid and its record swapped
    assert not cache.get(doublet, spec)[1] and same(a)
    a.write_bytes(a.read_bytes()[:-1000])  # truncated
    assert not cache.get(doublet, spec)[1] and "truncated" in capsys.readouterr().err and same(a)


def degrade_twice(batch_inputs, change, inputs=None):
    """Degrade the frames, `change(out)` the folder, degrade again: the second run's manifest."""
    from strict_json import strict_loads

    from solas_mi.batch import degrade_batch

    out = batch_inputs.root / "out"

    def run():
        return degrade_batch(
            inputs or [batch_inputs.images], out, psf_grid=batch_inputs.grid, workers=1, progress=False
        )

    first = run()
    assert not first.failed
    change(out)
    second = run()
    return out, {Path(j.output).name: j.status for j in second.jobs}, strict_loads((out / "batch.json").read_text())


def test_an_input_replaced_by_another_image_of_its_name_is_done_again(batch_inputs):
    frames = batch_inputs.write(2)
    from solas_mi.imageio import read_exr, write_png

    old = {}

    def replace(out):
        old["data"] = read_exr(out / "frame000.exr")[0]
        write_png(frames[0], np.random.default_rng(7).random((48, 64, 3)))
        os.utime(frames[0], ns=(frames[1].stat().st_atime_ns, frames[1].stat().st_mtime_ns))

    out, status, _ = degrade_twice(batch_inputs, replace)
    assert status == {"frame000.exr": "done", "frame001.exr": "skipped"}
    new = read_exr(out / "frame000.exr")[0]
    assert any(not np.array_equal(new[c], old["data"][c]) for c in new)


def test_a_manifest_pointing_an_item_at_another_items_files_is_not_believed(batch_inputs):
    import json

    from strict_json import strict_loads

    batch_inputs.write(2)

    def edit(out):
        m = strict_loads((out / "batch.json").read_text())
        m["items"][0]["outputs"] = m["items"][1]["outputs"]
        (out / "batch.json").write_text(json.dumps(m))
        (out / "frame000.exr").unlink()

    out, status, _ = degrade_twice(batch_inputs, edit)
    assert status == {"frame000.exr": "done", "frame001.exr": "skipped"} and (out / "frame000.exr").is_file()


def test_an_output_changed_in_place_keeping_size_and_time_is_done_again(batch_inputs):
    batch_inputs.write(1)

    def tamper(out):
        exr = out / "frame000.exr"
        st = exr.stat()
        data = bytearray(exr.read_bytes())
        data[-8:] = bytes(8)
        exr.write_bytes(bytes(data))
        os.utime(exr, ns=(st.st_atime_ns, st.st_mtime_ns))

    _, status, _ = degrade_twice(batch_inputs, tamper)
    assert status == {"frame000.exr": "done"}


def test_a_linked_input_keeps_its_name(batch_inputs, tmp_path):
    (frame,) = batch_inputs.write(1)
    link = tmp_path / "alias.png"
    link.symlink_to(frame)
    _out, status, m = degrade_twice(batch_inputs, lambda out: None, inputs=[link])
    assert status == {"alias.exr": "skipped"} and m["items"][0]["input"] == str(link)


def test_two_batches_on_one_folder_the_second_is_refused_naming_the_first(batch_inputs, tmp_path):
    import signal
    import subprocess
    import sys
    import time

    from strict_json import strict_loads

    from solas_mi.batch import degrade_batch

    batch_inputs.write(16, shape=(240, 320))
    out = tmp_path / "out"
    other = tmp_path / "other"
    other.mkdir()
    (other / "mine.png").write_bytes((batch_inputs.images / "frame000.png").read_bytes())
    first = subprocess.Popen(
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
            "1",
            "--quiet",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while not list(out.glob("[!.]*.exr")) and time.monotonic() < deadline:
        time.sleep(0.05)
    with pytest.raises(SolasError, match=f"in use by batch degrade .*process {first.pid}"):
        degrade_batch([other], out, psf_grid=batch_inputs.grid, workers=1, progress=False)
    first.send_signal(signal.SIGKILL)  # killed outright: its lock goes with it, its temporaries stay
    first.communicate(timeout=60)
    (out / ".frame015.exr.k1lled00.exr").write_bytes(b"half an EXR")  # as a killed writer leaves them
    second = degrade_batch([other], out, psf_grid=batch_inputs.grid, workers=1, progress=False)
    assert second.count("done") == 1
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # its temporaries and the lock gone
    assert strict_loads((out / "batch.json").read_text())["summary"] == {"done": 1}


def test_a_folder_that_turns_read_only_keeps_the_batch_s_error(tmp_path, monkeypatch):
    """The output folder made read-only while a batch runs (a remount, chattr +i): the batch's own
    one-line error (its manifest cannot be written), not a traceback of the lock file's removal; the
    lock file left behind holds nothing."""

    def read_only(path, *args, **kwargs):
        raise PermissionError(1, "Operation not permitted", str(path))

    with pytest.raises(SolasError, match="cannot write"), hold_folder(tmp_path / "out", "a batch"):  # noqa: PT012 -- raised in the hold
        monkeypatch.setattr(os, "unlink", read_only)
        raise SolasError("cannot write out/batch.json: Operation not permitted")
    monkeypatch.undo()
    with hold_folder(tmp_path / "out", "the next batch"):
        pass


def test_workers_are_capped_at_the_cores_and_cost_their_memory(batch_inputs, capsys):
    from solas_mi.batch.degrade import WORKER_BYTES, check_workers, estimate, plan_batch

    assert check_workers(300) == os.cpu_count() and "using" in capsys.readouterr().err
    assert check_workers(300, "tcp://host:8786") == 300  # a remote cluster's workers are its own
    batch_inputs.write(3)
    p = plan_batch([batch_inputs.images], batch_inputs.root / "o", psf_grid=batch_inputs.grid)
    one, three = estimate(p, 1)["peak_bytes"], estimate(p, 3)["peak_bytes"]
    assert three - one >= 2 * WORKER_BYTES["degrade"]


def test_an_address_space_limit_bounds_the_free_memory(tmp_path):
    import subprocess
    import sys

    code = (
        "import resource; from solas_mi.budget import available_memory, check_memory\n"
        "used = int(open('/proc/self/status').read().split('VmSize:')[1].split()[0]) * 1024\n"
        "resource.setrlimit(resource.RLIMIT_AS, (used + (300 << 20), resource.RLIM_INFINITY))\n"
        "assert available_memory() <= 300 << 20, available_memory()\n"
        "check_memory('job', 1e9)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 1 and "SolasError" in run.stderr and "needs about 1.0 GB" in run.stderr, run.stderr


TEXTURED = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="4"/>
        <transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film>
    </sensor>
    <include filename="parts/ball.xml"/>
    <emitter type="constant"/>
</scene>"""
BALL = """<scene version="3.0.0">
    <shape type="sphere">
        <bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename"
            value="textures/skin.png"/></texture></bsdf>
    </shape>
</scene>"""


def test_a_scene_whose_texture_or_include_changed_is_rendered_again(tmp_path):
    """Resume covers what a scene file reads: a texture replaced under its name (size and time kept) or
    an include edited renders the item again; the scene's own file unchanged."""
    from solas_mi.batch.render import render_batch
    from solas_mi.imageio import read_exr, write_png

    (tmp_path / "parts").mkdir()
    (tmp_path / "textures").mkdir()
    scene, texture, include = tmp_path / "ball.xml", tmp_path / "textures" / "skin.png", tmp_path / "parts" / "ball.xml"
    scene.write_text(TEXTURED)
    include.write_text(BALL)
    write_png(texture, np.full((8, 8, 3), 0.2))

    def run():
        result = render_batch([scene], tmp_path / "out", lens="solas-doublet", spp=2, workers=1, progress=False)
        (job,) = result.jobs
        assert job.status in ("done", "skipped"), job.error
        return job.status, read_exr(tmp_path / "out" / "ball.exr")[0]["R"]

    assert run()[0] == "done"
    assert run()[0] == "skipped"
    dark = run()[1]
    st = texture.stat()
    write_png(texture, np.full((8, 8, 3), 0.9))  # another texture, same name and time
    os.utime(texture, ns=(st.st_atime_ns, st.st_mtime_ns))
    status, bright = run()
    assert status == "done" and bright.mean() > 2 * dark.mean()
    include.write_text(BALL.replace('<shape type="sphere">', '<shape type="sphere"><float name="radius" value="0.9"/>'))
    assert run()[0] == "done"
    assert run()[0] == "skipped"
