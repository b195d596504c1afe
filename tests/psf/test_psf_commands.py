"""`solas-mi psf` and `solas-mi psf-grid` (psf.commands)."""

import pytest

from solas_mi.cli import main
from solas_mi.psf.grid import PSFGrid


def test_cli_psf_and_grid(tmp_path, capsys):
    out = tmp_path / "psf.exr"
    assert (
        main(
            [
                "psf",
                "solas-doublet",
                "--field-deg",
                "0,2",
                "--wavelengths-nm",
                "531",
                "--size",
                "32",
                "--pitch-um",
                "1",
                "--normalize",
                "peak",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    from solas_mi.imageio import read_exr

    ch, meta = read_exr(out)
    assert ch["Y"].max() == pytest.approx(1.0) and meta["field_deg"] == [0.0, 2.0]
    assert meta["chief_ray_origin_mm"][1] == pytest.approx(3.4745, abs=1e-3)
    assert (tmp_path / "psf.png").is_file()
    grid = tmp_path / "grid.exr"
    assert (
        main(
            [
                "psf-grid",
                "solas-doublet",
                "--grid",
                "2x2",
                "--wavelengths-nm",
                "531",
                "--size",
                "24",
                "--pupil-samples",
                "32",
                "-o",
                str(grid),
            ]
        )
        == 0
    )
    assert PSFGrid.read(str(grid)).data.shape == (1, 2, 2, 24, 24)


def test_cli_bad_input_is_one_clear_line(tmp_path, capsys):
    assert (
        main(["psf", "solas-doublet", "--field-deg", "0,2", "--wavelengths-nm", "100", "-o", str(tmp_path / "x.exr")])
        == 2
    )
    err = capsys.readouterr().err
    assert "wavelength 100 nm is outside glass" in err
    assert not any(tmp_path.iterdir())
