"""Flare in renders (`render SCENE --lens LENS --ghosts`, `render.flare`): the frame is the direct image plus
the ghosts' stray light, with the flare label layers beside it, named in the metadata, never NaN."""

import itertools
import json

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.cli import main
from solas_mi.imageio import read_exr
from solas_mi.optics import coating
from solas_mi.render.flare import FLARE_LAYERS, MAX_RATIO, flare_layers

SCENE = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/></film>
    </sensor>
    <shape type="sphere">
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
    assert np.isfinite(ratio).all() and np.isfinite(flare).all() and (flare >= 0).all()
    assert ((ratio == 0) == (flare == 0)).all() and 0.05 < (flare > 0).mean() < 1.0
    mean = np.mean([channels[c] for c in "RGB"], axis=0)
    lossless = np.mean([plain[c] for c in "RGB"], axis=0)  # without --ghosts: lossless surfaces (fresnel off)
    # the frame less the flare: the direct image through surfaces of Fresnel's transmittance (bare glass: 0.59 of
    # the lossless lens's at normal incidence; the sun is 10 deg off axis)
    lens = Lens.load("double-gauss-50mm")
    n = lens.indices(lens.primary_wavelength)
    transmittance = np.prod([coating.fresnel(a, b, 1.0).transmittance for a, b in itertools.pairwise(n) if a != b])
    assert mean.sum() - flare.sum() == pytest.approx(transmittance * lossless.sum(), rel=0.04)
    assert "flare.irradiance" not in plain


def test_ghosts_need_a_lens_camera(tmp_path, capsys):
    """--ghosts on a scene of `solas-mi scene` (a lens_sensor, solas-mi's loop) is refused in one line."""
    assert main(["scene", "solas-doublet", "-o", str(tmp_path / "s")]) == 0
    out = tmp_path / "o.exr"
    assert main(["render", str(tmp_path / "s" / "scene.xml"), "--ghosts", "--spp", "1", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--ghosts are traced through a lens camera" in err and err.count("\n") == 1, err
    assert not out.exists()
