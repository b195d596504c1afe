"""A lens whose object is virtual (behind surface 1) in the render stage: the lens camera, which images the
scene in front of the lens, refuses it naming the virtual object unless a focus distance puts the object in
the scene; the mesh scene's refusal is in tests/optics/test_virtual_object.py."""

import pytest

from solas_mi import Lens


@pytest.fixture
def relay(tmp_path):
    """A biconvex N-BK7 singlet whose object lies 30 mm behind its front vertex, saved as TOML."""
    lens = Lens.from_dict(
        {
            "name": "relay",
            "wavelengths_nm": [531.0],
            "object": {"distance": -30.0},
            "surface": [
                {"radius": 40.0, "thickness": 6.0, "diameter": 12.0, "stop": True, "material": "N-BK7"},
                {"radius": -60.0, "thickness": 15.0, "diameter": 12.0},
            ],
        }
    )
    return lens.save(tmp_path / "relay.toml")


def _sensor(relay, **extra):
    film = {"type": "hdrfilm", "width": 8, "height": 8, "pixel_format": "luminance", "rfilter": {"type": "box"}}
    return {"type": "lens_camera", "lens": str(relay), "pitch_um": 5.0, "response": "mono:531", "film": film, **extra}


def test_the_lens_camera_refuses_a_virtual_object_and_says_to_focus(mi, relay):
    with pytest.raises(
        Exception,
        match=r"lens_camera: lens relay has a virtual object, 30 mm behind surface 1 "
        r"\(light arrives converging toward it\).* give focus_distance to focus it",
    ):
        mi.load_dict(_sensor(relay))
    focused = mi.load_dict(_sensor(relay, focus_distance=2.0))  # 2 m in front: a real object, imaged
    assert focused.lens.object_distance == pytest.approx(2000.0)
