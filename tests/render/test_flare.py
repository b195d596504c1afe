"""Flare in renders (`render SCENE --lens LENS --ghosts`, `render.flare`): the frame is the direct image plus
the ghosts' stray light, with the flare label layers beside it, named in the metadata, never NaN."""

import dataclasses
import itertools
import json
import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.imageio import read_exr
from solas_mi.labelkinds import FLARE_LAYERS, MAX_RATIO, flare_layers
from solas_mi.optics import coating
from solas_mi.psf.starburst import iris_kernel, spread
from solas_mi.psf.stray_light import working_f_number

SCENE = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/></film>
    </sensor>
    <shape type="sphere" id="sun">
        <point name="center" x="1500" y="1000" z="10000"/>
        <float name="radius" value="150"/>
        <emitter type="area"><rgb name="radiance" value="2000, 1800, 1500"/></emitter>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="30" y="2"/><translate y="-3" z="40"/></transform>
        <bsdf type="diffuse"/>
    </shape>
</scene>"""


def test_flare_layers_are_the_stray_light_and_its_ratio_never_nan():
    """flare.irradiance is the stray image's channel mean; flare.ratio its ratio to the direct image's, 0 where
    no stray light arrives (also where both are dark), MAX_RATIO where the direct image is dark."""
    direct = np.array([[[2.0, 2.0, 2.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 3.0, 2.0]]], dtype=np.float32)
    stray = np.array([[[0.2, 0.4, 0.0], [0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.0, 0.0, 0.0]]], dtype=np.float32)
    layers = flare_layers(direct, stray)
    assert list(layers) == list(FLARE_LAYERS)
    assert np.allclose(layers["flare.irradiance"], [[0.2, 0.0, 0.5, 0.0]])
    assert np.allclose(layers["flare.ratio"], [[0.1, 0.0, MAX_RATIO, 0.0]])
    assert all(v.dtype == np.float32 and np.isfinite(v).all() for v in layers.values())


@pytest.mark.usefixtures("variant_llvm_ad_spectral")
def test_render_with_ghosts_writes_the_flare_layers(tmp_path, capsys):
    """A sun in the frame through the double Gauss: the EXR holds the image and the flare layers, named in
    its metadata; the ghosts put stray light on pixels away from the sun and the road, the ratio is 0 where
    no stray light arrives and finite everywhere, and the frame is brighter than the direct image by the
    flare's irradiance."""
    scene = tmp_path / "sun.xml"
    scene.write_text(SCENE)
    args = ["render", str(scene), "--lens", "double-gauss-50mm", "--spp", "16"]
    assert main([*args, "--ghosts", "-o", str(tmp_path / "flare.exr")]) == 0
    assert main([*args, "-o", str(tmp_path / "plain.exr")]) == 0
    channels, meta = read_exr(tmp_path / "flare.exr")
    plain, _ = read_exr(tmp_path / "plain.exr")
    flare, ratio = (channels[name] for name in FLARE_LAYERS)
    assert meta["flare"]["layers"] == list(FLARE_LAYERS), json.dumps(meta.get("flare"))
    assert meta["flare"]["method"].startswith("light-traced") and meta["flare"]["sources"] == ["area sun"]
    assert np.isfinite(ratio).all() and np.isfinite(flare).all() and (flare >= 0).all()
    assert ((ratio == 0) == (flare == 0)).all() and (flare > 0).mean() > 0.05
    assert meta["flare"]["starburst"]["blades"] == 0 and 0 <= meta["flare"]["starburst"]["wings"] < 0.1
    mean = np.mean([channels[c] for c in "RGB"], axis=0)
    lossless = np.mean([plain[c] for c in "RGB"], axis=0)  # without --ghosts: lossless surfaces (fresnel off)
    # the frame's light: the direct image's through surfaces of Fresnel's transmittance (bare glass: 0.59 of the
    # lossless lens's at normal incidence; the sun is 10 deg off axis), the starburst only moving it, and the
    # ghosts' (a few % of it)
    lens = Lens.load("double-gauss-50mm")
    n = lens.indices(lens.primary_wavelength)
    transmittance = np.prod([coating.fresnel(a, b, 1.0).transmittance for a, b in itertools.pairwise(n) if a != b])
    assert 0.96 < mean.sum() / (transmittance * lossless.sum()) < 1.1
    assert mean.sum() - flare.sum() < transmittance * lossless.sum()
    assert "flare.irradiance" not in plain


def test_ghosts_need_a_lens_camera(tmp_path, capsys):
    """--ghosts on a scene of `solas-mi scene` (a lens_sensor, solas-mi's loop) is refused in one line."""
    assert main(["scene", "solas-doublet", "-o", str(tmp_path / "s")]) == 0
    out = tmp_path / "o.exr"
    assert main(["render", str(tmp_path / "s" / "scene.xml"), "--ghosts", "--spp", "1", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--ghosts are traced through a lens camera" in err and err.count("\n") == 1, err
    assert not out.exists()


def double_gauss_stop(blades):
    lens = Lens.load("double-gauss-50mm")
    stop = next(s for s in lens.surfaces if s.stop)
    return dataclasses.replace(stop, blades=blades), working_f_number(lens)


def test_a_round_stop_s_kernel_is_the_airy_pattern():
    """The round stop's kernel at f/2, 550 nm, 2 µm pixels against the Airy pattern (2 J1(v)/v)², v = π r / (λN),
    integrated over the same pixels (40² points each): the light of the centre pixel and of the central 3², 7²
    squares, as fractions of the central 21², within 0.5 %."""
    from scipy.special import j1

    stop, f_number = double_gauss_stop(0)
    pitch, lam_n = 2.0, 0.55 * f_number
    kernel = iris_kernel(stop, f_number, 550.0, pitch)
    c = kernel.shape[0] // 2
    g = (np.arange(-420, 420) + 0.5) * pitch / 40
    x, y = np.meshgrid(g, g)
    v = math.pi * np.hypot(x, y) / lam_n
    airy = (2.0 * j1(v) / v) ** 2

    def square(m):
        return airy[(np.abs(x) < (m + 0.5) * pitch) & (np.abs(y) < (m + 0.5) * pitch)].sum()

    for m in (0, 1, 3):
        mine = kernel[c - m : c + m + 1, c - m : c + m + 1].sum() / kernel[c - 10 : c + 11, c - 10 : c + 11].sum()
        assert mine == pytest.approx(square(m) / square(10), rel=0.005), m


@pytest.mark.parametrize("blades, spike", [(6, "rows"), (5, "columns")])
def test_an_iris_s_kernel_has_its_spikes_along_its_edge_normals(blades, spike):
    """A regular N-gon with a corner on +x diffracts along its edges' normals: a hexagon's spikes include ±y (the
    rows through the centre's column), a pentagon's 2N = 10 include ±x; across them, 100× less light."""
    stop, f_number = double_gauss_stop(blades)
    kernel = iris_kernel(stop, f_number, 550.0, 2.0)
    c = kernel.shape[0] // 2
    along_y, along_x = kernel[c + 20, c] + kernel[c - 20, c], kernel[c, c + 20] + kernel[c, c - 20]
    ratio = along_y / along_x if spike == "rows" else along_x / along_y
    assert ratio > 100


def test_spread_keeps_the_light():
    """A point away from the edges: what it keeps and what the wings bring add up to its light (1e-9), the
    wings bring nothing to its own pixel, and a kernel of one pixel spreads nothing."""
    stop, f_number = double_gauss_stop(6)
    kernel = iris_kernel(stop, f_number, 550.0, 5.0)
    image = np.zeros((150, 160, 3))
    image[75, 80] = [1.0, 2.0, 3.0]
    kept, brought = spread(image, kernel)
    assert (kept + brought).sum(axis=(0, 1)) == pytest.approx([1.0, 2.0, 3.0], rel=1e-9)
    assert brought[75, 80].max() < 1e-12 and (brought >= 0).all()
    assert np.array_equal(sum(spread(image, np.ones((1, 1)))), image)
