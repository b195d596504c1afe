"""A sun in an environment map (the feature of public sky scenes: a lat-long HDR sky whose sun is a few bright
texels) rendered with ghosts through two coated lenses (`render --lens --ghosts`): every pixel and flare layer
finite, the ghosts' light beside the sun, and the framing that of the render without ghosts and of the pinhole
camera's (the sun on the same pixel)."""

import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.imageio import read_exr, write_exr
from solas_mi.labelkinds import FLARE_LAYERS
from solas_mi.optics.typical_ar import with_typical_ar
from solas_mi.render.scene import lens_file

SUN = (8.0, 4.0)  # the sun's direction, degrees right of and above the camera's axis
SCENE = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="24"/>
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film>
    </sensor>
    <emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>
</scene>"""


def sky_with_sun(path, width=720, height=360):
    """A lat-long sky (Mitsuba's envmap: u along azimuth from -x, v from +y down) of radiance 0.5 with a sun of
    0.6 deg radius (a few texels) at `SUN` from +z (the camera's axis) of radiance 1e5."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    phi, theta = np.meshgrid(u * 2 * math.pi, v * math.pi)
    direction = np.stack([np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)], axis=-1)
    tx, ty = (math.tan(math.radians(a)) for a in SUN)
    sun = np.array([-tx, ty, 1.0]) / math.hypot(tx, ty, 1.0)  # Mitsuba's camera: +x of the world on the image's left
    radiance = np.where(direction @ sun > math.cos(math.radians(0.6)), 1e5, 0.5).astype(np.float32)
    write_exr(path, dict.fromkeys("RGB", radiance), {})


def brightest(image):
    row, col = np.unravel_index(np.argmax(image), image.shape)
    return np.array([col, row])


@pytest.mark.slow
@pytest.mark.usefixtures("variant_llvm_ad_spectral")
@pytest.mark.parametrize("name", ["double-gauss-50mm", "cooke-triplet"])
def test_an_environment_maps_sun_renders_with_ghosts_finite_and_framed_as_without(tmp_path, name):
    sky_with_sun(tmp_path / "sky.exr")
    (tmp_path / "sky.xml").write_text(SCENE)
    lens = lens_file(with_typical_ar(Lens.load(name)), tmp_path)
    base = ["render", str(tmp_path / "sky.xml"), "--spp", "8"]
    assert main([*base, "-o", str(tmp_path / "pinhole.exr")]) == 0
    assert main([*base, "--lens", str(lens), "-o", str(tmp_path / "plain.exr")]) == 0
    assert main([*base, "--lens", str(lens), "--ghosts", "-o", str(tmp_path / "flare.exr")]) == 0
    images = {}
    for key in ("pinhole", "plain", "flare"):
        channels, _ = read_exr(tmp_path / f"{key}.exr")
        assert all(np.isfinite(v).all() for v in channels.values()), key
        images[key] = (np.mean([channels[c] for c in "RGB"], axis=0), channels)
    flare, ratio = (images["flare"][1][layer] for layer in FLARE_LAYERS)
    assert (flare >= 0).all() and flare.max() > 0 and ratio.max() > 0
    sun = brightest(images["pinhole"][0])
    assert 0 < sun[0] < 63 and 0 < sun[1] < 47  # the sun inside the frame
    assert np.array_equal(brightest(images["plain"][0]), brightest(images["flare"][0]))
    assert np.abs(brightest(images["flare"][0]) - sun).max() <= 1
