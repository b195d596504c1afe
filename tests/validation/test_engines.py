"""The two engines in the cross-validation's settings agree (`solas_mi.validation.engines`)."""

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.validation.engines import Case, convolve, psf_grid_for, render


def test_a_bad_case_is_a_solas_error():
    with pytest.raises(SolasError, match="METHOD:PSF"):
        Case.parse("blur:geometric:32x24")
    with pytest.raises(SolasError, match="32x24"):
        Case.parse("interp:geometric:32")
    assert Case.parse("patch:fraunhofer:8x6") == Case("patch", "fraunhofer", (8, 6))


def test_uniform_white_radiometry_agrees(doublet):
    """A white object: the render's relative illumination (0.986 at the edge middle, 0.978 at the
    corner, of the on-axis irradiance, which is ≈ 1.01 ideal-camera units) is what interp gives with
    cos³θ, "none" kernels and the unit factor k."""
    from solas_mi.optics.camera import pinhole_focal_mm
    from solas_mi.optics.illumination import axis_irradiance, ideal_irradiance

    w, h = 160, 120
    white = np.ones((h, w, 3))
    grid, _ = psf_grid_for(doublet, "geometric", (16, 12), w, h, 2.0)
    conv, _ = convolve(white, grid, "interp", doublet, 2.0)
    ref = render(doublet, white, 48, 3, 2.0).image.astype(np.float64)
    axis = axis_irradiance(doublet, 531.0) / ideal_irradiance(doublet, pinhole_focal_mm(doublet, 2.0))
    centre = ref[h // 2 - 2 : h // 2 + 2, w // 2 - 2 : w // 2 + 2, 1].mean()
    assert centre == pytest.approx(axis, abs=2e-3)
    assert ref[h // 2 - 2 : h // 2 + 2, :3, 1].mean() / centre == pytest.approx(0.986, abs=3e-3)
    assert ref[:3, :3, 1].mean() / centre == pytest.approx(0.978, abs=3e-3)
    ratio = conv / ref
    # inside the outermost nodes (the 16×12 grid's nodes are 10 px apart, the outer ones 5 px from the border)
    for region in (
        np.s_[h // 2 - 4 : h // 2 + 4, w // 2 - 4 : w // 2 + 4],
        np.s_[h // 2 - 4 : h // 2 + 4, 6:10],
        np.s_[6:10, 6:10],
        np.s_[6:10, w // 2 - 4 : w // 2 + 4],
        np.s_[:, :],
    ):
        assert ratio[region].mean() == pytest.approx(1.0, abs=3e-3)
    # beyond them interp holds the outermost chief-ray offsets (no distortion there): ~1-2 % too bright
    assert 1.0 < ratio[:2, :2].mean() < 1.03
