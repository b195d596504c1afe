"""`psf()` through the method registry: energy, symmetry, wave vs ray optics, polychromatic PSFs, normalisation, bad arguments."""

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.optics import pupil as P
from solas_mi.psf import psf
from solas_mi.psf.geometric import geometric


def test_energy_matches_geometric_transmission(doublet):
    """The pupil's transmitted power equals the power of real rays through the entrance pupil."""
    fields = np.array([[0.0, 0.0], [0.0, 2.0]])
    pf = P.pupil_function(doublet, fields, [531.0, 531.0], 128)
    geo, _, transmission = geometric(doublet, fields, np.array([531.0, 531.0]), 1.0, 200, rays=400)
    assert transmission == pytest.approx(pf.transmission, rel=2e-3)
    assert geo.sum(axis=(1, 2)) == pytest.approx(transmission, rel=1e-12)  # the 200 µm grid holds every ray
    small = psf(doublet, (0, 0), 531.0, method="geometric", size=16, pitch_um=1.0)
    assert small.meta["transmission"] == pytest.approx(pf.transmission[0], rel=2e-3)
    # the 16 µm square catches about its area over that of the 58 µm defocus disc: 256 / (π 29²) ≈ 0.1
    assert 0.07 < small.meta["energy_in_grid"] < 0.13
    assert pf.transmission[0] == pytest.approx(1.0, abs=2e-3)


def test_field_symmetry(doublet):
    up = psf(doublet, (0, 2), 486.0, size=161).data
    down = psf(doublet, (0, -2), 486.0, size=161).data
    right = psf(doublet, (2, 0), 486.0, size=161).data
    peak = up.max()
    assert np.sqrt(np.mean((up - down[::-1, :]) ** 2)) < 1e-6 * peak
    assert np.sqrt(np.mean((up - up[:, ::-1]) ** 2)) < 1e-6 * peak
    assert np.sqrt(np.mean((np.rot90(up, -1) - right) ** 2)) < 1e-6 * peak


def test_fraunhofer_centroid_matches_geometric(doublet):
    """Coma moves the centroid off the chief ray; wave and ray optics agree where it lands."""
    kw = dict(pitch_um=1.0, size=241)
    wave = psf(doublet, (0, 2), 531.0, **kw)
    ray = psf(doublet, (0, 2), 531.0, method="geometric", rays=600, **kw)
    cy = [float((p.data.sum(axis=1) * p.y_um).sum()) for p in (wave, ray)]
    assert cy[0] > 2.0  # +y: the comatic flare points away from the axis
    assert cy[0] == pytest.approx(cy[1], abs=0.1)
    cx = float((wave.data.sum(axis=0) * wave.x_um).sum())
    assert abs(cx) < 1e-3


def test_polychromatic_keeps_lateral_colour(doublet):
    blue = psf(doublet, (0, 2), 486.0, method="geometric", pitch_um=1.0, size=101)
    red_on_blue = psf(doublet, (0, 2), [486.0, 656.0], weights=[0.0, 1.0], method="geometric", pitch_um=1.0, size=101)
    red = psf(doublet, (0, 2), 656.0, method="geometric", pitch_um=1.0, size=101)
    shift_um = (red.chief_ray_mm[1] - blue.chief_ray_mm[1]) * 1e3
    assert -5 < shift_um < -1  # lateral colour of a few µm
    c = lambda p: float((p.data.sum(axis=1) * p.y_um).sum())  # noqa: E731
    assert c(red_on_blue) == pytest.approx(c(red) + shift_um, abs=0.05)


def test_normalizations(doublet):
    s = psf(doublet, (0, 0), 531.0, size=64)
    p = psf(doublet, (0, 0), 531.0, size=64, normalization="peak")
    n = psf(doublet, (0, 0), 531.0, size=64, normalization="none")
    assert s.data.sum() == pytest.approx(1.0)
    assert p.data.max() == pytest.approx(1.0)
    assert n.data / n.data.sum() == pytest.approx(s.data, rel=1e-9, abs=1e-15)
    assert s.meta["lens_hash"] == doublet.hash and s.meta["origin_pixel"] == [32, 32]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(pitch_um=0.0), "pitch 0.0 µm must be a positive number"),
        (dict(size=1), "size 1 must be an integer from 2"),
        (dict(method="huygens"), "method 'huygens' must be one of fraunhofer, geometric"),
        (dict(normalization="max"), "normalization 'max' must be one of sum, peak, none"),
        (dict(pupil_samples=4), "pupil samples 4 must be an integer from 8 to 4096"),
        (dict(pupil_samples=100000), "pupil samples 100000 must be an integer from 8 to 4096"),
        (dict(method="geometric", rays=1), "rays 1 must be an integer from 2 to 4096"),
    ],
)
def test_bad_psf_arguments(doublet, kwargs, match):
    with pytest.raises(SolasError, match=match):
        psf(doublet, (0, 0), 531.0, **kwargs)


def test_triplet_with_inner_stop(triplet):
    """A lens with its stop between elements and a ±20° field: wave and ray optics agree on the
    transmitted power and on where the light lands, at every field."""
    fields = np.array([[0.0, 0.0], [0.0, 10.0], [0.0, 20.0]])
    pf = P.pupil_function(triplet, fields, [587.56] * 3, 128)
    _, _, transmission = geometric(triplet, fields, np.full(3, 587.56), 2.0, 50, rays=400)
    assert transmission == pytest.approx(pf.transmission, rel=1e-3)
    for fy in (10.0, 20.0):
        kw = dict(pitch_um=1.0, size=241)
        wave = psf(triplet, (0, fy), 587.56, **kw)
        ray = psf(triplet, (0, fy), 587.56, method="geometric", rays=600, **kw)
        cy = [float((p.data.sum(axis=1) * p.y_um).sum()) for p in (wave, ray)]
        assert abs(cy[0]) > 1.0 and cy[0] == pytest.approx(cy[1], abs=0.1)
