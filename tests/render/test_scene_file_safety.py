"""The files a Mitsuba scene names, as a hostile or broken scene names them (`render.user_scene`): a mesh
whose header is someone's secret, a FIFO or /dev/zero as a mesh, a texture, an include or the scene
itself. Refused in time (Mitsuba would wait on a FIFO for ever), naming the file, never quoting it."""

import os
import subprocess
import sys

import pytest
from in_time import WAIT_S, refused

from solas_mi.render.user_scene import load

VARIANT = "llvm_ad_spectral"
SECRET = "SECRET_TOKEN=hunter2"


def _scene(folder, body: str):
    path = folder / "scene.xml"
    path.write_text(f'<scene version="3.0.0">\n{body}\n    <shape type="sphere"/>\n</scene>\n')
    return path


def test_a_mesh_error_quotes_nothing_of_the_mesh(tmp_path):
    """Mitsuba's PLY reader quotes the token it could not read ("unknown token "SECRET_TOKEN=hunter2"",
    a line of any file a scene names): the message keeps what the scene says and drops the rest."""
    (tmp_path / "mesh.ply").write_text(f"{SECRET}\nmore\n")
    message = refused(
        load, _scene(tmp_path, '<shape type="ply"><string name="filename" value="mesh.ply"/></shape>'), VARIANT
    )
    assert "hunter2" not in message and "SECRET" not in message
    assert "mesh.ply" in message and "invalid PLY header" in message  # what went wrong, and where


MESH = '<shape type="ply"><string name="filename" value="{name}"/></shape>'
SPECTRUM = '<bsdf type="diffuse" id="b"><spectrum name="reflectance" filename="{name}"/></bsdf>'


@pytest.mark.parametrize(
    "body, name, data",
    [
        (MESH, "mesh.ply", SECRET.encode() + b"\0OTHER=x\n"),  # a token cut at a NUL, as in /proc/self/environ
        (MESH, "mesh.ply", b'ply"' + SECRET.encode() + b" more\n"),  # a quote inside the token
        (SPECTRUM, "spectrum.spd", f'{SECRET} "x" more\n'.encode()),  # a line of a spectrum file
    ],
    ids=["token-cut-at-nul", "quote-in-token", "spectrum-line"],
)
def test_what_mitsuba_quotes_of_a_named_file_is_left_out(tmp_path, body, name, data):
    """Mitsuba quotes what it read without escaping it: a token cut at a NUL byte left its quote open
    ("unknown token "SECRET_TOKEN=hunter2!", the first variable of /proc/self/environ), and a quote in the
    file's text closed it early, so the rest of the line came out. The message ends at that quote."""
    (tmp_path / name).write_bytes(data)
    message = refused(load, _scene(tmp_path, body.format(name=name)), VARIANT)
    assert "hunter2" not in message and "SECRET" not in message and "more" not in message, message
    assert name in message  # the file is named


@pytest.mark.parametrize(
    "name, text",
    [
        ("lens.dat", f"{SECRET} 1 2 3\n"),  # the .dat reader quotes a row that is no numbers
        ("lens.seq", f"{SECRET}\n"),  # the CODE V reader names an unknown command
        ("lens.toml", f"{SECRET.replace('=', '_')} = 1\n"),  # the TOML reader names an unknown key
    ],
    ids=["dat", "seq", "toml"],
)
def test_a_lens_file_the_scene_names_is_not_quoted(tmp_path, name, text):
    """A lens_camera's lens is a file the scene names: the lens readers' refusals quote the faulty line
    (right for a lens file the user gives), so a shared scene could print a line of any .dat, .seq or
    .toml file. The refusal names the file and the command that says why."""
    (tmp_path / name).write_text(text)
    sensor = (
        f'<sensor type="lens_camera"><string name="lens" value="{name}"/><float name="pitch_um" value="20"/>'
        '<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>'
    )
    message = refused(load, _scene(tmp_path, sensor), VARIANT)
    assert "SECRET" not in message and "hunter2" not in message, message
    assert name in message and "solas-mi lens info" in message


def test_a_scene_that_is_no_xml_keeps_the_parser_s_reason(tmp_path):
    (tmp_path / "scene.xml").write_text("not xml at all")
    message = refused(load, tmp_path / "scene.xml", VARIANT)
    assert "scene.xml" in message and "No document element found" in message


def _render(scene, tmp_path) -> subprocess.CompletedProcess:
    """`solas-mi render` of `scene` in its own process: Mitsuba's parser, blocked on a FIFO, holds the
    interpreter, so only a process can be timed out."""
    return subprocess.run(
        [sys.executable, "-m", "solas_mi", "render", str(scene), "--spp", "1", "-o", str(tmp_path / "out.exr")],
        capture_output=True,
        text=True,
        timeout=WAIT_S,
    )


@pytest.mark.parametrize("target", ["fifo", "/dev/zero"])
@pytest.mark.parametrize(
    "body",
    [
        '<shape type="ply"><string name="filename" value="{name}"/></shape>',
        '<texture type="bitmap" id="t"><string name="filename" value="{name}"/></texture>',
        '<include filename="{name}"/>',
    ],
)
def test_what_a_scene_names_is_a_regular_file(tmp_path, target, body):
    """A mesh, texture or include that is a FIFO or a device: one line, exit 2 (before: Mitsuba waited on
    the FIFO for ever, or read the device)."""
    if target == "fifo":
        os.mkfifo(tmp_path / "fifo")
    done = _render(_scene(tmp_path, body.format(name=target)), tmp_path)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr[-300:]
    assert "is not a regular file" in done.stderr and target in done.stderr
    assert not (tmp_path / "out.exr").exists()


def test_the_scene_itself_is_a_regular_file(tmp_path):
    os.mkfifo(tmp_path / "scene.xml")
    assert "is not a regular file" in refused(load, tmp_path / "scene.xml", VARIANT)
