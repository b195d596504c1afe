"""The command line as a whole (`cli`): composition of the stages' commands, --version, and user
errors as one line naming the bad value."""

import numpy as np
import pytest
from PIL import Image
from strict_json import strict_loads

from solas_mi import __version__
from solas_mi.cli import main

PHOTO_SMALL = Image.fromarray((np.indices((24, 32)).sum(axis=0) * 4).astype(np.uint8))


def test_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.strip() == f"solas-mi {__version__}"


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["psf", "solas-doublet", "--field-deg", "0,2", "--wavelengths-nm", "", "-o", "{tmp}/x.exr"],
            "--wavelengths-nm '' must be one or more comma-separated numbers",
        ),
        (
            ["psf", "solas-doublet", "--field-deg", "0,89", "--wavelengths-nm", "531", "-o", "{tmp}/x.exr"],
            "field (0, 89) deg: each angle must be finite and below 89 deg in magnitude",
        ),
        (
            ["psf", "solas-doublet", "--field-deg", "0,1", "--wavelengths-nm", "2500.0001", "-o", "{tmp}/x.exr"],
            "wavelength 2500.0001 nm is outside glass SCHOTT:N-BK7's valid range 300-2500 nm",
        ),
        (["sfr", "{tmp}"], "is a folder, not an image file"),
        (["sfr", "{tmp}/garbage.png"], "cannot read image"),
        (
            ["lens", "info", "{tmp}/binary.toml"],
            "binary.toml' is not UTF-8 text (byte 1 is not UTF-8: Latin-1 or binary)",
        ),
        (
            [
                "psf",
                "solas-doublet",
                "--field-deg",
                "0,1",
                "--wavelengths-nm",
                "531",
                "--pupil-samples",
                "100000",
                "-o",
                "{tmp}/x.exr",
            ],
            "pupil samples 100000 must be an integer from 8 to 4096",
        ),
        (
            [
                "render-image",
                "solas-doublet",
                "{tmp}/photo.png",
                "--sensor",
                "32x24",
                "--spp",
                "1",
                "--seed",
                "-1",
                "-o",
                "{tmp}/x.exr",
            ],
            "seed -1 must be an integer from 0 to 4294967295",
        ),
        (
            ["scene", "solas-doublet", "-o", "{tmp}/scene", "--spp", "0"],
            "samples per pixel 0 must be an integer from 1",
        ),
        (["scene", "solas-doublet", "-o", "{tmp}/scene", "--response", "mono:x"], "mono needs a wavelength in nm"),
        (
            ["scene", "solas-doublet", "-o", "{tmp}/scene", "--response", "table:{tmp}/rising.csv"],
            "wavelengths must increase",
        ),
        (["ss-sfr", "{tmp}/photo.png", "--plot", "{tmp}/photo.png"], "is an input of this command"),
        (["sfr-target", "-o", "{tmp}/t.png", "--low", "0.5", "--high", "0.5"], "an edge needs two different levels"),
    ],
)
def test_user_errors_are_one_line(tmp_path, capsys, argv, message):
    (tmp_path / "garbage.png").write_text("not a png")
    (tmp_path / "binary.toml").write_bytes(b"\x89PNG\r\n")
    (tmp_path / "rising.csv").write_text("nm,r,g,b\n600,1,1,1\n500,1,1,1\n")
    PHOTO_SMALL.save(tmp_path / "photo.png")
    assert main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "pip install" not in err
    assert not (tmp_path / "x.exr").exists()


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["degrade", "x.png", "--psf-grid", "g.exr", "-o", "d.exr", "--boundary", "nope"],
            "solas-mi degrade: error: argument --boundary: invalid choice: 'nope'",
        ),
        (["nope"], "solas-mi: error: argument COMMAND: invalid choice: 'nope'"),
        (["lens"], "solas-mi lens: error: the following arguments are required: COMMAND"),
    ],
)
def test_usage_errors_are_one_line(capsys, argv, message):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.startswith(message) and err.count("\n") == 1, err
    assert err.rstrip().endswith("--help)")


def test_no_measurement_says_so_on_stderr(tmp_path, capsys):
    """An image without a usable edge: exit status 1 and a line on stderr, even when stdout is JSON."""
    PHOTO_SMALL.save(tmp_path / "flat.png")
    assert main(["sfr", str(tmp_path / "flat.png"), "--json"]) == 1
    out, err = capsys.readouterr()
    assert strict_loads(out)["results"] == [] and "no valid edge measured" in err


def test_a_library_warning_is_one_line(monkeypatch, capsys):
    """A warning a stage raises with `warnings.warn` (the lens camera's dark corners, the exit-pupil
    bounds) reads as the command's own warnings do; Python's format added the file, line and source
    line that raised it ("lens_sensor.py:91: UserWarning: ...", then "  heights, radial, ... = ...")."""
    import warnings

    from solas_mi.sensor import commands

    def warns(args):
        warnings.warn("the film reaches past the lens's field", stacklevel=2)
        return 0

    monkeypatch.setattr(commands, "run_sensors", warns)
    assert main(["sensors"]) == 0
    assert capsys.readouterr().err.splitlines() == ["solas-mi sensors: warning: the film reaches past the lens's field"]


def test_a_command_builds_the_parser_of_its_stage_only_and_the_same_help():
    """`build_parser(command)` stops at the stage that registers the command (and that extends it): each command's
    every sub-command has the help it has in the whole parser, and `psf-grid` imports no later stage's commands."""
    import subprocess
    import sys

    from solas_mi.cli import build_parser, iter_commands

    full = {path: p.format_help() for path, p in iter_commands(build_parser()) if path}
    for name in {path[0] for path in full}:
        own = {path: p.format_help() for path, p in iter_commands(build_parser(name)) if path and path[0] == name}
        assert own == {path: text for path, text in full.items() if path[0] == name}, name
    code = (
        "import sys; from solas_mi.cli import AREAS, build_parser; build_parser('psf-grid'); "
        "print(','.join(a for a in AREAS if f'solas_mi.{a}.commands' in sys.modules))"
    )
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "optics,psf"
