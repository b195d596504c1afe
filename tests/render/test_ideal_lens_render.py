"""An ideal thin lens (`focal_length`) in the render stage: the lens camera traces it (a dot lands where
the thin-lens equation puts it), the mesh scene, which has no glass to build for it, refuses it by name."""

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics.focus import focused
from solas_mi.optics.tracer import object_points
from solas_mi.render.scene import lens_parts

F_MM = 20.0


@pytest.fixture
def ideal(tmp_path):
    """An ideal lens f = 20 mm stopped to 4 mm (f/5), focused at infinity, saved as TOML."""
    lens = Lens.from_dict(
        {
            "name": "ideal",
            "field_deg": 10.0,
            "wavelengths_nm": [531.0],
            "surface": [{"radius": 0.0, "thickness": F_MM, "diameter": 4.0, "stop": True, "focal_length": F_MM}],
        }
    )
    return lens.save(tmp_path / "ideal.toml")


def test_lens_camera_images_a_dot_where_the_thin_lens_equation_says(mi, ideal):
    """A 1 mm disc 10 m away at +2°, the camera focused there: the image centroid at −s'/s times the
    object point (1/s' = 1/f − 1/s), within 0.5 µm (every ray of an ideal lens meets there)."""
    distance, n, rows = 10.0, 64, 8000
    lens = focused(Lens.load(ideal), distance * 1e3)
    s = lens.object_distance
    magnification = -1.0 / (1.0 / F_MM - 1.0 / s) / s
    ox, oy = object_points(lens, np.array([[0.0, 2.0]]))[0]
    expected = magnification * np.array([ox, oy])
    row0 = int(round(rows / 2 - expected[1] * 1e3)) - n // 2
    T = mi.ScalarTransform4f
    film = {
        "type": "hdrfilm",
        "width": n,
        "height": rows,
        "pixel_format": "luminance",
        "rfilter": {"type": "box"},
        "crop_offset_y": row0,
        "crop_width": n,
        "crop_height": n,
    }
    sensor = {
        "type": "lens_camera",
        "lens": str(ideal),
        "pitch_um": 1.0,
        "response": "mono:531",
        "focus_distance": distance,
        "film": film,
    }
    disk = T().translate([ox * 1e-3, -oy * 1e-3, distance]).rotate([0, 1, 0], 180).scale(1e-3)
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path"},
            "sensor": sensor,
            "dot": {
                "type": "disk",
                "to_world": disk,
                "emitter": {"type": "area", "radiance": {"type": "uniform", "value": 1.0}},
            },
        }
    )
    image = np.array(mi.render(scene, spp=64, seed=1))[..., 0]
    assert image.sum() > 0
    w = image / image.sum()
    x = (np.arange(n) + 0.5 - n / 2) * 1e-3
    y = (rows / 2 - (row0 + np.arange(n) + 0.5)) * 1e-3
    centroid = np.array([(w.sum(axis=0) * x).sum(), (w.sum(axis=1) * y).sum()])
    assert np.all(np.abs(centroid - expected) < 0.5e-3), (centroid, expected)


def test_the_mesh_scene_refuses_an_ideal_lens_and_names_the_routes_that_trace_it(ideal):
    with pytest.raises(SolasError, match="surface 1 of lens ideal is an ideal thin lens .* the lens camera"):
        lens_parts(Lens.load(ideal))
