"""Near a pupil caustic (rays close to total internal reflection) the Fraunhofer method's pupil
function folds and its integral is wrong: the Cooke triplet at 31° and 31.5° gave transmissions of
1.09 and 2.18 where a ray count gives 0.393 and 0.263. Such fields fall back to the geometric PSF,
with a warning saying so."""
import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.psf import psf

KW = dict(size=64, pitch_um=4.0, normalization="none")


@pytest.fixture(scope="module")
def cooke():
    return Lens.load("cooke-triplet")


@pytest.mark.parametrize("field", [31.0, 31.5])
def test_a_folded_pupil_falls_back_to_the_geometric_psf(cooke, field):
    f = psf(cooke, (0, field), 587.56, pupil_samples=128, **KW)
    g = psf(cooke, (0, field), 587.56, method="geometric", rays=512, **KW)
    assert f.meta["transmission"] == pytest.approx(g.meta["transmission"], rel=0.01)
    assert np.abs(f.data - g.data).max() < 0.02 * g.data.max()
    text = " ".join(f.meta["warnings"])
    assert "folds over a caustic" in text and "geometric" in text
    assert "under-resolve" not in text and "converged value" not in text  # no advice that diverges


def test_an_unfolded_pupil_keeps_the_fraunhofer_psf(cooke):
    f = psf(cooke, (0, 30.0), 587.56, pupil_samples=128, **KW)
    assert "caustic" not in " ".join(f.meta["warnings"])
    assert f.meta["transmission"] == pytest.approx(0.568, abs=0.005)  # the ray count's
