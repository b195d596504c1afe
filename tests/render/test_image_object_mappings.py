"""`image_object`'s emitter sampling for Mitsuba's integrators in every mapping (`plane_direction`, the
inverse of `plane_point`): the pdf integrates to one over the sphere, sampled directions carry the pdf
that `pdf_direction` gives them, and the sampled estimate of the emitted radiance over the sphere
equals a uniform-sphere estimate. Then the fisheye's environment under stock `path`."""

import math

import numpy as np
import pytest

N = 1 << 18
# images the mapping covers wholly (12 × 20 texels: the height spans 0.6 of the width)
CASES = [("rectilinear", 60.0), ("equidistant", 100.0), ("equisolid", 110.0), ("equirectangular", 140.0)]


def _emitter(mi, tmp_path, mapping, fov):
    from solas_mi.imageio import write_exr

    rng = np.random.default_rng(3)
    image = (0.2 + rng.random((12, 20))).astype(np.float32)
    image[3:6, 4:9] = 6.0  # a bright patch: the sampling must follow the texel weights
    write_exr(tmp_path / "env.exr", {"Y": image})
    emitter = mi.load_dict(
        {"type": "image_object", "filename": str(tmp_path / "env.exr"), "fov_deg": fov, "mapping": mapping}
    )
    emitter.set_scene(mi.load_dict({"type": "scene", "ball": {"type": "sphere"}}))
    return emitter, image


def _interaction(mi, n):
    import drjit as dr

    it = dr.zeros(mi.Interaction3f, n)
    it.wavelengths = mi.Spectrum(550.0)
    return it


@pytest.mark.parametrize("mapping, fov", CASES)
def test_emitter_sampling_matches_its_pdf_and_radiance(mi, tmp_path, mapping, fov):
    import drjit as dr

    emitter, image = _emitter(mi, tmp_path, mapping, fov)
    rng = np.random.default_rng(7)
    # uniform directions over the sphere: ∫ pdf dω and ∫ L dω
    d = mi.warp.square_to_uniform_sphere(mi.Point2f(*rng.random((2, N))))
    it = _interaction(mi, N)
    ds = dr.zeros(mi.DirectionSample3f, N)
    ds.d = d
    pdf_uniform = np.array(emitter.pdf_direction(it, ds))
    radiance_uniform = np.array(emitter.eval_direction(it, ds))[0]
    assert 4 * math.pi * pdf_uniform.mean() == pytest.approx(1.0, abs=0.02)
    # sampled directions: their pdf is pdf_direction's, and weight × pdf is the radiance
    ds_s, weight = emitter.sample_direction(it, mi.Point2f(*rng.random((2, N))))
    pdf_s, again = np.array(ds_s.pdf), np.array(emitter.pdf_direction(it, ds_s))
    ok = pdf_s > 0
    assert ok.mean() > 0.99
    # (a float32 direction on a texel's border may land in the neighbour: a few in 1e5)
    assert np.isclose(again[ok], pdf_s[ok], rtol=2e-4).mean() > 0.9999
    value = np.array(emitter.eval_direction(it, ds_s))[0]
    assert np.isclose(np.array(weight)[0][ok] * pdf_s[ok], value[ok], rtol=2e-4).mean() > 0.9999
    # ∫ L dω over the image two ways: importance-sampled, and uniform over the sphere (the "edge"
    # surroundings beyond the image are left to BSDF sampling)
    sampled = np.array(weight)[0].mean()
    assert sampled == pytest.approx(4 * math.pi * (radiance_uniform * (pdf_uniform > 0)).mean(), rel=0.02)
    # texels are drawn by their weight: the bright patch's share of the samples
    u, v = np.array(ds_s.uv.x) * image.shape[1], np.array(ds_s.uv.y) * image.shape[0]
    in_patch = (u >= 4) & (u < 9) & (v >= 3) & (v < 6)
    assert in_patch.mean() == pytest.approx(image[3:6, 4:9].sum() / image.sum(), abs=0.005)


def test_texels_beyond_the_mapping_are_never_drawn(mi, tmp_path):
    """An equisolid image (±170° across) whose corners reach past the 180° its mapping covers: the
    texels wholly outside get no samples; the few lost fall in texels the domain's edge cuts."""
    import drjit as dr

    emitter, _ = _emitter(mi, tmp_path, "equisolid", 170.0)
    rng = np.random.default_rng(11)
    ds, weight = emitter.sample_direction(_interaction(mi, N), mi.Point2f(*rng.random((2, N))))
    pdf = np.array(ds.pdf)
    assert (pdf > 0).mean() > 0.97 and np.all(np.isfinite(np.array(weight)))
    d = mi.warp.square_to_uniform_sphere(mi.Point2f(*rng.random((2, N))))
    uniform = dr.zeros(mi.DirectionSample3f, N)
    uniform.d = d
    mass = 4 * math.pi * np.array(emitter.pdf_direction(_interaction(mi, N), uniform)).mean()
    assert mass == pytest.approx((pdf > 0).mean(), abs=0.02)  # what is not lost integrates to one


def test_stock_path_renders_the_fisheye_environment_as_the_loop_does(mi, tmp_path):
    """An equidistant environment through the fisheye, 32×32 px to 90°: Mitsuba's `path` (through the
    lens's glass its paths reach the environment by BSDF sampling, weighted by the MIS pdf above)
    against solas-mi's loop, quadrant means within 2 %. (Mitsuba's `path` asks the emitter's
    `pdf_direction` for its MIS weights; before every mapping had one, this render stopped.)"""
    from solas_mi import Lens
    from solas_mi.imageio import write_exr
    from solas_mi.render.image import fisheye_camera
    from solas_mi.render.loop import render
    from solas_mi.render.scene import write_scene

    lens = Lens.load("nikkor-fisheye")
    n, step = 192, 1.0
    _yy, xx = np.indices((n, n))
    env = (0.5 + 0.4 * np.cos(2 * np.pi * (xx - n / 2) * step / 40.0)).astype(np.float32)
    write_exr(tmp_path / "env.exr", {"Y": env})
    camera = fisheye_camera(lens, (32, 32), n * step / 2, 600.0)
    xml = write_scene(
        lens, tmp_path, str(tmp_path / "env.exr"), camera, response="srgb", fresnel="off", mapping="equidistant"
    )
    scene = mi.load_file(str(xml))
    stock = np.array(mi.render(scene, spp=1024, seed=1))  # independent wavelengths: 1024 for 1 % in the means
    loop = render(scene, 64, seed=1).image
    assert stock.shape == loop.shape
    # hdrfilm develops as the srgb response does (one colour convention, README "Colour"): the same
    # channel means with no factor (there was one per channel while srgb was balanced for a flat spectrum)
    ratio = stock.mean(axis=(0, 1)) / loop.mean(axis=(0, 1))
    assert np.allclose(ratio, 1.0, atol=0.01)
    q_stock = stock.reshape(2, 16, 2, 16, 3).mean(axis=(1, 3))
    q_loop = loop.reshape(2, 16, 2, 16, 3).mean(axis=(1, 3))
    assert np.allclose(q_stock, q_loop, rtol=0.02)
