"""`sellmeier_dielectric` under a stock camera (four different wavelengths per path) and its
component masks."""

import math

import numpy as np
import pytest

import solas_mi
from solas_mi.optics.glass import resolve


def _flat_white(mi) -> np.ndarray:
    """hdrfilm's linear sRGB of a flat spectrum of radiance 1 (Mitsuba's CIE tables, 360–830 nm)."""
    step = 0.05
    lam = np.arange(mi.MI_CIE_MIN, mi.MI_CIE_MAX, step) + step / 2
    xyz = np.array(mi.cie1931_xyz(mi.Float(lam))).T.sum(axis=0) * step * mi.MI_CIE_Y_NORMALIZATION
    return np.array(mi.xyz_to_srgb(mi.Color3f(*(float(v) for v in xyz)))).ravel()


@pytest.mark.parametrize("variant, size, spp", [("llvm_ad_spectral", 16, 1024), ("scalar_spectral", 8, 128)])
def test_a_glass_slab_seen_by_a_stock_camera_passes_white_light_unchanged(variant, size, spp):
    """A perspective camera (four wavelengths per path) looks through a BK7 slab at a flat-spectrum
    emitter of radiance 1; without Fresnel losses the radiance n² gained entering is lost leaving,
    so each pixel is the film's flat white. Lane termination at every interface without its
    probability would come out 4× too bright (two interfaces), no termination weight 4× too dark."""
    mi = solas_mi.mitsuba(variant)
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 4},
            "sensor": {
                "type": "perspective",
                "fov": 10.0,
                "to_world": mi.ScalarTransform4f().look_at([0, 0, -5], [0, 0, 0], [0, 1, 0]),
                "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": spp},
            },
            "light": {"type": "constant", "radiance": {"type": "spectrum", "value": 1.0}},
            "slab": {
                "type": "cube",
                "to_world": mi.ScalarTransform4f().scale([3.0, 3.0, 0.5]),
                "bsdf": {"type": "sellmeier_dielectric", "int_glass": "N-BK7", "fresnel": "off"},
            },
        }
    )
    image = np.array(mi.render(scene, seed=5))
    ratio = image.mean(axis=(0, 1)) / _flat_white(solas_mi.mitsuba("llvm_ad_spectral"))
    assert np.abs(ratio - 1).max() < (0.03 if variant == "llvm_ad_spectral" else 0.08), ratio


def _interaction(mi, wavelengths, cos_theta=0.8):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(math.sqrt(1 - cos_theta**2), 0.0, cos_theta)
    si.wavelengths = mi.Spectrum(*wavelengths)
    return si


def _sample(mi, bsdf, ctx, si, sample1=0.5):
    bs, weight = bsdf.sample(ctx, si, mi.Float(sample1), mi.Point2f(0.5, 0.5))
    return bs, np.array(weight).ravel()


def _fresnel(mi, lam_nm, cos_theta=0.8):
    n = float(resolve("N-BK7").index_formula(lam_nm * 1e-3, math.sqrt))
    r, _cos_t, _, _eta_ti = mi.fresnel(mi.Float(cos_theta), mi.Float(n))
    return float(r[0]), n


@pytest.mark.parametrize("fresnel", ["transmit", "sample"])
def test_component_masks_return_one_component_with_its_weight(mi, fresnel):
    """Reflection only: the mirror direction, weight R; transmission only: the refracted direction,
    weight (1 − R)/n² for radiance entering glass of index n (Mitsuba's `dielectric` does the same)."""
    bsdf = mi.load_dict({"type": "sellmeier_dielectric", "int_glass": "N-BK7", "fresnel": fresnel})
    si = _interaction(mi, [550.0] * 4)
    r, n = _fresnel(mi, 550.0)
    for flags, component in ((mi.BSDFFlags.DeltaReflection, 0), (mi.BSDFFlags.DeltaTransmission, 1)):
        for ctx in (
            mi.BSDFContext(mi.TransportMode.Radiance, +flags, component),  # by type
            mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.All, component),
        ):  # by index
            bs, weight = _sample(mi, bsdf, ctx, si, sample1=0.999 if component == 0 else 0.0)
            expected = r if component == 0 else (1 - r) / n**2
            assert np.allclose(weight, expected, rtol=1e-5)
            assert int(bs.sampled_component[0]) == component and (float(bs.wo.z[0]) > 0) == (component == 0)


def test_off_mode_reflects_only_under_total_internal_reflection(mi):
    bsdf = mi.load_dict({"type": "sellmeier_dielectric", "int_glass": "N-BK7", "fresnel": "off"})
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.DeltaReflection, 0)
    assert np.allclose(_sample(mi, bsdf, ctx, _interaction(mi, [550.0] * 4))[1], 0.0)
    inside = _interaction(mi, [550.0] * 4, cos_theta=-0.3)  # from the glass, beyond the critical angle
    assert np.allclose(_sample(mi, bsdf, ctx, inside)[1], 1.0)


@pytest.mark.parametrize("sample1, lane", [(0.1, 0), (0.3, 1), (0.6, 2), (0.9, 3)])
def test_different_wavelengths_follow_one_lane_weighted_by_four(mi, sample1, lane):
    """Four wavelengths: the interface refracts along the lane sample1 picks, weight 4·T in that lane,
    0 in the others; equal wavelengths: weight T in all four."""
    bsdf = mi.load_dict({"type": "sellmeier_dielectric", "int_glass": "N-BK7"})
    ctx = mi.BSDFContext()
    lams = [450.0, 520.0, 600.0, 700.0]
    bs, weight = _sample(mi, bsdf, ctx, _interaction(mi, lams), sample1)
    r, n = _fresnel(mi, lams[lane])
    expected = np.zeros(4)
    expected[lane] = 4 * (1 - r) / n**2
    assert np.allclose(weight, expected, rtol=1e-5)
    sin_t = -float(bs.wo.x[0])  # the refracted ray crosses to the other side of the normal
    assert sin_t == pytest.approx(0.6 / n, rel=1e-5)  # Snell's law at this lane's index
    _, equal = _sample(mi, bsdf, ctx, _interaction(mi, [lams[lane]] * 4), sample1)
    assert np.allclose(equal, (1 - r) / n**2, rtol=1e-5)


@pytest.mark.parametrize("name", ["HOYA:TAFD5F", "OHARA:S-LAH59"])
def test_vendor_glass_refracts_with_its_catalogue_index(mi, name):
    """A polynomial-formula glass (HOYA) and a Sellmeier one (OHARA) in the BSDF: the refracted
    direction obeys Snell's law with the catalogue's index at each lane's wavelength."""
    bsdf = mi.load_dict({"type": "sellmeier_dielectric", "int_glass": name, "fresnel": "transmit"})
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.DeltaTransmission, 1)
    for lam in (450.0, 587.5618, 700.0):
        bs, _ = _sample(mi, bsdf, ctx, _interaction(mi, [lam] * 4), sample1=0.0)
        n = resolve(name).index(lam)
        assert abs(float(bs.wo.x[0])) == pytest.approx(0.6 / n, rel=2e-6)


def test_glass_at_a_temperature_refracts_with_its_index_there(mi, tmp_path):
    """`temperature_c` and `pressure_kpa` put the glass there (`Glass.at`), as the mesh scene of a lens at
    80 °C writes them on each of its dielectrics; without them, 20 °C and standard air."""
    from solas_mi import Lens
    from solas_mi.render.scene import lens_parts

    hot = Lens.load("solas-doublet").at(80.0, 95.0)
    (part, *_) = [p for p in lens_parts(hot) if p.int_glass]
    assert dict(part.environment) == {"temperature_c": 80.0, "pressure_kpa": 95.0}
    assert all(not p.environment for p in lens_parts(Lens.load("solas-doublet")))
    bsdf = mi.load_dict(
        {"type": "sellmeier_dielectric", "int_glass": "N-BK7", "fresnel": "transmit", **dict(part.environment)}
    )
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.DeltaTransmission, 1)
    for lam in (450.0, 700.0):
        bs, _ = _sample(mi, bsdf, ctx, _interaction(mi, [lam] * 4), sample1=0.0)
        n = resolve("N-BK7").at(80.0, 95.0).index(lam)
        assert n != resolve("N-BK7").index(lam)
        assert abs(float(bs.wo.x[0])) == pytest.approx(0.6 / n, rel=2e-6)
