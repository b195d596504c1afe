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


def brute_force_transmission(lens, field_deg: float, wavelength_nm: float, rays: int = 600) -> float:
    """Power that reaches the image: a dense regular grid over the entrance window of the field's whole
    stop (about the paraxial entrance pupil, not about any chief ray), traced one by one."""
    from solas_mi.optics import pupil as P
    from solas_mi.optics import tracer as T

    f, w = np.array([[0.0, field_deg]]), np.array([wavelength_nm])
    chief = P.chief_rays(lens, f, w)
    ex, ey, _, _ = P.stop_rim(P.Bundle(lens, f, w, P.RIM_RAYS), chief)
    lo, hi = np.array([ex.min(), ey.min()]) - 0.5, np.array([ex.max(), ey.max()]) + 0.5
    u = (np.arange(rays) + 0.5) / rays
    gx, gy = np.meshgrid(lo[0] + (hi[0] - lo[0]) * u, lo[1] + (hi[1] - lo[1]) * u)
    power = P.entrance_power(lens, f, w, gx[None], gy[None]).ravel() * np.prod(hi - lo) / rays**2
    tr = P.Bundle(lens, f, w, rays * rays).trace(T.F(gx.ravel()), T.F(gy.ravel()))
    (keep,) = T.to_numpy(tr.ok & (tr.clipped_by == 0))
    return float(power[keep].sum())


@pytest.mark.parametrize("method", ["geometric", "fraunhofer", "render"])
def test_a_totally_reflected_chief_ray_still_gives_the_light_that_arrives(cooke, method):
    """At 32° the Cooke triplet's chief ray is totally reflected and 7.9 % of the beam arrives. Every
    method was refused; then the Fraunhofer method gave 0.015 (its pupil built about a substitute ray,
    unchecked) and the render method refused ("every ray is blocked": the light lands 31 mm off axis,
    outside the scene's 30 mm barrel). Each now gives the PSF of the light that arrives, centred on it."""
    brute = brute_force_transmission(cooke, 32.0, 587.56)
    assert 0.07 < brute < 0.09
    p = psf(cooke, (0, 32.0), 587.56, method=method, size=128, pitch_um=10.0, normalization="none")
    assert p.meta["transmission"] == pytest.approx(brute, rel=0.02)
    assert p.data.sum() * 100.0 > 0.95 * p.meta["transmission"]  # the window, centred on the light, holds it


def test_the_power_peak_test_counts_cells_as_the_median_would_decide():
    """`power_peaks` decides "peak > FOLD_POWER × median" by counting cells below the bound: on pupils built
    to sit at every edge of that rule (odd and even counts, an even count split exactly at the bound, ties,
    zeros, no full cell, one cell) it agrees with the median taken directly."""
    from solas_mi.psf.fraunhofer import FOLD_POWER, power_peaks

    rng = np.random.default_rng(7)
    power, full = rng.exponential(1.0, (400, 6, 6)), rng.random((400, 6, 6)) < 0.6
    full[0], full[1] = False, False  # no full cell
    full[1, 2, 3] = True  # one cell
    power[2:50] = np.round(power[2:50] * 4) / 4  # ties at the bound
    power[50:60] = 0.0  # all zero
    power[::2, 0, 0] *= 30.0  # half the pupils with a peak near the bound
    for i in range(60, 400):  # an even count split so that the mean of the two middle cells meets the bound
        cells = np.sort(power[i][full[i]])
        if len(cells) >= 2 and len(cells) % 2 == 0:
            k = len(cells) // 2
            peak = np.where(full[i], power[i], 0.0).max()
            bound = peak / FOLD_POWER  # the two middle cells astride it, their mean below, at or above it
            lower, upper = full[i] & (power[i] == cells[k - 1]), full[i] & (power[i] == cells[k])
            if cells[k] < peak:
                power[i][lower], power[i][upper] = bound * 0.5, bound * rng.choice([1.4, 1.5, 1.6])
    direct = np.array(
        [
            np.where(m, p, 0.0).max() > FOLD_POWER * max(np.median(p[m]) if m.any() else 0.0, 1e-300)
            for p, m in zip(power, full)
        ]
    )
    assert direct.any() and not direct.all()
    assert (power_peaks(power, full) == direct).all()
