"""The lens as Mitsuba geometry against the Float64 tracer: PSFs, image positions, radiometry,
dispersion, and the scalar reference variant."""
import math

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics.camera import camera_for
from solas_mi.optics.illumination import (
    ideal_irradiance,
    irradiance,
    relative_illumination,
)
from solas_mi.optics.pupil import chief_rays
from solas_mi.psf.geometric import entrance_grid_hits
from solas_mi.render.loop import load_scene, mitsuba, render_image
from solas_mi.render.scene import cap_mesh, lens_parts, write_scene
from solas_mi.validation.scene_psf import scene_psf

RAYS = 256


@pytest.fixture(scope="module")
def doublet():
    return Lens.load("solas-doublet")


@pytest.fixture(scope="module")
def scene(doublet, tmp_path_factory):
    """The doublet's scene with the tracer's radiometry (no Fresnel losses)."""
    mitsuba("llvm_ad_spectral")
    out = tmp_path_factory.mktemp("scene")
    white = out / "white.exr"
    from solas_mi.imageio import write_exr

    write_exr(white, {"Y": np.ones((12, 16), dtype=np.float32)})
    return load_scene(write_scene(doublet, out, "white.exr", camera_for(doublet, (12, 16)), fresnel="off"),
                      "llvm_ad_spectral")


def _tracer_spot(lens, field, wavelength):
    """Centroid (µm from the chief ray) and RMS radius of the tracer's rays on the same entrance grid."""
    f, w = np.array([field], dtype=float), np.array([wavelength], dtype=float)
    dx, dy, p = entrance_grid_hits(lens, f, w, RAYS, chief_rays(lens, f, w))[0]
    cx, cy = np.average(dx, weights=p), np.average(dy, weights=p)
    return np.array([cx, cy]), math.sqrt(np.average((dx - cx) ** 2 + (dy - cy) ** 2, weights=p))


def test_cap_mesh_lies_on_the_sphere_and_faces_the_object():
    v, n, f = cap_mesh(-30.716, 6.0, 15.0, 32)
    centre = np.array([0.0, 0.0, 6.0 - 30.716])
    assert np.allclose(np.linalg.norm(v - centre, axis=1), 30.716, atol=1e-9)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0) and np.all(n[:, 2] < 0)
    geo = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    assert np.all(geo[:, 2] < 0)  # winding agrees with the normals
    # the flat triangles sit inside the sphere by about (edge length)² / 8R, no more
    edge = np.linalg.norm(v[f[:, 1]] - v[f[:, 2]], axis=1).max()
    depth = 30.716 - np.linalg.norm(v[f].mean(axis=1) - centre, axis=1)
    assert 0 < depth.max() < 1.5 * edge ** 2 / (8 * 30.716)


def test_parts_of_the_doublet(doublet):
    names = [p.name for p in lens_parts(doublet, 16)]
    # three refracting caps (the stop refracts nothing), an absorbing ring per aperture, the barrel
    assert names == ["surface1", "aperture1", "surface2", "aperture2", "surface3", "aperture3", "aperture4", "barrel"]
    glasses = [(p.ext_glass, p.int_glass) for p in lens_parts(doublet, 16) if p.int_glass]
    assert glasses == [("AIR", "BK7"), ("BK7", "F2"), ("F2", "AIR")]


@pytest.mark.parametrize("wavelength", [486.0, 531.0, 656.0])
@pytest.mark.parametrize("field", [(0.0, 0.0), (0.0, 2.0), (0.0, -2.0)])
def test_scene_psf_matches_tracer(doublet, scene, field, wavelength):
    p = scene_psf(scene, doublet, field, wavelength, rays=RAYS)
    centroid, rms = _tracer_spot(doublet, field, wavelength)
    assert np.hypot(*(np.array(p.meta["centroid_um"]) - centroid)) < 0.5
    assert p.meta["rms_radius_um"] == pytest.approx(rms, rel=0.02)
    assert p.meta["transmission"] > 0.5 and p.data.sum() == pytest.approx(1.0, rel=1e-6)


def test_lateral_colour_matches_tracer(doublet, scene):
    """486 vs 656 nm centroid shift at +2°, the same through the scene and the tracer. (The chief rays
    are 3.1 µm apart; coma moves the 486 nm centroid up more, leaving 0.9 µm.)"""
    field = (0.0, 2.0)
    shift = {}
    for source in ("scene", "tracer"):
        pos = []
        for w in (486.0, 656.0):
            chief = chief_rays(doublet, np.array([field]), np.array([w])).image_xy[0] * 1e3
            c = (np.array(scene_psf(scene, doublet, field, w, rays=RAYS).meta["centroid_um"]) if source == "scene"
                 else _tracer_spot(doublet, field, w)[0])
            pos.append(chief + c)
        shift[source] = pos[0] - pos[1]
    assert 0.5 < abs(shift["tracer"][1]) < 5.0
    assert np.hypot(*(shift["scene"] - shift["tracer"])) < 0.2


def test_white_object_relative_illumination(doublet):
    """A uniform white object renders the tracer's irradiance (image side, exact) and its
    transmitted-energy view (pupil transmission × cos³θ × J(0)/J) across the field within 1 %."""
    camera = camera_for(doublet, (6, 8))
    r = render_image(doublet, np.ones((6, 8)), (6, 8), spp=1024, response="mono:531", fresnel="off",
                     variant="llvm_ad_spectral")
    x, y = np.meshgrid(camera.pixel_x_mm(), camera.pixel_y_mm())
    pts = np.stack([x.ravel(), y.ravel()], -1)
    exact = irradiance(doublet, pts, 531.0, samples=256) / ideal_irradiance(doublet, camera.focal_mm)
    assert np.max(np.abs(r.image[..., 0].ravel() / exact - 1)) < 0.003
    axis = irradiance(doublet, np.zeros((1, 2)), 531.0, samples=256)[0] / ideal_irradiance(doublet, camera.focal_mm)
    # fields whose chief rays land at the pixel centres (rectilinear guess, refined once)
    guess = np.degrees(np.arctan(pts / camera.focal_mm))
    landed = chief_rays(doublet, guess, np.full(len(guess), 531.0)).image_xy
    fields = np.degrees(np.arctan(np.tan(np.radians(guess)) * pts / np.where(landed == 0, 1, landed)))
    ri = relative_illumination(doublet, fields, 531.0, pupil_samples=64)
    assert np.max(np.abs(r.image[..., 0].ravel() / axis / ri - 1)) < 0.01
    assert r.image.min() < 0.99 * r.image.max()  # the corners are darker: the test can tell


def test_white_object_never_exceeds_the_lens_transmission(doublet):
    lossless = render_image(doublet, np.ones((6, 8)), (6, 8), spp=192, response="lines", fresnel="off",
                            variant="llvm_ad_spectral").image
    real = render_image(doublet, np.ones((6, 8)), (6, 8), spp=192, response="lines", fresnel="transmit",
                        variant="llvm_ad_spectral").image
    camera = camera_for(doublet, (6, 8))
    # a lossless lens gives at most its on-axis irradiance (in the ideal camera's unit: (f'/f)² × sin²u'/tan²u')
    axis = irradiance(doublet, np.zeros((1, 2)), 531.0, samples=256)[0] / ideal_irradiance(doublet, camera.focal_mm)
    assert lossless.max() <= axis * (1 + 2e-3)
    assert np.all(real < lossless) and 0.85 < real.mean() / lossless.mean() < 0.95  # two air-glass surfaces + cement


def test_dot_lands_where_the_tracer_says(doublet):
    """A bright texel at field (+2°, 0) seen through a ±2.5° image: its rendered centroid is the
    tracer's (chief ray + geometric PSF centroid) within 0.5 µm."""
    fov = 2.5
    camera = camera_for(doublet, (24, 720), fov_deg=fov)
    image = np.zeros((24, 720))
    t = math.tan(math.radians(fov)) / 360
    col = int(math.floor(math.tan(math.radians(2.0)) / t + 360))
    image[11:13, col] = 1.0  # two texels straddling y = 0
    field = np.degrees(np.arctan((col + 0.5 - 360) * t))
    r = render_image(doublet, image, (24, 720), fov_deg=fov, spp=64, response="mono:531", fresnel="off",
                     variant="llvm_ad_spectral")
    img = r.image[..., 0]
    x, y = np.meshgrid(camera.pixel_x_mm(), camera.pixel_y_mm())
    cx = float((img * x).sum() / img.sum()) * 1e3
    chief = chief_rays(doublet, np.array([[field, 0.0]]), np.array([531.0])).image_xy[0, 0] * 1e3
    offset = _tracer_spot(doublet, (field, 0.0), 531.0)[0][0]
    assert cx == pytest.approx(chief + offset, abs=0.5)
    assert abs(float((img * y).sum() / img.sum()) * 1e3) < 0.5


def test_scalar_and_llvm_variants_agree(doublet):
    """A small render in the scalar reference variant matches llvm_ad_spectral within noise."""
    image = np.zeros((4, 6, 3))
    image[:, :3] = (0.2, 0.5, 1.0)
    image[:, 3:] = (1.0, 0.3, 0.1)
    runs = {v: render_image(doublet, image, (4, 6), spp=48, response="lines", variant=v, rings=16).image
            for v in ("scalar_spectral", "llvm_ad_spectral")}
    mitsuba("llvm_ad_spectral")
    a, b = runs["scalar_spectral"], runs["llvm_ad_spectral"]
    assert np.abs(a.mean(axis=(0, 1)) - b.mean(axis=(0, 1))).max() < 0.02 * b.mean()
    assert np.sqrt(np.mean((a - b) ** 2)) < 0.05 * np.sqrt(np.mean(b ** 2))


def test_bad_inputs(doublet):
    with pytest.raises(SolasError, match="variant"):
        mitsuba("llvm_ad_rgb_nonexistent")
    with pytest.raises(SolasError, match="samples per pixel"):
        render_image(doublet, np.ones((6, 8)), (6, 8), spp=0, variant="llvm_ad_spectral")
    with pytest.raises(SolasError, match="at least the response's 3 lines"):
        render_image(doublet, np.ones((6, 8)), (6, 8), spp=2, response="lines", variant="llvm_ad_spectral")
    with pytest.raises(SolasError, match="camera response"):
        render_image(doublet, np.ones((6, 8)), (6, 8), spp=4, response="infrared", variant="llvm_ad_spectral")
    with pytest.raises(SolasError, match="boundary"):
        render_image(doublet, np.ones((6, 8)), (6, 8), spp=4, boundary="wrap", variant="llvm_ad_spectral")
    with pytest.raises(SolasError, match="rings"):
        lens_parts(doublet, 1)


def test_scene_and_render_commands(tmp_path):
    """`solas-mi scene` writes an editable scene; `solas-mi render` renders it with overrides."""
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr

    scene_dir = tmp_path / "scene"
    assert main(["scene", "solas-doublet", "-o", str(scene_dir), "--sensor", "16x12", "--rings", "16"]) == 0
    xml = scene_dir / "scene.xml"
    assert (scene_dir / "meshes" / "surface1.ply").is_file() and (scene_dir / "rocket.png").is_file()
    out = tmp_path / "r.exr"
    assert main(["render", str(xml), "-o", str(out), "--spp", "3", "--set", "response=lines",
                 "--variant", "llvm_ad_spectral"]) == 0
    channels, meta = read_exr(out)
    assert sorted(channels) == ["B", "G", "R"] and channels["R"].shape == (12, 16)
    assert meta["spp"] == 3 and meta["response"].startswith("lines") and out.with_suffix(".png").is_file()
    assert main(["render", str(xml), "-o", str(tmp_path / "bad.exr"), "--set", "image=missing.png"]) == 2
    assert not (tmp_path / "bad.exr").exists()
    assert main(["render-image", "solas-doublet", str(tmp_path / "nope.png"), "-o", str(tmp_path / "x.exr")]) == 2
