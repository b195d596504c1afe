"""The lens camera with a coated lens (`fresnel` "transmit"): each refraction weighs its ray by the
surface's coating, looked up in the tracer's table inside the render's kernel."""

import numpy as np

from solas_mi import Lens
from solas_mi.optics import coating


def test_a_coated_lens_camera_dims_by_its_coatings(mi, doublet_spec, tmp_path):
    """The centre of a white scene through the doublet, MgF2 quarter waves on its air faces: the ratio to
    the lossless render is the product of each crossing's normal-incidence transmittance (coated faces by
    the transfer matrix, the cemented one by Fresnel) within 0.5 %, and above the bare lens's."""
    for k in (0, 2):
        doublet_spec["surface"][k]["coating"] = {"kind": "quarter_wave", "material": "MGF2", "design_nm": 531.0}
    lens = Lens.from_dict(doublet_spec)
    path = str(lens.save(tmp_path / "coated.toml"))
    means = {}
    for name, fresnel in (("off", "off"), ("coated", "transmit")):
        film = {"type": "hdrfilm", "width": 4, "height": 4, "pixel_format": "luminance", "rfilter": {"type": "box"}}
        sensor = {
            "type": "lens_camera",
            "lens": path,
            "pitch_um": 2.0,
            "response": "mono:531",
            "film": film,
            "fresnel": fresnel,
        }
        tf = mi.ScalarTransform4f().translate([1e3, 0, 1e6]).rotate([0, 1, 0], 180).scale(1e3)
        scene = mi.load_dict(
            {
                "type": "scene",
                "integrator": {"type": "path"},
                "sensor": sensor,
                "plane": {
                    "type": "rectangle",
                    "to_world": tf,
                    "emitter": {"type": "area", "radiance": {"type": "uniform", "value": 1.0}},
                },
            }
        )
        means[name] = float(np.array(mi.render(scene, spp=4096, seed=1)).mean())
    n = lens.indices(531.0)
    crossings = [(s, a, b) for s, a, b in zip(lens.surfaces, n[:-1], n[1:]) if a != b]
    expected = np.prod(
        [
            (s.coating.power(a, b, 531.0, 1.0) if s.coating else coating.fresnel(a, b, 1.0)).transmittance
            for s, a, b in crossings
        ]
    )
    bare = np.prod([coating.fresnel(a, b, 1.0).transmittance for _, a, b in crossings])
    ratio = means["coated"] / means["off"]
    assert abs(ratio / expected - 1) < 0.005 and ratio > bare + 0.05, (ratio, expected, bare)
