"""The shared fixtures of tests/conftest.py: the Mitsuba variant fixtures set a variant with solas-mi's
plugins and give the variant before back; the synthetic grids are what their parameters say."""

import math

import numpy as np
import pytest

from solas_mi.render.mitsuba import mitsuba

START = {}


def test_a_variant_fixture_sets_its_variant_with_the_plugins(variant_scalar_spectral):
    mi = variant_scalar_spectral
    assert mi.variant() == "scalar_spectral"
    assert isinstance(mi.load_dict({"type": "sellmeier_dielectric"}), mi.BSDF)


def test_in_variant_gives_the_variant_before_back(in_variant):
    mitsuba("llvm_ad_spectral")
    with in_variant("scalar_spectral") as mi:
        assert mi.variant() == "scalar_spectral"
        assert type(mi.load_dict({"type": "sellmeier_dielectric"})).__name__ == "SellmeierDielectric"
    assert mi.variant() == "llvm_ad_spectral"


def test_variants_spectral_runs_in_each(variants_spectral, request):
    assert variants_spectral.variant() == request.node.callspec.params["variants_spectral"]


def test_a_test_that_switches_the_variant_itself():
    """The next test must find the variant this one started with."""
    import mitsuba as mi

    START["variant"] = mi.variant()  # set by the tests above
    mitsuba("llvm_ad_spectral" if START["variant"] == "scalar_spectral" else "scalar_spectral")
    assert mi.variant() != START["variant"]


def test_finds_the_variant_the_test_before_started_with():
    import mitsuba as mi

    assert START["variant"] in ("llvm_ad_spectral", "scalar_spectral") and mi.variant() == START["variant"]


@pytest.mark.parametrize("kind", ["gaussian", "delta"])
def test_synthetic_grid_is_what_its_parameters_say(synthetic_grid, kind):
    g = synthetic_grid((2, 3, 5), (486.0, 656.0), pitch_um=1.5, size=21, kind=kind, sigma_um=3.0, field=(4.0, 2.0))
    assert g.data.shape == (2, 3, 5, 21, 21) and g.wavelengths_nm == (486.0, 656.0) and g.pitch_um == 1.5
    assert np.allclose(g.data.sum(axis=(-2, -1)), 1.0)
    assert g.fields_deg[0, 0].tolist() == pytest.approx([-3.2, 4 / 3]) and g.fields_deg[-1, -1, 1] < 0  # top row first
    assert np.allclose(g.chief_ray_mm, synthetic_grid.focal_mm * np.tan(np.radians(g.fields_deg))[None])
    x = (np.arange(21) - 10) * 1.5
    variance = (g.data[0, 0, 0].sum(axis=0) * x**2).sum()
    assert variance == (pytest.approx(9.0, rel=1e-3) if kind == "gaussian" else 0.0)
    assert math.isclose(g.data[0, 0, 0, 10, 10], g.data[0, 0, 0].max())


def test_synthetic_grid_offsets_move_the_chief_rays(synthetic_grid):
    psfs = np.broadcast_to(synthetic_grid.delta(5), (1, 2, 2, 5, 5))
    off = np.full((1, 2, 2, 2), 3.0)
    a, b = synthetic_grid.from_psfs(psfs, 1.0), synthetic_grid.from_psfs(psfs, 1.0, off)
    assert np.allclose(b.chief_ray_mm - a.chief_ray_mm, 3e-3)


def test_synthetic_grid_refuses_an_unknown_kind(synthetic_grid):
    with pytest.raises(ValueError, match="kind 'airy' must be one of gaussian, delta"):
        synthetic_grid(kind="airy")
