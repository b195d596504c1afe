"""A user's scene file prepared for rendering (`render.user_scene`): a default integrator, and the
perspective camera swapped for a lens_camera at the same pose with the matching field."""
import xml.etree.ElementTree as ET

import pytest

from solas_mi.errors import SolasError
from solas_mi.optics.camera import camera_for
from solas_mi.optics.pupil import chief_rays
from solas_mi.render.user_scene import scene_text

SCENE = """<scene version="3.0.0">
    <default name="w" value="1280"/>
    <sensor type="perspective">
        <float name="fov" value="4"/>
        <transform name="to_world"><lookat origin="0, 1, -5" target="0, 1, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="$w"/><integer name="height" value="960"/></film>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    </sensor>
    <shape type="sphere"/>
</scene>"""


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "scene.xml"
    path.write_text(SCENE)
    return path


def test_a_default_path_integrator_is_added(scene_file):
    root = ET.fromstring(scene_text(scene_file))
    assert root.find("integrator").get("type") == "path"
    assert root.find("sensor").get("type") == "perspective"


def test_lens_camera_takes_the_pose_film_and_field(scene_file, doublet):
    root = ET.fromstring(scene_text(scene_file, doublet, focus_distance=2.0))
    sensor = root.find("sensor")
    assert sensor.get("type") == "lens_camera"
    values = {c.get("name"): c.get("value") for c in sensor if c.get("name")}
    assert values["lens"] == doublet.source and values["focus_distance"] == "2.0"
    # the ±2° field across 1280 px: the pitch of the convolution's default camera (`optics.camera`)
    assert float(values["pitch_um"]) == pytest.approx(camera_for(doublet, (960, 1280), 2.0).pitch_um, rel=1e-9)
    assert sensor.find("transform/lookat").get("origin") == "0, 1, -5"
    assert sensor.find("film").get("type") == "hdrfilm" and sensor.find("sampler") is not None


def test_explicit_pitch_and_fov_axis_y(tmp_path, doublet):
    path = tmp_path / "y.xml"
    path.write_text(SCENE.replace('<float name="fov" value="4"/>',
                                  '<float name="fov" value="3"/><string name="fov_axis" value="y"/>'))
    values = {c.get("name"): c.get("value") for c in ET.fromstring(scene_text(path, doublet)).find("sensor")}
    # the real chief ray of the 1.5° field in y lands at the film's top edge, 480 px above the centre
    height_mm = chief_rays(doublet, [[0.0, 1.5]], [doublet.primary_wavelength]).image_xy[0, 1]
    assert float(values["pitch_um"]) == pytest.approx(height_mm * 1e3 / 480, rel=1e-9)
    values = {c.get("name"): c.get("value") for c in
              ET.fromstring(scene_text(path, doublet, pitch_um=3.0)).find("sensor")}
    assert values["pitch_um"] == "3.0"


@pytest.mark.parametrize("text, match", [
    ("<scene version='3.0.0'><shape type='sphere'/></scene>", "has no <sensor>"),
    ("<scene version='3.0.0'><sensor type='orthographic'/></scene>", "sensor is 'orthographic'"),
    ("<scene version='3.0.0'><sensor type='perspective'/></scene>", "neither fov nor focal_length"),
    ("<scene", "not valid XML"),
])
def test_scenes_that_cannot_take_a_lens(tmp_path, doublet, text, match):
    path = tmp_path / "bad.xml"
    path.write_text(text)
    with pytest.raises(SolasError, match=match):
        scene_text(path, doublet)


def test_missing_scene_file(tmp_path):
    with pytest.raises(SolasError, match="no such scene file"):
        scene_text(tmp_path / "none.xml")


def test_set_names_only_the_scenes_defaults(scene_file):
    from solas_mi.render.user_scene import load

    with pytest.raises(SolasError, match=r"has no <default> named nope, spp; its defaults: w"):
        load(scene_file, "scalar_spectral", params={"nope": "1", "spp": "4", "w": "64"})


def test_spp_renders_a_scene_without_an_spp_default(tmp_path):
    """`render --spp` sets the samples of the render, not a <default> the scene may not have."""
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr

    path = tmp_path / "scene.xml"
    path.write_text(SCENE.replace('value="1280"', 'value="16"').replace('value="960"', 'value="12"')
                    .replace("</scene>", '<emitter type="constant"/></scene>'))
    assert main(["render", str(path), "--spp", "2", "-o", str(tmp_path / "out.exr")]) == 0
    channels, _ = read_exr(tmp_path / "out.exr")
    assert all(c.shape == (12, 16) and c.mean() > 0 for c in channels.values())


def test_a_response_table_travels_with_the_scene(tmp_path, monkeypatch):
    """`solas-mi scene --response table:F.csv` copies the table beside the scene (a header line is
    allowed), so the scene renders from any working folder and gives the table's white balance."""
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr

    table = tmp_path / "camera.csv"
    table.write_text("# a camera\nwavelength_nm,r,g,b\n" + "".join(f"{w},1,1,1\n" for w in range(400, 701, 50)))
    assert main(["scene", "solas-doublet", "-o", str(tmp_path / "scene"), "--sensor", "16x12",
                 "--response", f"table:{table}"]) == 0
    assert (tmp_path / "scene" / "camera.csv").read_text() == table.read_text()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    table.unlink()
    assert main(["render", str(tmp_path / "scene" / "scene.xml"), "--spp", "1", "-o", "out.exr"]) == 0
    assert all(c.shape == (12, 16) for c in read_exr(elsewhere / "out.exr")[0].values())


def test_a_camera_wider_than_the_lens_is_named(tmp_path, doublet):
    path = tmp_path / "wide.xml"
    path.write_text(SCENE.replace('name="fov" value="4"', 'name="fov" value="30"'))
    with pytest.raises(SolasError, match=r"the scene's camera sees ±15 deg along x and lens solas-doublet cannot image "
                                         r"that field .*narrow the camera's fov, or give --pitch-um"):
        scene_text(path, doublet)
