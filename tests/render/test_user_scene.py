"""A user's scene file prepared for rendering (`render.user_scene`), read by Mitsuba's own parser: a
default integrator where it has none (includes read), the perspective camera swapped for a lens_camera
at the same pose with the matching field, everything else as Mitsuba loads it."""

import math

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.optics.camera import camera_for
from solas_mi.optics.focus import focused
from solas_mi.optics.lens import Lens
from solas_mi.optics.pupil import chief_rays
from solas_mi.render.user_scene import load

VARIANT = "llvm_ad_spectral"
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


def _sensor(path, lens=None, params=None, notes=None, **options):
    return load(path, VARIANT, lens, params, notes, **options).sensors()[0]


def test_a_default_path_integrator_is_added(scene_file):
    scene = load(scene_file, VARIANT)
    assert str(scene.integrator()).startswith("PathIntegrator")
    assert str(scene.sensors()[0]).startswith("PerspectiveCamera")


def test_lens_camera_takes_the_pose_film_and_field(scene_file, doublet):
    sensor = _sensor(scene_file, doublet, focus_distance=2.0)
    assert type(sensor).__name__ == "LensCamera"
    assert sensor.lens.hash == focused(doublet, 2000.0).hash and sensor.focus_distance == 2.0
    # the ±2° field across 1280 px: the pitch of the convolution's default camera (`optics.camera`)
    assert sensor.pitch_um == pytest.approx(camera_for(doublet, (960, 1280), 2.0).pitch_um, rel=1e-9)
    matrix = np.array(sensor.world_transform().matrix).reshape(4, 4)
    assert matrix[:3, 3] == pytest.approx([0, 1, -5], abs=1e-6) and matrix[:3, 2] == pytest.approx([0, 0, 1], abs=1e-6)
    assert sensor.film().class_name() == "HDRFilm" and int(sensor.sampler().sample_count()) == 16


def test_explicit_pitch_and_fov_axis_y(tmp_path, doublet):
    path = tmp_path / "y.xml"
    path.write_text(
        SCENE.replace(
            '<float name="fov" value="4"/>', '<float name="fov" value="3"/><string name="fov_axis" value="y"/>'
        )
    )
    # the real chief ray of the 1.5° field in y lands at the film's top edge, 480 px above the centre
    height_mm = chief_rays(doublet, [[0.0, 1.5]], [doublet.primary_wavelength]).image_xy[0, 1]
    assert _sensor(path, doublet).pitch_um == pytest.approx(height_mm * 1e3 / 480, rel=1e-6)
    assert _sensor(path, doublet, pitch_um=3.0).pitch_um == 3.0


@pytest.mark.parametrize(
    "text, match",
    [
        ("<scene version='3.0.0'><shape type='sphere'/></scene>", "has no <sensor>"),
        ("<scene version='3.0.0'><sensor type='orthographic'/></scene>", "sensor is 'orthographic'"),
        ("<scene", "cannot read scene .*Parsing of XML file"),
    ],
)
def test_scenes_that_cannot_take_a_lens(tmp_path, doublet, text, match):
    path = tmp_path / "bad.xml"
    path.write_text(text)
    with pytest.raises(SolasError, match=match):
        load(path, VARIANT, doublet)


def test_a_perspective_without_fov_takes_mitsubas_default(tmp_path, doublet, mi):
    """Mitsuba's perspective without fov or focal_length (its default focal length): the lens camera's
    film edge meets the chief ray of the field Mitsuba gives it."""
    path = tmp_path / "nofov.xml"
    path.write_text(
        "<scene version='3.0.0'><sensor type='perspective'><film type='hdrfilm'>"
        "<integer name='width' value='64'/><integer name='height' value='48'/></film></sensor></scene>"
    )
    x_fov = float(mi.traverse(load(path, VARIANT).sensors()[0])["x_fov"][0])
    wide = Lens.load("double-gauss-50mm")
    edge_mm = chief_rays(wide, [[0.5 * x_fov, 0.0]], [wide.primary_wavelength]).image_xy[0, 0]
    assert _sensor(path, wide).pitch_um == pytest.approx(abs(edge_mm) * 1e3 / 32, rel=1e-6)


def test_missing_scene_file(tmp_path):
    with pytest.raises(SolasError, match="scene file .*none.xml. does not exist"):
        load(tmp_path / "none.xml", VARIANT)


def test_set_takes_what_mitsuba_takes(scene_file):
    """A parameter the scene uses, declared or not, is taken (as `mi.load_file` takes it); one it
    never uses is refused by name."""
    with pytest.raises(SolasError, match=r"unused parameters: \$nope=1"):
        load(scene_file, VARIANT, params={"nope": "1", "w": "64"})
    assert int(load(scene_file, VARIANT, params={"w": "64"}).sensors()[0].film().size()[0]) == 64


def test_spp_renders_a_scene_without_an_spp_default(tmp_path):
    """`render --spp` sets the samples of the render, not a <default> the scene may not have."""
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr

    path = tmp_path / "scene.xml"
    path.write_text(
        SCENE.replace('value="1280"', 'value="16"')
        .replace('value="960"', 'value="12"')
        .replace("</scene>", '<emitter type="constant"/></scene>')
    )
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
    assert (
        main(
            [
                "scene",
                "solas-doublet",
                "-o",
                str(tmp_path / "scene"),
                "--sensor",
                "16x12",
                "--response",
                f"table:{table}",
            ]
        )
        == 0
    )
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
    with pytest.raises(
        SolasError,
        match=r"the scene's camera sees ±15 deg along x and lens solas-doublet cannot image "
        r"that field .*narrow the camera's fov, or give --pitch-um",
    ):
        load(path, VARIANT, doublet)


INCLUDED = """<scene version="3.0.0">
    <default name="spp" value="8"/>
    <integrator type="path"><integer name="max_depth" value="$depth"/></integrator>
    <sensor type="thinlens" id="front">
        <float name="focus_distance" value="$focus"/><float name="aperture_radius" value="0.01"/>
        <float name="fov" value="3"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="$width"/><integer name="height" value="$height"/>
            <rfilter type="box"/></film>
        <sampler type="stratified"><integer name="sample_count" value="$spp"/></sampler>
    </sensor>
</scene>"""

MAIN = """<scene version="3.0.0">
    <default name="width" value="683"/><default name="height" value="512"/><default name="focus" value="1.7"/>
    <include filename="camera.xml"/>
    <shape type="rectangle"><transform name="to_world"><scale value="0.01"/></transform>
        <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>
</scene>"""


@pytest.fixture
def included(tmp_path):
    (tmp_path / "camera.xml").write_text(INCLUDED)
    (tmp_path / "main.xml").write_text(MAIN)
    return tmp_path / "main.xml"


def test_integrator_sensor_and_defaults_inside_includes(included, doublet):
    """The integrator and the thinlens camera in an include, a default ($spp) declared there and one
    ($depth) declared nowhere: the scene loads with its own integrator (none added), the lens camera
    keeps the sensor's id, sampler and rfilter, takes the thinlens's focus and says the aperture is unused."""
    scene = load(included, VARIANT, None, {"depth": 3})
    assert "max_depth = 3" in str(scene.integrator())
    notes = []
    sensor = _sensor(included, doublet, {"depth": 3, "spp": 16}, notes)
    assert type(sensor).__name__ == "LensCamera" and sensor.id() == "front"
    assert sensor.focus_distance == 1.7 and sensor.lens.hash == focused(doublet, 1700.0).hash
    assert int(sensor.sampler().sample_count()) == 16 and "StratifiedSampler" in str(sensor.sampler())
    assert "BoxFilter" in str(sensor.film())
    assert any("aperture_radius 0.01 is not used" in n for n in notes), notes


def test_set_film_size_keeps_the_framing(included, doublet):
    """--set width=320 --set height=240 on a 683x512 scene: the same field on fewer pixels (the film's
    width in mm, and so the framing, unchanged: scale 1.00), not a 2.13x zoom."""
    full = _sensor(included, doublet, {"depth": 3})
    small = _sensor(included, doublet, {"depth": 3, "width": 320, "height": 240})
    assert tuple(int(v) for v in small.film().size()) == (320, 240)
    assert small.pitch_um * 320 / (full.pitch_um * 683) == pytest.approx(1.0, abs=1e-6)


def test_world_unit_mm_and_focus_in_millimetres(included, doublet):
    """A scene in mm (--world-unit-mm 1): the thinlens's 1700 (mm) focuses the lens at 1.7 m."""
    sensor = _sensor(included, doublet, {"depth": 3, "focus": 1700}, world_unit_mm=1.0)
    assert sensor.world_unit_mm == 1.0 and sensor.lens.image_z == pytest.approx(focused(doublet, 1700.0).image_z)


def test_focus_auto_is_the_depth_at_the_image_centre(included, doublet):
    """The emitting square at the origin, the camera at z = 5 (surface 1 at the camera's origin)."""
    notes = []
    sensor = _sensor(included, doublet, {"depth": 3}, notes, focus_distance="auto")
    assert sensor.focus_distance == pytest.approx(5.0, rel=1e-5)
    assert sensor.lens.image_z == pytest.approx(focused(doublet, 5000.0).image_z, rel=1e-6)
    assert any("auto" in n for n in notes)


def test_to_world_moved_by_traverse_renders_as_a_reload(included, doublet, mi):
    """A camera moved through `mi.traverse` (no reload) renders the image of a scene loaded at the new pose."""
    small = {"depth": 3, "width": 24, "height": 16}
    scene = load(included, VARIANT, doublet, small, pitch_um=20.0)
    moved = mi.ScalarTransform4f().look_at([0.01, 0.005, 5], [0.01, 0.005, 0], [0, 1, 0])
    params = mi.traverse(scene)
    params["sensor.to_world" if "sensor.to_world" in params else "front.to_world"] = moved
    params.update()
    shifted = np.array(mi.render(scene, spp=16, seed=3))
    (included.parent / "moved.xml").write_text(
        INCLUDED.replace('origin="0, 0, 5" target="0, 0, 0"', 'origin="0.01, 0.005, 5" target="0.01, 0.005, 0"')
    )
    (included.parent / "main2.xml").write_text(MAIN.replace("camera.xml", "moved.xml"))
    reloaded = np.array(
        mi.render(load(included.parent / "main2.xml", VARIANT, doublet, small, pitch_um=20.0), spp=16, seed=3)
    )
    original = np.array(mi.render(load(included, VARIANT, doublet, small, pitch_um=20.0), spp=16, seed=3))
    assert np.abs(shifted - reloaded).max() < 1e-4
    assert np.abs(shifted - original).max() > 0.1


def test_render_metadata_holds_pitch_focus_and_unit(included, tmp_path, doublet):
    """Also the f-number of the render's unit (what `solas-mi camera` reads it through): a lossless lens's
    on-axis irradiance per unit radiance, π sin²θ' over the exit pupil (the cos⁴θ / d² integral over a
    disc), so N = 1 / (2 sin θ'), θ' from the focused lens's paraxial exit pupil."""
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr
    from solas_mi.optics.paraxial import paraxial

    out = tmp_path / "out.exr"
    assert (
        main(
            [
                "render",
                str(included),
                "--lens",
                "solas-doublet",
                "--set",
                "depth=2",
                "--set",
                "focus=170",
                "--set",
                "width=16",
                "--set",
                "height=12",
                "--spp",
                "1",
                "--pitch-um",
                "40",
                "--world-unit-mm",
                "10",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    meta = read_exr(out)[1]
    assert meta["pitch_um"] == 40.0 and meta["focus_distance"] == 170.0 and meta["world_unit_mm"] == 10.0
    lens = focused(doublet, 1700.0)
    p = paraxial(lens, lens.primary_wavelength)
    half_angle = math.atan(0.5 * p.exit_pupil_diameter_mm / abs(lens.image_z - p.exit_pupil_z_mm))
    assert meta["f_number"] == pytest.approx(1.0 / (2.0 * math.sin(half_angle)), rel=1e-3)


def test_render_metadata_of_a_lens_focused_at_infinity_is_strict_json(included, tmp_path):
    """--focus-distance inf: the EXR header said "focus_distance": Infinity, which no JSON reader but
    Python's accepts; it says "inf", and our reader gives back the infinite distance."""
    from strict_json import exr_meta

    from solas_mi.cli import main
    from solas_mi.imageio import read_exr

    out = tmp_path / "out.exr"
    assert (
        main(
            [
                "render",
                str(included),
                "--lens",
                "solas-doublet",
                "--set",
                "depth=2",
                "--set",
                "width=16",
                "--set",
                "height=12",
                "--spp",
                "1",
                "--focus-distance",
                "inf",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    assert exr_meta(out)["focus_distance"] == "inf"
    assert float(read_exr(out)[1]["focus_distance"]) == math.inf


def test_a_lens_as_built_is_refused_for_itself_not_for_the_scene_s_field(tmp_path):
    """A lens with a toroid (or a coordinate break) cannot be rendered at any field; the film's default pitch once
    reported it as "cannot image that field ... narrow the camera's fov", advice that cannot help. The refusal
    names the surface and says nothing of the field."""
    from dataclasses import replace

    from solas_mi.optics.shapes import KINDS
    from solas_mi.render.user_scene import default_pitch_um

    lens = Lens.load("cooke-triplet")
    toroid = KINDS["toroid"].function(radius=lens.surfaces[0].radius, conic=0.0, terms_y=(), radius_rotation=0.0)
    as_built = replace(lens, surfaces=(replace(lens.surfaces[0], form=toroid), *lens.surfaces[1:]))
    with pytest.raises(SolasError, match=r"surface 1 \(surface 1\) is a toroid") as refused:
        default_pitch_um(as_built, 5.0, "x", 32, 24)
    assert "fov" not in str(refused.value) and "field" not in str(refused.value)
