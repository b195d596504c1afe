"""Names from user data are never paths: a lens name, an input's name or a sweep value cannot make a
batch or the PSF-grid cache write outside its folder (`outputs.safe_name`, `outputs.inside`)."""
import dataclasses
import os
from pathlib import Path

import pytest

from solas_mi.batch.cache import GridCache
from solas_mi.batch.jobs import expand_inputs, plan
from solas_mi.batch.render import plan_render
from solas_mi.errors import SolasError
from solas_mi.optics.lens import Lens
from solas_mi.outputs import inside, safe_name
from solas_mi.psf.spec import GridSpec

HOSTILE = ["../../escape", "/etc/passwd", "a/b\\c", "nul\0byte", "new\nline", "..", ".hidden", "", "x" * 400]


@pytest.mark.parametrize("text", HOSTILE)
def test_a_safe_name_is_one_plain_component(text, tmp_path):
    name = safe_name(text)
    assert name and len(name) <= 120 and not name.startswith(".")
    assert not set(name) & set("/\\\0\n\r ")
    assert inside(tmp_path, name + ".exr").parent == tmp_path.resolve()


@pytest.mark.parametrize("name", ["../x", "/abs/x", "a/../../x"])
def test_inside_refuses_a_path_leaving_its_folder(name, tmp_path):
    with pytest.raises(SolasError, match="outside the folder"):
        inside(tmp_path, name)


def hostile_lens(doublet, folder: Path, name: str, file: str) -> Path:
    return dataclasses.replace(doublet, name=name).save(folder / file)


@pytest.mark.parametrize("name", ["../../escaped", "/tmp/abs", "sub/dir", "nul\0x", "two\nlines"])
def test_a_lens_name_cannot_lead_batch_render_outputs_out(name, doublet, batch_inputs):
    batch_inputs.write(1, shape=(24, 32))
    a = hostile_lens(doublet, batch_inputs.root, name, "a.toml")
    assert Lens.load(a).name == name  # the name survives the file (escaped), and is still hostile
    out = batch_inputs.root / "deep" / "out"
    p = plan_render([batch_inputs.images], out, lens=[str(a), "solas-doublet"], sensor=(24, 32), spp=1)
    for job in p.jobs:
        for target in (job.output, job.png):
            assert Path(target).parent == out.resolve() and "\n" not in target and "\0" not in target


@pytest.mark.parametrize("name", ["../../escaped", "/tmp/abs", "sub/dir", "nul\0x", "two\nlines"])
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
