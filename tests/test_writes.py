"""Every command that writes takes the one output check (`outputs.check_target`), `lens convert`
included; text we write is escaped (a name cannot add a line or a key); an error quotes at most the
name of a file a scene points to, never its content."""

import dataclasses
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from solas_mi.cli import main
from solas_mi.optics.lens import Lens
from solas_mi.optics.paraxial import paraxial


def shipped_file(name="solas-doublet"):
    return Lens.load(name).source


@pytest.fixture
def lens_copy(tmp_path):
    d = tmp_path / "d"
    d.mkdir()
    path = d / "x.toml"
    shutil.copy(shipped_file(), path)
    with open(path, "a") as f:
        f.write("# a comment the converter would drop\n")
    return path


@pytest.mark.parametrize("spelling", ["{p}", "{d}/../d/x.toml", "{d}/./x.toml"])
def test_lens_convert_never_rewrites_its_input(lens_copy, spelling, capsys):
    before = lens_copy.read_bytes()
    out = spelling.format(p=lens_copy, d=lens_copy.parent)
    assert main(["lens", "convert", str(lens_copy), "-o", out]) == 2
    assert "input of this command" in capsys.readouterr().err
    assert lens_copy.read_bytes() == before


def test_lens_convert_never_replaces_a_link_a_folder_or_a_device(lens_copy, tmp_path, capsys):
    target = tmp_path / "target.zmx"
    target.write_text("keep")
    link = tmp_path / "link.zmx"
    link.symlink_to(target)
    for out, kind in ((link, "symbolic link"), (tmp_path, "folder"), ("/dev/null", "not a regular file")):
        assert main(["lens", "convert", str(lens_copy), "-o", str(out)]) == 2
        assert kind in capsys.readouterr().err
    assert link.is_symlink() and target.read_text() == "keep"


# Names with a line break or control character are refused when the lens is made (tests/optics/test_bad_input.py).
NAMES = ['a "quote"', "close ] bracket", "hash # sign", "back\\slash", 'x" name = "evil', 'x\\" ] evil']


@pytest.mark.parametrize("ext", [".toml", ".dat"])
@pytest.mark.parametrize("name", NAMES)
def test_a_name_written_into_a_lens_file_reads_back_as_written(doublet, name, ext, tmp_path):
    lens = dataclasses.replace(doublet, name=name, description=name)
    path = lens.save(tmp_path / f"lens{ext}")
    plain = doublet.save(tmp_path / f"plain{ext}")
    back = Lens.load(path)
    assert len(back.surfaces) == len(doublet.surfaces)
    assert paraxial(back).efl_mm == paraxial(Lens.load(plain)).efl_mm
    if ext == ".toml":
        assert (back.name, back.description) == (name, name)
    assert path.read_text().count("\n") == plain.read_text().count("\n")  # no line added


SECRET = "root:$6$s3cr3t-hash-never-printed:19000:0:99999:7:::"


@pytest.mark.parametrize(
    "content", [f"first line\n{SECRET}\n", f"{SECRET}\n1,2,3,4\n", "1,2,3,4\n" + SECRET, "\xff\xfe" + SECRET]
)
def test_a_response_table_is_never_quoted(tmp_path, content):
    from solas_mi.errors import SolasError
    from solas_mi.render.response import parse

    secret = tmp_path / "shadow"
    secret.write_bytes(content.encode("latin-1"))
    with pytest.raises(SolasError) as info:
        parse(f"table:{secret}", [486.1, 587.6, 656.3])
    assert "shadow" in str(info.value) and "s3cr3t" not in str(info.value)


def test_scene_folders_of_killed_renders_are_removed_by_the_next(tmp_path, monkeypatch):
    import tempfile

    from solas_mi.render.image import SCENE_PREFIX, remove_stale_scenes

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = tmp_path / f"{SCENE_PREFIX}{int(dead.stdout)}-abcd1234"
    live = tmp_path / f"{SCENE_PREFIX}{os.getppid()}-abcd1234"
    for folder in (stale, live):
        (folder / "meshes").mkdir(parents=True)
        (folder / "scene.xml").write_text("<scene/>")
    assert remove_stale_scenes() == 1 and not stale.exists() and live.is_dir()


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--spp", "100000000"], "samples per pixel 100000000"),
        (["--spp-ideal", "0"], "samples per pixel 0"),
        (["--size", "100000x100000"], "render 100000x100000 needs about"),
    ],
)
def test_the_street_experiment_checks_its_renders_before_any_work(tmp_path, capsys, extra, message):
    out = tmp_path / "street"
    assert main(["experiment", "street", "-o", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and not out.exists()


def test_paths_and_names_written_into_scene_xml_cannot_add_elements(doublet, tmp_path):
    import xml.etree.ElementTree as ET

    from solas_mi.render.scene import write_scene

    image = str(tmp_path / 'a"b<c&d\nx"/><emitter type="constant"/><x y=".exr')
    response = 'table:r"s.csv'
    xml = write_scene(doublet, tmp_path / "scene", image, response=response)
    root = ET.parse(xml).getroot()
    defaults = {d.get("name"): d.get("value") for d in root.iter("default")}
    assert defaults["image"] == image and defaults["response"] == response
    assert not list(root.iter("emitter")) or all(e.get("type") != "constant" for e in root.iter("emitter"))


def test_temporaries_of_a_killed_writer_are_removed_by_the_next_write(lens_copy, tmp_path, capsys):
    dead = int(
        subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True).stdout
    )
    stale = tmp_path / f".out.zmx.{dead}.k1lled00.zmx"
    live = tmp_path / f".out.zmx.{os.getppid()}.wr1t1ng0.zmx"  # a writer still running: kept
    other = tmp_path / f".other.zmx.{dead}.k1lled00.zmx"  # another target's: its own next write removes it
    for f in (stale, live, other):
        f.write_text("half a file")
    assert main(["lens", "convert", str(lens_copy), "-o", str(tmp_path / "out.zmx")]) == 0
    assert not stale.exists() and live.exists() and other.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.zmx.") and p != live]


def test_a_lens_file_written_into_a_scene_folder_is_named_plainly(doublet, tmp_path):
    from solas_mi.render.scene import lens_file

    odd = tmp_path / "src" / "two\nlines ..x.toml"
    odd.parent.mkdir()
    changed = dataclasses.replace(doublet, source=str(odd), description="changed in memory")
    held = lens_file(changed, tmp_path / "scene")
    assert held.parent == (tmp_path / "scene").resolve() and "\n" not in held.name and " " not in held.name


def test_two_writers_of_one_output_pair_leave_one_writers_pair_whole(tmp_path, monkeypatch):
    """Single-file commands take no folder lock: two writers of the same EXR + PNG at once. The first
    is held between its two renames while the second writes: each file ends whole, the pair comes from
    one writer (not the data of one and the preview of the other), neither's temporaries are removed
    by the other, and none is left."""
    import threading

    from solas_mi.outputs import written_together

    targets = (tmp_path / "r.exr", tmp_path / "r.png")
    real_replace = os.replace
    first_renamed, second_done = threading.Event(), threading.Event()

    def replace(src, dst):
        real_replace(src, dst)
        if threading.current_thread().name == "first" and not first_renamed.is_set():
            first_renamed.set()
            second_done.wait(2.0)  # the second writer renames here unless the first holds the folder

    monkeypatch.setattr(os, "replace", replace)

    def write(tag: str) -> None:
        with written_together(*targets) as tmps:
            for tmp in tmps:
                Path(tmp).write_text(f"{tag} " * 1000)
        if tag == "second":
            second_done.set()

    first = threading.Thread(target=write, args=("first",), name="first")
    first.start()
    assert first_renamed.wait(30)
    second = threading.Thread(target=write, args=("second",), name="second")
    second.start()
    first.join(30)
    second.join(30)
    contents = {p.read_text() for p in targets}
    assert contents in ({"first " * 1000}, {"second " * 1000}), [c[:7] for c in contents]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.exr", "r.png"]


def test_two_commands_writing_one_output_at_once_both_succeed(tmp_path):
    """Two real processes writing one -o at once: neither removes the other's temporaries (each
    carries its live writer's process id), both succeed, and what is left is one whole EXR and PNG."""
    from solas_mi.imageio import read_exr

    runs = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "solas_mi",
                "psf",
                "solas-doublet",
                "--field-deg",
                field,
                "--wavelengths-nm",
                "531",
                "--size",
                "48",
                "-o",
                "p.exr",
            ],
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for field in ("0,0", "0,1")
    ]
    for p in runs:
        _, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
    data, _meta = read_exr(tmp_path / "p.exr")
    assert data and sorted(f.name for f in tmp_path.iterdir()) == ["p.exr", "p.png"]
