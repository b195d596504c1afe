"""The PSF method "render" (`render.psf`): rays traced through the Mitsuba scene's lens meshes agree
with the Float64 tracer's geometric PSF, at infinity and for a finite object."""

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.imageio import read_exr
from solas_mi.psf import psf

KW = dict(rays=256, pitch_um=1.0, size=80)


def moments(p):
    """Centroid (µm, x right, y up) and RMS radius (µm) of a PSF."""
    x, y = np.meshgrid(p.x_um, p.y_um)
    w = p.data / p.data.sum()
    cx, cy = (w * x).sum(), (w * y).sum()
    return np.array([cx, cy]), float(np.sqrt((w * ((x - cx) ** 2 + (y - cy) ** 2)).sum()))


@pytest.mark.parametrize("distance", [None, 3000.0])
def test_render_psf_matches_the_tracer(doublet_spec, distance):
    if distance is not None:
        doublet_spec["object"] = {"distance": distance}
        doublet_spec["surface"][-1]["thickness"] += 3.5  # refocus near the new image (f²/d ≈ 3.4 mm)
    lens = Lens.from_dict(doublet_spec, source="doublet")
    scene = psf(lens, (0, 2), 531.0, method="render", normalization="none", **KW)
    ray = psf(lens, (0, 2), 531.0, method="geometric", normalization="none", **KW)
    assert scene.meta["transmission"] == pytest.approx(ray.meta["transmission"], rel=1e-3)
    (c_scene, r_scene), (c_ray, r_ray) = moments(scene), moments(ray)
    assert np.abs(c_scene - c_ray).max() < 0.5  # µm, as the scene-PSF bridge
    assert r_scene == pytest.approx(r_ray, rel=0.02)


def test_psf_command_with_the_render_method(tmp_path, capsys):
    out = tmp_path / "psf.exr"
    assert (
        main(
            [
                "psf",
                "solas-doublet",
                "--field-deg",
                "0,2",
                "--wavelengths-nm",
                "531",
                "--psf-method",
                "render",
                "--rays",
                "128",
                "--size",
                "40",
                "--pitch-um",
                "2",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    channels, meta = read_exr(out)
    assert meta["method"] == "render" and meta["sampling"] == {"rays": 128}
    assert channels["Y"].sum() == pytest.approx(1.0, rel=1e-5)


def test_render_psf_of_an_aspheric_lens_matches_the_tracer(doublet_spec):
    doublet_spec["surface"][0].update(conic=-2.0, aspheric=[-3e-7, 1e-10])
    lens = Lens.from_dict(doublet_spec, source="aspheric doublet")
    scene = psf(lens, (0, 2), 531.0, method="render", normalization="none", **KW)
    ray = psf(lens, (0, 2), 531.0, method="geometric", normalization="none", **KW)
    sphere = psf(Lens.load("solas-doublet"), (0, 2), 531.0, method="geometric", normalization="none", **KW)
    (c_scene, r_scene), (c_ray, r_ray), (_, r_sphere) = moments(scene), moments(ray), moments(sphere)
    assert abs(r_ray - r_sphere) > 0.1 * r_sphere  # the asphere changes the PSF: the test can tell
    assert scene.meta["transmission"] == pytest.approx(ray.meta["transmission"], rel=1e-3)
    assert np.abs(c_scene - c_ray).max() < 0.5  # µm
    assert r_scene == pytest.approx(r_ray, rel=0.02)


def test_render_psf_launches_polar_fields_as_the_tracer_does():
    """A fisheye names its fields by polar angle: the scene's rays leave in that direction (launched
    by field tangents, a 60° field went elsewhere and the window stayed dark)."""
    lens = Lens.load("nikkor-fisheye")
    kw = dict(rays=96, pitch_um=2.0, size=60, normalization="none")
    scene = psf(lens, (0, 60), 587.56, method="render", **kw)
    ray = psf(lens, (0, 60), 587.56, method="geometric", **kw)
    assert scene.meta["transmission"] == pytest.approx(ray.meta["transmission"], rel=2e-3)
    assert scene.data.sum() == pytest.approx(ray.data.sum(), rel=0.02)
    (c_scene, r_scene), (c_ray, r_ray) = moments(scene), moments(ray)
    assert np.abs(c_scene - c_ray).max() < 1.0  # µm
    assert r_scene == pytest.approx(r_ray, rel=0.03)


def test_chunked_rays_give_the_same_psf(doublet, monkeypatch):
    """A field's rays traced in chunks (so a signal is answered between them) give the PSF of one wavefront."""
    from solas_mi.render import psf as render_psf

    whole = psf(doublet, (0, 2), 531.0, method="render", normalization="none", **KW)
    monkeypatch.setattr(render_psf, "steps_per_pass", lambda variant: 10 * 1000)  # 1000 rays a chunk: 66 chunks
    chunked = psf(doublet, (0, 2), 531.0, method="render", normalization="none", **KW)
    assert np.allclose(chunked.data, whole.data, rtol=1e-6, atol=1e-9 * whole.data.max())
