"""Bad input at the optics boundary: a SolasError naming the value and what is allowed (one line,
exit 2, on the command line), never a TypeError or a misleading message."""

import math

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.errors import SolasError
from solas_mi.optics.focus import focused
from solas_mi.optics.lens import Lens, shipped_lenses
from solas_mi.optics.paraxial import paraxial
from solas_mi.resources import resource_dir


def test_shipped_lenses_are_the_shipped_folder():
    names = shipped_lenses()
    assert names == sorted(p.stem.replace("_", "-") for p in (resource_dir("scenes") / "lenses").glob("*.toml"))
    assert "solas-doublet" in names


@pytest.mark.parametrize("value", [None, 5, [], 1.5, {"lens": "solas-doublet"}, b"solas-doublet"])
def test_a_lens_is_a_name_or_a_path(value):
    with pytest.raises(
        SolasError,
        match=r"must be a shipped lens name \(.*solas-doublet.*\) or a path to a lens file "
        r"\(\.toml, \.zmx, \.seq, \.dat\)",
    ) as err:
        Lens.load(value)
    assert repr(value) in str(err.value)


@pytest.mark.parametrize(
    "given, message",
    [
        ("/etc/passwd", "lens file '/etc/passwd' has no lens extension; allowed: .toml, .zmx, .seq, .dat"),
        ("{tmp}/lens.txt", "has unknown extension '.txt'; allowed: .toml, .zmx, .seq, .dat"),
        ("{tmp}/folder.toml", "is a folder, not a lens file"),
        ("{tmp}/missing.zmx", "missing.zmx' does not exist"),
        ("sub/solas-doublet", "has no lens extension"),  # a path, even one that ends in a shipped name
    ],
)
def test_a_name_with_a_separator_is_a_path(tmp_path, given, message):
    (tmp_path / "lens.txt").write_text("[lens]\n")
    (tmp_path / "folder.toml").mkdir()
    with pytest.raises(SolasError) as err:
        Lens.load(given.replace("{tmp}", str(tmp_path)))
    assert message in str(err.value)


def test_an_unknown_name_lists_every_shipped_lens():
    with pytest.raises(SolasError) as err:
        Lens.load("no-such-lens")
    assert f"shipped lenses: {', '.join(shipped_lenses())}," in str(err.value)


@pytest.mark.parametrize("wavelength", ["531", math.nan, -531.0, 0, True, math.inf, [531.0]])
def test_paraxial_refuses_odd_wavelengths(doublet, wavelength):
    with pytest.raises(SolasError, match=r"wavelength .* nm must be a positive number"):
        paraxial(doublet, wavelength)


@pytest.mark.parametrize("fields", ["0,1", [math.nan], [True], 5, [0.0, 180.0], [None]])
def test_paraxial_refuses_odd_fields(doublet, fields):
    with pytest.raises(SolasError, match="must be a list of y field angles in degrees"):
        paraxial(doublet, 531.0, fields)


def test_paraxial_takes_numpy_values(doublet):
    assert paraxial(doublet, np.float32(531.0)) == paraxial(doublet, 531.0)
    assert paraxial(doublet, 531.0, np.array([0.0, 2.0])) == paraxial(doublet, 531.0, [0.0, 2.0])


@pytest.mark.parametrize("lens", [None, "solas-doublet"])
def test_analyses_take_a_lens(lens):
    with pytest.raises(SolasError, match=r"must be a Lens: Lens.load"):
        paraxial(lens)
    with pytest.raises(SolasError, match=r"must be a Lens: Lens.load"):
        focused(lens, 1e4)


@pytest.mark.parametrize("distance", ["20000", None, math.nan, -1e4, 0, True])
def test_focused_refuses_odd_distances(doublet, distance):
    with pytest.raises(SolasError, match=r"focus distance .* mm must be a positive number"):
        focused(doublet, distance)


def test_focused_takes_numpy_distances(doublet):
    assert focused(doublet, np.int64(20000)) == focused(doublet, 20000.0)


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["lens", "info", "/etc/passwd"],
            "lens file '/etc/passwd' has no lens extension; allowed: .toml, .zmx, .seq, .dat",
        ),
        (["lens", "info", "no-such-lens"], "shipped lenses: cooke-triplet, "),
        (["lens", "info", "{tmp}/folder.toml"], "is a folder, not a lens file"),
        (["lens", "info", "solas-doublet", "--fields", "0,nan"], "must be a list of y field angles in degrees"),
        (["lens", "info", "solas-doublet", "--wavelengths", "-5"], "wavelength -5.0 nm must be a positive number"),
        (["lens", "convert", "/etc/passwd", "-o", "{tmp}/x.toml"], "has no lens extension"),
        (["lens", "convert", "solas-doublet", "-o", "{tmp}/x.txt"], "unknown extension '.txt'"),
    ],
)
def test_cli_lens_errors_are_one_line(tmp_path, capsys, argv, message):
    (tmp_path / "folder.toml").mkdir()
    assert main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize(
    "old, new, message",
    [
        (
            "thickness = 39.496",
            "thickness = 1e30",
            r"surface 4 \(Aperture stop\): thickness 1e\+30 mm must lie within ±1e\+15",
        ),
        (
            "thickness = 39.496",
            "thickness = 1e300",
            r"surface 4 \(Aperture stop\): thickness 1e\+300 mm must lie within",
        ),
        ("thickness = 6.0", "thickness = -1e300", r"surface 1 \(Surface 1\): thickness -1e\+300 mm must lie within"),
        ('distance = "infinity"', "distance = 1e300", r"object distance 1e\+300 mm must lie within ±1e\+15 mm, or be "),
        (
            "diameter = 5.0",
            "diameter = 1e300",
            r"surface 4 \(Aperture stop\): diameter 1e\+300 mm must be positive and at "
            r"most 1e\+15 mm",
        ),
    ],
)
def test_lengths_beyond_any_lens_are_refused_by_name(tmp_path, capsys, old, new, message):
    """An image 1e30 mm behind the stop rendered black (the lens camera NaN), DISZ 1e300 gave lens info a
    TypeError, an object 1e300 mm away an OverflowError: a lens file's lengths are refused past 1e15 mm (an
    object farther is at infinity to every digit), in one line naming the value."""
    text = (resource_dir("scenes") / "lenses" / "solas_doublet.toml").read_text()
    assert text.count(old) == 1
    path = tmp_path / "far.toml"
    path.write_text(text.replace(old, new))
    with pytest.raises(SolasError, match=message):
        Lens.load(path)
    assert main(["lens", "info", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err


def test_a_zemax_image_distance_of_1e300_is_refused_by_name(tmp_path, capsys):
    """The same through a .zmx with fields, where lens info ended in a TypeError."""
    from test_zemax_files import BFD, zmx

    path = tmp_path / "far.zmx"
    text = zmx()
    assert text.count(f"DISZ {BFD!r}") == 1
    path.write_text(text.replace(f"DISZ {BFD!r}", "DISZ 1e300"))
    assert main(["lens", "info", str(path)]) == 2
    assert "thickness 1e+300 mm must lie within ±1e+15 mm" in capsys.readouterr().err


@pytest.mark.parametrize(
    "key, text", [("name", "evil\x1b[31mRED"), ("description", "a\x1b]0;title\x07"), ("name", "two\nlines")]
)
def test_a_lens_text_that_would_drive_the_terminal_is_refused(tmp_path, key, text):
    """`lens info` prints a lens's name and description: an escape sequence there would drive the terminal."""
    path = tmp_path / "lens.toml"
    source = (resource_dir("scenes") / "lenses" / "solas_doublet.toml").read_text()
    lines = [
        f"{key} = {text!r}".replace("'", '"').replace("\\x", "\\u00") if line.startswith(f"{key} =") else line
        for line in source.splitlines()
    ]
    path.write_text("\n".join(lines))
    with pytest.raises(SolasError, match=f"the {key} .* holds control characters; it must be printable text"):
        Lens.load(path)


def test_control_characters_of_a_codev_title_become_spaces(tmp_path):
    """CODE V files from Windows hold CP1252 quotes, which read as C1 control codes (the Zemax reader makes
    them spaces too): the title loads, its control characters spaces."""
    path = tmp_path / "lens.seq"
    path.write_bytes(
        b"LEN\nTIT '\x93quoted\x94 lens'\nDIM M\nWL 587.6\nEPD 10\nYAN 0\nSO 0 1e10\nS 50 5 BK7_SCHOTT\n"
        b"STO\nS -50 45\nSI 0 0\nGO\n"
    )
    lens = Lens.load(path)
    assert lens.name == "quoted  lens"
