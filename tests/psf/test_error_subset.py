"""The sampling-error estimate of a batch of PSFs (`fraunhofer.sampling_errors`) first estimates the PSFs
where errors gather (every 16th, the steepest wavefronts, the vignetted), and every PSF only where one of
those comes near the limit: a grid's warnings are those of estimating every PSF, at a fraction of its cost
where nothing comes near."""

import numpy as np

from solas_mi.optics import pupil as P
from solas_mi.psf import fraunhofer as F
from solas_mi.psf import psf_grid


def estimated(monkeypatch, samples: int) -> list[int]:
    """The number of PSFs each pass of the error estimate (pupils of `coarse_samples(samples)`) estimates,
    recorded as a grid runs."""
    passes = []
    sampled = P.Pupils.sampled

    def record(self, n, index=None):
        if n == F.coarse_samples(samples):
            passes.append(len(self.field_deg) if index is None else len(index))
        return sampled(self, n, index)

    monkeypatch.setattr(P.Pupils, "sampled", record)
    return passes


def test_a_grid_near_the_limit_is_estimated_whole_and_warned_as_before(doublet, monkeypatch):
    """The doublet's 32x32 grid at one wavelength on 48² pupils: 136 distinct PSFs, of which the first
    pass estimates 17; they come near the limit, so the other 119 are estimated too, and the warnings are
    those of estimating every PSF at once."""
    options = dict(grid=(32, 32), wavelengths_nm=[531.0], pupil_samples=48, size=32, pitch_um=1.0)
    passes = estimated(monkeypatch, 48)
    grid = psf_grid(doublet, **options)
    assert passes == [17, 119]
    monkeypatch.setattr(F, "PROBE_STRIDE", 1)  # every PSF in the first pass
    assert psf_grid(doublet, **options).meta["warnings"] == grid.meta["warnings"]
    assert any("off its converged value" in w for w in grid.meta["warnings"])


def test_a_converged_grid_estimates_a_few(doublet, monkeypatch):
    """On its 128² pupils the doublet at f/8 converges everywhere (every PSF's estimate below PROBE_WIDEN of
    the limit): of the 136 distinct PSFs of a 32x32 grid at one wavelength the first pass estimates one in
    eight, and no more."""
    options = dict(grid=(32, 32), wavelengths_nm=[531.0], size=32, pitch_um=1.0)
    passes = estimated(monkeypatch, 128)
    grid = psf_grid(doublet, **options)
    assert sum(passes) <= 136 // 8 and not [w for w in grid.meta["warnings"] if "converged" in w]
    errors, estimate = [], F.error_estimate
    monkeypatch.setattr(F, "PROBE_STRIDE", 1)
    monkeypatch.setattr(F, "error_estimate", lambda *a: errors.append(estimate(*a)) or errors[-1])
    psf_grid(doublet, **options)
    assert np.max(np.concatenate(errors)) < F.PROBE_WIDEN * F.ERROR_LIMIT  # the first pass was right


def test_the_estimate_s_coarser_pupils_are_aimed_from_the_psfs_own_rays(doublet, monkeypatch):
    """The error estimate's coarser pupils (85² of the PSFs' 128²) start from the PSFs' solved rays, one
    level of Newton steps on the 85² grid alone (the coarser levels 6² and 22² of an aim from the stop rim
    left out), and are the pupils that aim gives: every ray converges to the same tolerance."""
    fields = np.array([[0.0, 0.0], [1.0, 0.5], [2.0, 2.0], [0.3, 1.9]])
    waves = np.array([486.0, 531.0, 656.0, 531.0])
    coarse, index = F.coarse_samples(128), np.array([1, 3])
    cold = P.Pupils(doublet, fields, waves).sampled(coarse, index)
    pupils = P.Pupils(doublet, fields, waves)
    pupils.sampled(128)
    traced = []
    trace = P.Bundle.trace

    def record(self, ex, ey, heights=None, rays=None):
        traced.append(self.per_field)
        return trace(self, ex, ey, heights, rays)

    monkeypatch.setattr(P.Bundle, "trace", record)
    warm = pupils.sampled(coarse, index)
    assert set(traced) == {coarse * coarse}
    np.testing.assert_allclose(warm.opd_mm, cold.opd_mm, rtol=0, atol=1e-12)
    np.testing.assert_allclose(warm.power, cold.power, rtol=1e-8, atol=1e-8 * cold.power.max())
    np.testing.assert_allclose(warm.coverage, cold.coverage, rtol=0, atol=1e-8)
