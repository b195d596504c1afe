"""What a PSF's window holds, and sampling that cannot carry the wavefront: recorded in every PSF's
and grid's metadata, warned about, and (on request) the window enlarged until it holds the light."""

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.psf import psf, psf_grid
from solas_mi.psf.base import WINDOW_ENERGY_LIMIT


def test_a_window_too_small_is_warned_about_and_can_grow(doublet):
    small = psf(doublet, (0, 0), 656.0, size=40)  # ±10 µm of a ~25 µm defocus blur
    assert small.meta["energy_in_grid"] < 0.6 and small.data.sum() == pytest.approx(1.0)
    assert "holds only" in small.meta["warnings"][0] and "--auto-window" in small.meta["warnings"][0]
    grown = psf(doublet, (0, 0), 656.0, size=40, auto_window=True)
    assert grown.size == 160 and grown.meta["energy_in_grid"] >= WINDOW_ENERGY_LIMIT
    assert grown.meta["warnings"] == []


def test_the_default_sampling_raises_no_alarm(doublet):
    for field in ((0, 0), (0, 2)):
        for wavelength in (486.0, 531.0, 656.0):
            assert psf(doublet, field, wavelength).meta["warnings"] == []


def test_an_under_sampled_pupil_is_detected(doublet):
    """16 pupil samples on axis at 486 nm: phase steps above π per cell and a PSF period (51 µm) shorter
    than the 80 µm window, so copies of the PSF fold in: the window 'holds' more than the light."""
    p = psf(doublet, (0, 2), 486.0, pupil_samples=16, normalization="none")
    text = " ".join(p.meta["warnings"])
    assert "copies of the PSF fold in" in text and "aliasing" in text and p.meta["energy_in_grid"] > 1.06
    assert "--pupil-samples 32 or more" in text
    assert psf(doublet, (0, 2), 486.0, pupil_samples=32).meta["warnings"] == []


def test_grids_record_the_energy_of_every_window(doublet):
    g = psf_grid(doublet, grid=(2, 3), wavelengths_nm=[531.0, 656.0], size=40, pupil_samples=48)
    energy = np.array(g.meta["energy_in_window"])
    assert energy.shape == (2, 2, 3)  # wavelengths, rows, columns
    one = psf(doublet, tuple(g.fields_deg[0, 1]), 656.0, size=40, pupil_samples=48)
    assert energy[1, 0, 1] == pytest.approx(one.meta["energy_in_grid"], rel=1e-6)
    assert any("holds only" in w for w in g.meta["warnings"])


def test_warnings_go_to_stderr_once(tmp_path, capsys):
    assert (
        main(
            [
                "psf",
                "solas-doublet",
                "--field-deg",
                "0,0",
                "--wavelengths-nm",
                "656",
                "--size",
                "40",
                "-o",
                str(tmp_path / "p.exr"),
            ]
        )
        == 0
    )
    out, err = capsys.readouterr()
    assert err.count("solas-mi psf: warning: the 40x40 window") == 1 and "solas-mi psf: warning" not in out
