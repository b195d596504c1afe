"""A lens whose air gap closes before the rim (faces crossing at r = 15.6 mm inside 20 mm apertures) in the
`lens_camera`: the Dr.Jit tracer inside the sensor steps back where the second face comes first, so the
spot it renders is the Float64 tracer's, rays through the overlap included; the mesh scene refuses it."""

import numpy as np
import pytest

from solas_mi import Lens, SolasError, paraxial
from solas_mi.optics.spot import spot

PITCH_UM, W = 100.0, 96
LENS = """name = "crossing air gap"
wavelengths_nm = [531.0]
surface = [
  {radius = 60.0, thickness = 10.0, diameter = 40.0, material = "model:1.5", stop = true},
  {radius = -40.0, thickness = 0.5, diameter = 40.0},
  {radius = -35.0, thickness = 3.0, diameter = 40.0, material = "model:1.5"},
  {radius = -80.0, thickness = 73.4, diameter = 40.0},
]
"""


def test_lens_camera_renders_the_tracers_spot_through_crossing_faces(mi, tmp_path):
    """A disc of radius 400 m 100 km away on the axis, 0.32 mm on the film (f = 79.7 mm): the share of the
    light in the pixels within 0.5 … 3 mm of the centre within 0.01 of the Float64 tracer's spot (each ray
    spread over the disc's image) binned into the same pixels. The spot's rays reach r = 20 mm, 39 % of
    them beyond the crossing (f/2 with 1 mm RMS of spherical aberration)."""
    path = tmp_path / "gap.toml"
    path.write_text(LENS)
    lens = Lens.load(path)
    assert "surfaces 2 (surface 2) and 3 (surface 3) cross at r = 15.58 mm" in lens.overlaps[0]
    s = spot(lens, (0, 0), 531.0, "grid", 400)
    film = {"type": "hdrfilm", "width": W, "height": W, "pixel_format": "luminance", "rfilter": {"type": "box"}}
    sensor = {"type": "lens_camera", "lens": str(path), "pitch_um": PITCH_UM, "response": "mono:531", "film": film}
    tf = mi.ScalarTransform4f().translate([0, 0, 1e5]).rotate([0, 1, 0], 180).scale(400.0)
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path"},
            "sensor": sensor,
            "dot": {
                "type": "disk",
                "to_world": tf,
                "emitter": {"type": "area", "radiance": {"type": "uniform", "value": 1.0}},
            },
        }
    )
    image = np.array(mi.render(scene, spp=2048, seed=1))[..., 0]
    efl = paraxial(lens, 531.0).efl_mm
    rng = np.random.default_rng(1)  # the disc's image, radius f·R/D, uniform: 16 points about each ray
    a, t = np.sqrt(rng.random((16, 1))) * efl * 400.0 / 1e5 * 1e3, 2 * np.pi * rng.random((16, 1))
    x, y = (s.x_um + a * np.cos(t)).ravel(), (s.y_um + a * np.sin(t)).ravel()
    edges = (np.arange(W + 1) - W / 2) * PITCH_UM
    traced = np.histogram2d(y, x, bins=(edges, edges))[0] / len(x)  # the same pixels
    c = 0.5 * (edges[1:] + edges[:-1]) * 1e-3
    rho = np.hypot(*np.meshgrid(c, c))
    for radius in (0.5, 1.0, 2.0, 3.0):  # measured: within 0.0016 (0.63, 0.77, 0.91, 0.98 of the light)
        inside = rho < radius
        assert abs(image[inside].sum() / image.sum() - traced[inside].sum()) < 0.01, radius
    from solas_mi.render.scene import lens_parts

    with pytest.raises(
        SolasError,
        match=r"cannot be built as Mitsuba geometry: surfaces 2 \(surface 2\) and 3 "
        r"\(surface 3\) cross at .*the lens camera",
    ):
        lens_parts(lens)
