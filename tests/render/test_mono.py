"""The mono variants (`render.mitsuba.variant_for`): a job of one wavelength in a grey scene renders in
llvm_ad_mono / cuda_ad_mono, on request, and gives the spectral variant's image at that wavelength.

Both variants draw the same samples (the loop's stratified sets, the same sampler seeds), so the
renders agree to float32 rounding; 450 nm is far from the d line (587.6 nm), the wavelength a plugin
falls back to without one, and the test checks that the d line renders measurably differently."""

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.render import response as responses
from solas_mi.render.mitsuba import default_variant, variant_for

LAMBDA_NM = 450.0


def _mono_variant() -> str:
    return "cuda_ad_mono" if default_variant().startswith("cuda") else "llvm_ad_mono"


def test_variant_for_is_spectral_unless_a_variant_is_named():
    """The spectral variant by default, also at one wavelength (mono is no faster, README); a variant
    named wins, a non-spectral one only with a response of one wavelength."""
    mono, srgb, lines = responses.mono(LAMBDA_NM), responses.srgb(), responses.lines([656.0, 531.0, 486.0])
    assert variant_for(mono) == variant_for(srgb) == variant_for(lines) == default_variant()
    assert variant_for(mono, "llvm_ad_mono") == "llvm_ad_mono"
    assert variant_for(responses.lines([531.0]), "llvm_ad_mono") == "llvm_ad_mono"  # one line is one wavelength
    assert variant_for(lines, "scalar_spectral") == "scalar_spectral"
    with pytest.raises(SolasError, match=r"llvm_ad_mono.*lines:656,531,486"):
        variant_for(lines, "llvm_ad_mono")
    with pytest.raises(SolasError, match=r"llvm_ad_mono.*srgb"):
        variant_for(srgb, "llvm_ad_mono")
    with pytest.raises(SolasError, match="RGB variants"):
        variant_for(mono, "llvm_ad_rgb")


def _object():
    """A 48×64 RGB image whose three channels differ (each band of the object its own image): a
    bright square and a thin bar, on a dim background."""
    img = np.full((48, 64, 3), 0.05, np.float32)
    img[14:34, 20:44] = (0.2, 0.5, 1.0)
    img[8:40, 50:52] = (1.0, 0.7, 0.4)
    return img


def test_mono_image_render_matches_spectral_at_450_nm(doublet):
    from solas_mi.render.image import render_image

    run = dict(sensor=(48, 64), spp=32, fresnel="transmit", seed=5)
    mono = render_image(doublet, _object(), response=f"mono:{LAMBDA_NM:g}", variant=_mono_variant(), **run)
    assert mono.meta["variant"] == _mono_variant()
    spectral = render_image(doublet, _object(), response=f"mono:{LAMBDA_NM:g}", **run)
    assert spectral.meta["variant"] == default_variant()
    a, b = mono.image[..., 0], spectral.image[..., 0]
    scale = float(b.max())
    # the same samples: float32 rounding at most (measured: bit-identical), 1e-4 of the peak is 14× below
    # the noise's RMS (1.4e-3 of the peak, measured) and 5000× below the d line's worst pixel (0.5)
    assert np.max(np.abs(a - b)) < 1e-4 * scale
    # what the tolerance is against: the render's noise (another seed) and the d line's image
    other = render_image(doublet, _object(), response=f"mono:{LAMBDA_NM:g}", **(run | {"seed": 6})).image[..., 0]
    d_line = render_image(doublet, _object(), response="mono:587.5618", **run).image[..., 0]
    assert np.sqrt(np.mean((other - b) ** 2)) > 5e-4 * scale
    assert np.max(np.abs(d_line - b)) > 0.1 * scale  # another band of the object, another blur


def test_mono_refuses_a_response_of_more_wavelengths(doublet):
    from solas_mi.render.image import render_image

    with pytest.raises(SolasError, match=r"llvm_ad_mono.*lines:656,531,486"):
        render_image(doublet, _object(), sensor=(6, 8), spp=3, response="lines", variant="llvm_ad_mono")


def test_the_loop_refuses_plugins_at_another_wavelength(doublet, tmp_path):
    """A mono scene whose `wavelength` default was changed away from the response's is refused."""
    from solas_mi.imageio import image_channels, write_exr
    from solas_mi.optics.camera import camera_for
    from solas_mi.render.loop import render
    from solas_mi.render.mitsuba import load_scene
    from solas_mi.render.scene import write_scene

    write_exr(tmp_path / "object.exr", image_channels(_object()))
    xml = write_scene(
        doublet,
        tmp_path,
        str(tmp_path / "object.exr"),
        camera_for(doublet, (6, 8)),
        rings=8,
        spp=4,
        response=f"mono:{LAMBDA_NM:g}",
    )
    text = xml.read_text()
    assert text.count('<float name="wavelength" value="$wavelength"/>') == 4  # three glass caps and the object
    assert '<default name="wavelength" value="450.0"/>' in text
    scene = load_scene(xml, "llvm_ad_mono", wavelength=600)
    with pytest.raises(SolasError, match=r"450 nm.*image_object at 600 nm, sellmeier_dielectric at 600 nm"):
        render(scene, 4)
    srgb = write_scene(
        doublet, tmp_path / "srgb", str(tmp_path / "object.exr"), camera_for(doublet, (6, 8)), rings=8, spp=4
    )
    assert "wavelength" not in srgb.read_text()  # more than one wavelength: the plugins' default


def test_lens_camera_in_mono_matches_spectral_on_a_grey_scene(doublet, tmp_path):
    """The street experiment's grey scene through the lens camera at 450 nm, 80×60 px, 8 spp: the mono
    variant's luminance film against the spectral variant's one-line specfilm, the same samples."""
    from solas_mi.experiments.street.framings import framing
    from solas_mi.experiments.street.run import SCENE, experiment_scene
    from solas_mi.render.stock import render_scene
    from solas_mi.render.user_scene import default_pitch_um, load

    fov, w, h = float(doublet.field_deg), 80, 60
    params = {k: v for k, v in framing(doublet).params(2 * fov, w, h, 8).items() if k != "fov"}
    images = {}
    for variant in (default_variant(), _mono_variant()):
        spectral = "spectral" in variant
        xml = experiment_scene(SCENE, tmp_path / variant, LAMBDA_NM, spectral=spectral)
        scene = load(
            xml,
            variant,
            doublet,
            params,
            response=f"mono:{LAMBDA_NM:g}",
            pitch_um=default_pitch_um(doublet, fov, "x", w, h),
        )
        result = render_scene(scene, 8, seed=2)
        assert result.meta["variant"] == variant
        images[spectral] = result.image[..., 0]
    scale = float(images[True].max())
    assert scale > 0.1
    assert np.max(np.abs(images[False] - images[True])) < 1e-4 * scale
