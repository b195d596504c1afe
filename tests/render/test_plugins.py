"""The Mitsuba plugins (`plugins/`): the defaults their docstrings document, what they expose to
`mi.traverse`, and their parameter checks."""

import math

import numpy as np
import pytest

from solas_mi.optics.camera import pinhole_focal_mm
from solas_mi.optics.pupil import chief_rays


@pytest.fixture
def plugins(mi):
    """Each plugin with its default parameters (the object's image from Python: a 2×4 grey 0.5)."""
    image = mi.TensorXf(np.full((2, 4), 0.5, dtype=np.float32))
    return {
        "lens_sensor": mi.load_dict({"type": "lens_sensor"}),
        "sellmeier_dielectric": mi.load_dict({"type": "sellmeier_dielectric"}),
        "image_object": mi.load_dict({"type": "image_object", "image": image}),
    }


def test_lens_sensor_defaults(plugins, doublet):
    sensor = plugins["lens_sensor"]
    # no pitch_um: the film's 768 px width spans the field, where the real chief ray of ±2° lands
    edge = chief_rays(doublet, [[doublet.field_deg, 0.0]], [doublet.primary_wavelength]).image_xy[0, 0]
    assert sensor.lens.name == doublet.name and sensor.pitch_mm * 768 / 2 == pytest.approx(edge, rel=1e-9)
    assert sensor.focal_mm == pytest.approx(pinhole_focal_mm(doublet, doublet.field_deg))
    assert sensor.response.channels == ("R", "G", "B") and sensor.response.lo_nm.tolist() == [656.0, 531.0, 486.0]
    assert (sensor.width, sensor.height) == (768, 576) and sensor.sampler().sample_count() == 4


def test_sellmeier_dielectric_defaults(plugins):
    bsdf = plugins["sellmeier_dielectric"]
    assert (bsdf.int_glass.name, bsdf.ext_glass.name, bsdf.fresnel) == ("AIR", "AIR", "transmit")


def test_image_object_defaults(plugins):
    emitter = plugins["image_object"]
    assert emitter.fov_deg == 2.0 and emitter.boundary == "edge" and math.isinf(emitter.distance)
    # grey 0.5 as Mitsuba upsamples it: the flat spectrum 0.5 (coefficients 0, 0, 0 of 0.5 × s, s = 1); scale 1
    assert (emitter.width, emitter.height) == (4, 2) and emitter.spectrum == "srgb"
    assert np.allclose(np.asarray(emitter.texel_scale), 1.0) and np.allclose(np.asarray(emitter.texels), 0.0)


def test_plugins_expose_their_documented_parameters(mi, plugins):
    keys = {name: {k.split(".", 1)[-1] for k in mi.traverse(p).keys()} for name, p in plugins.items()}  # noqa: SIM118 -- SceneParameters
    assert keys["image_object"] == {"scale"} and keys["sellmeier_dielectric"] == set()
    assert {"pitch_um", "fov_deg"} <= keys["lens_sensor"]


@pytest.mark.parametrize(
    "plugin, message",
    [
        ({"type": "sellmeier_dielectric", "fresnel": "ghost"}, "fresnel 'ghost' must be one of transmit, sample, off"),
        ({"type": "image_object", "boundary": "wrap"}, "boundary 'wrap' must be one of edge, reflect, zero"),
        ({"type": "lens_sensor", "pitch_um": -1.0}, "lens_sensor: pitch_um -1.0 must be a positive number \\(µm\\)"),
    ],
)
def test_bad_parameters_are_named(mi, plugin, message):
    with pytest.raises(RuntimeError, match=message):
        mi.load_dict(plugin)


@pytest.mark.parametrize(
    "lens, film", [("solas-doublet", (64, 48)), ("cooke-triplet", (40, 30)), ("nikkor-fisheye", (64, 64))]
)
def test_lens_camera_without_pitch_spans_the_lens_s_field(mi, lens, film):
    """`lens_camera` loaded from Python without `pitch_um` took 5 µm, silently a ±0.9° crop of the scene
    (the doublet's 768 px): as Mitsuba's cameras take the film's size and a field, the film's width now
    spans the lens's field, where its real chief ray lands (a fisheye: its image diameter), and
    `to_string` says the pitch was derived; a lens that states neither is refused naming pitch_um."""
    from solas_mi import Lens

    camera = mi.load_dict(
        {"type": "lens_camera", "lens": lens, "film": {"type": "hdrfilm", "width": film[0], "height": film[1]}}
    )
    optics = Lens.load(lens)
    if optics.field_type.pinhole:
        edge = chief_rays(optics, [[optics.field_deg, 0.0]], [optics.primary_wavelength]).image_xy[0, 0]
    else:
        edge = optics.image_diameter / 2
    assert camera.pitch_mm * film[0] / 2 == pytest.approx(edge, rel=1e-9)
    assert f"({camera.pitch_note})" in str(camera) and camera.pitch_note.startswith("derived: the film's")
    given = mi.load_dict({"type": "lens_camera", "lens": lens, "pitch_um": 7.0})
    assert given.pitch_um == 7.0 and given.pitch_note == "given"


def test_lens_camera_of_a_lens_without_field_needs_a_pitch(mi, tmp_path):
    from dataclasses import replace

    from solas_mi import Lens

    path = replace(Lens.load("solas-doublet"), field_deg=0.0).save(tmp_path / "nofield.toml")
    with pytest.raises(
        RuntimeError,
        match=r"lens_camera: no pitch_um given, and lens solas-doublet sets none "
        r"\(field of view 0(\.0)? deg .*\); give pitch_um",
    ):
        mi.load_dict({"type": "lens_camera", "lens": str(path)})
    assert mi.load_dict({"type": "lens_camera", "lens": str(path), "pitch_um": 5.0}).pitch_um == 5.0
