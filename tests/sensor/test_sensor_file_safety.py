"""A sensor model, its QE curve and an ISP file as a tester (or a hostile sensor file) gives them: files
that are no text, devices, FIFOs, the process environment. Each is one line naming the file and what is
allowed, in time, quoting nothing the file holds (`solas_mi.userfiles`)."""

import os
import re

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.errors import SolasError
from solas_mi.imageio import write_exr
from solas_mi.sensor.files import load_sensor


def _camera(folder, sensor, isp=None) -> list[str]:
    return [
        "camera",
        str(folder / "in.exr"),
        "--sensor-model",
        str(sensor),
        "--exposure-ms",
        "5",
        *(["--isp", str(isp)] if isp else []),
        "-o",
        str(folder / "raw.exr"),
    ]


@pytest.fixture
def folder(tmp_path):
    write_exr(tmp_path / "in.exr", {c: np.full((8, 8), 0.02, np.float32) for c in "RGB"})
    (tmp_path / "sensor.toml").write_text("[sensor]\npixel_pitch_um = 3.0\n")
    return tmp_path


@pytest.mark.parametrize("curve", ["/proc/self/environ", "secrets.csv"])
def test_a_qe_curve_error_quotes_nothing_of_the_file(folder, curve):
    """A sensor file's `qe_curve` may name any file the user can read: the refusal names the file, never
    a line of it (before: "columns SHELL=/bin/bash ... unknown", the whole environment)."""
    secrets = {v for v in os.environ.values() if len(v) > 3} | {"hunter2"}
    (folder / "secrets.csv").write_text("TOKEN=hunter2,wavelength_nm\n400,0.5\n")
    (folder / "s.toml").write_text(f'[sensor]\nqe_curve = "{curve}"\n')
    with pytest.raises(SolasError, match=f"QE curve '.*{os.path.basename(curve)}'") as info:
        load_sensor(folder / "s.toml")
    assert not any(s in str(info.value) for s in secrets), str(info.value)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda p: os.symlink("/dev/zero", p), "is not a regular file"),
        (lambda p: p.write_bytes("[sensor]\n# caf\xe9\n".encode("latin-1")), "is not UTF-8 text"),
        (lambda p: p.write_bytes("[sensor]\npixel_pitch_um = 3.0\n".encode("utf-16")), "is not UTF-8 text"),
        (lambda p: p.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR"), "is not UTF-8 text"),
        (lambda p: p.write_text("[sensor]\nx = " + "[" * 3000 + "]" * 3000 + "\n"), "nests tables and arrays"),
    ],
    ids=["dev-zero", "latin-1", "utf-16", "binary", "nested"],
)
@pytest.mark.parametrize("role", ["sensor", "isp"])
def test_odd_sensor_and_isp_files_are_one_line(folder, capsys, make, message, role):
    """--sensor-model /dev/zero read 2 GB in 14 s (a FIFO, which waited for ever: `test_odd_files`); Latin-1,
    UTF-16 and binary files raised UnicodeDecodeError, deep arrays RecursionError. Now: exit 2, one line,
    nothing written."""
    odd = folder / "odd.toml"
    make(odd)
    argv = _camera(folder, odd) if role == "sensor" else _camera(folder, folder / "sensor.toml", odd)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err and "odd.toml" in err, err
    assert re.search("sensor model|isp file", err)
    assert not (folder / "raw.exr").exists()
