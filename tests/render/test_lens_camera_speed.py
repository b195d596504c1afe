"""What `lens_camera` does to stay cheap per sample, checked against what it replaces: the wavelengths
from the response's quantile table (`WavelengthSampler.sample_quantile`) against the response's bins,
and the rays the lens blocks, which leave with no length (no scene path traced for a weight 0)."""

import numpy as np

from solas_mi.render.response import parse

N = 1 << 16


def _sampler(mi, name="srgb"):
    from solas_mi.plugins.wavelength_sampling import WavelengthSampler

    return WavelengthSampler(parse(name, [486.1, 587.6, 656.3]))


def test_quantile_wavelengths_follow_the_response_and_weigh_by_their_own_density(mi):
    """Stratified samples: the wavelengths rise with the sample inside the response's range; each 1-nm
    bin receives its probability within 2/QUANTILES (the intervals that straddle a bin edge); and the
    weights 1/p(λ) integrate both 1 (the range, 400 nm) and the response's own density (1) exactly,
    as the estimate of a render's ∫ f(λ) dλ must."""
    from solas_mi.plugins.wavelength_sampling import QUANTILES

    sampler = _sampler(mi)
    r = parse("srgb", [486.1, 587.6, 656.3])
    u = (np.arange(N) + 0.5) / N
    lam, inverse_pdf = (np.array(v, dtype=np.float64) for v in sampler.sample_quantile(mi.Float(u)))
    assert np.all(np.diff(lam) >= 0) and lam.min() >= r.lo_nm.min() and lam.max() <= r.hi_nm.max()
    assert abs(inverse_pdf.mean() - (r.hi_nm.max() - r.lo_nm.min())) < 1e-3
    bins = np.clip(np.searchsorted(r.lo_nm, lam, side="right") - 1, 0, len(r.lo_nm) - 1)
    density = r.probability / (r.hi_nm - r.lo_nm)
    assert abs(np.mean(density[bins] * inverse_pdf) - 1.0) < 1e-4
    share = np.bincount(bins, minlength=len(r.lo_nm)) / N
    assert np.max(np.abs(share - r.probability)) <= 2.0 / QUANTILES
    quarters = np.array(sampler.sample_quantile(mi.Float(np.array([0.25, 0.5, 0.75]))))[0]
    assert np.allclose(quarters, r.sample(np.array([0.25, 0.5, 0.75]))[0], atol=1e-3)  # the lanes' quarters


def test_lines_keep_the_bins(mi):
    """A response with lines has no density: `sample_quantile` is `sample` and `weight`."""
    sampler = _sampler(mi, "lines")
    u = mi.Float((np.arange(64) + 0.5) / 64)
    lam, inverse_pdf = sampler.sample_quantile(u)
    lam_bins, index = sampler.sample(u)
    assert np.array_equal(np.array(lam), np.array(lam_bins))
    assert np.array_equal(np.array(inverse_pdf), np.array(sampler.weight(index)))


def test_blocked_rays_leave_with_no_length(mi):
    """Past the doublet's image circle (a film 4× the field) the lens blocks many rays: exactly those of
    weight 0 in every lane leave with maxt 0 (the scene traces nothing for them), the rest with
    Mitsuba's default (the largest float)."""
    film = {"type": "hdrfilm", "width": 64, "height": 48, "rfilter": {"type": "box"}}
    sensor = mi.load_dict({"type": "lens_camera", "pitch_um": 400.0, "response": "srgb", "film": film})
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(3, 64 * 48 * 4)
    ray, weight = sensor.sample_ray(0.0, sampler.next_1d(), sampler.next_2d(), sampler.next_2d())
    blocked = np.all(np.array(weight) == 0, axis=0)
    maxt = np.array(ray.maxt)
    assert 0.05 < blocked.mean() < 0.95
    assert np.array_equal(maxt == 0, blocked) and np.all(maxt[~blocked] == np.finfo(np.float32).max)
