"""The command line as a whole (`cli`): composition of the stages' commands, --version, and user
errors as one line naming the bad value."""
import pytest

from solas_mi import __version__
from solas_mi.cli import main


def test_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.strip() == f"solas-mi {__version__}"


@pytest.mark.parametrize("argv, message", [
    (["psf", "solas-doublet", "--field-deg", "0,2", "--wavelength-nm", "", "-o", "{tmp}/x.exr"],
     "at least one wavelength (nm) is needed"),
    (["psf", "solas-doublet", "--field-deg", "0,89", "--wavelength-nm", "531", "-o", "{tmp}/x.exr"],
     "field (0, 89) deg: each angle must be finite and below 89 deg in magnitude"),
    (["psf", "solas-doublet", "--field-deg", "0,1", "--wavelength-nm", "2500.0001", "-o", "{tmp}/x.exr"],
     "wavelength 2500.0001 nm is outside glass SCHOTT:N-BK7's valid range 300-2500 nm"),
    (["sfr", "{tmp}"], "is a folder, not an image file"),
    (["sfr", "{tmp}/garbage.png"], "cannot read image"),
])
def test_user_errors_are_one_line(tmp_path, capsys, argv, message):
    (tmp_path / "garbage.png").write_text("not a png")
    assert main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "pip install" not in err
    assert not (tmp_path / "x.exr").exists()
