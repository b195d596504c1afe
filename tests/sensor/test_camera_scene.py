"""`solas-mi camera SCENE.xml`: a Mitsuba scene file rendered over the sensor's exposure windows, then captured — an
LED named with --pwm-emitter is dark in a short exposure that falls in its off-time and as bright as the steady LED in
one within its on-time; a camera given --camera-motion gives the RAW of the Python API's `render_in_time` with the
end pose its velocity reaches over the frame (leaning a bar by speed × line time × rows); bad values are named."""

import math

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.imageio import read_exr
from solas_mi.sensor.capture import capture
from solas_mi.sensor.files import load_sensor
from solas_mi.sensor.rendered import INDEX, render_in_time
from solas_mi.sensor.scene_input import MOTION_FORM, PWM_FORM, TURN_UNIT
from solas_mi.sensor.timing import Shutter

DISTANCE, FOV_DEG = 5.0, 40.0  # the camera 5 m in front of the plane z = 0, its horizontal field 40°
ROWS, COLS, LINE_S, LINES = 48, 64, 30e-6, 8  # a rolling shutter's exposure: 8 line times
SENSOR = "[sensor]\nread_noise_e = 3.0\nfull_well_e = 20000\ngain_dn_per_e = 0.2\n"
ROLLING = SENSOR + f'\n[sensor.shutter]\nmode = "rolling"\nline_time_s = {LINE_S}\ntime_samples = {LINES + ROWS - 1}\n'


def scene_xml(width_m: float) -> str:
    """A perspective camera at z = 5 looking down −z at an emitting rectangle "led" of `width_m` × 20 m."""
    return f"""<scene version="3.0.0">
    <integrator type="direct"/>
    <sensor type="perspective">
        <float name="fov" value="{FOV_DEG}"/>
        <transform name="to_world"><lookat origin="0, 0, {DISTANCE}" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{COLS}"/><integer name="height" value="{ROWS}"/>
            <rfilter type="box"/></film>
        <sampler type="stratified"><integer name="sample_count" value="16"/></sampler>
    </sensor>
    <shape type="rectangle" id="led">
        <transform name="to_world"><scale x="{width_m / 2}" y="10"/></transform>
        <emitter type="area"><rgb name="radiance" value="1.0"/></emitter>
    </shape>
</scene>
"""


@pytest.fixture
def files(tmp_path):
    (tmp_path / "wall.xml").write_text(scene_xml(40.0))  # the LED fills the view
    bar_m = 4 * 2.0 * DISTANCE * math.tan(math.radians(FOV_DEG / 2)) / COLS  # 4 pixels wide
    (tmp_path / "bar.xml").write_text(scene_xml(bar_m))
    (tmp_path / "blinding.xml").write_text(scene_xml(40.0).replace('value="1.0"', 'value="1e39"'))  # inf in float32
    (tmp_path / "global.toml").write_text(SENSOR)
    (tmp_path / "rolling.toml").write_text(ROLLING)
    return tmp_path


def camera(folder, scene, toml, exposure_ms, *extra, name="raw.exr"):
    argv = ["camera", str(folder / scene), "--sensor-model", str(folder / toml), "--exposure-ms", str(exposure_ms)]
    assert main([*argv, "--spp", "4", *extra, "-o", str(folder / name)]) == 0
    return read_exr(folder / name)


def test_an_led_is_dark_in_its_off_time_and_steady_in_its_on_time(files):
    """100 Hz at 10 %: on for the first 1 ms of each 10 ms at phase 0, so over the whole 0.5 ms exposure (the RAW of
    the steady LED, same seeds); at phase 0.5 on from 5 ms, so off over it (the black level and its noise only)."""
    steady, _ = camera(files, "wall.xml", "global.toml", 0.5)
    on, meta = camera(files, "wall.xml", "global.toml", 0.5, "--pwm-emitter", "led,100,0.1,0")
    off, _ = camera(files, "wall.xml", "global.toml", 0.5, "--pwm-emitter", "led,100,0.1,0.5")
    black = load_sensor(files / "global.toml").black_level_dn
    assert np.abs(on["RAW"].astype(np.float64) - steady["RAW"]).max() <= 1.0
    assert abs(off["RAW"].mean() - black) < 0.5 < 1000.0 < steady["RAW"].mean() - black  # read noise 0.6 DN
    windows = meta["rendered"]["exposure_windows"]
    assert windows["pwm_emitters"] == {"led": {"frequency_hz": 100.0, "duty_cycle": 0.1, "phase": 0.0}}
    assert windows["shutter"]["mode"] == "global" and meta["rendered"]["scene"].endswith("wall.xml")


def test_an_emitter_without_an_id_is_named_by_its_index(files, capsys):
    """Public scenes often give an emitter no id (Mitsuba's Cornell box): "#0" names the scene's first emitter, and
    a name that matches none is refused with the scene's emitters listed by index."""
    (files / "anonymous.xml").write_text(scene_xml(40.0).replace(' id="led"', ""))
    off, meta = camera(files, "anonymous.xml", "global.toml", 0.5, "--pwm-emitter", f"{INDEX}0,100,0.1,0.5")
    assert abs(off["RAW"].mean() - load_sensor(files / "global.toml").black_level_dn) < 0.5
    assert list(meta["rendered"]["exposure_windows"]["pwm_emitters"]) == [f"{INDEX}0"]
    argv = ["camera", str(files / "anonymous.xml"), "--sensor-model", str(files / "global.toml"), "--exposure-ms", "1"]
    assert main([*argv, "--pwm-emitter", "led,100,0.1", "-o", str(files / "out.exr")]) == 2
    assert f"{INDEX}0 (AreaLight)" in capsys.readouterr().err


def test_a_lens_cameras_scene_is_read_as_radiance_through_its_lens(files, variant_llvm_ad_spectral):
    """A scene whose camera is a `lens_camera`: its render is radiance, read through the camera equation at the
    lens's f-number as `render --lens` states it (`user_scene.unit_f_number`), the lens named."""
    from solas_mi.render.user_scene import load, unit_f_number

    text = scene_xml(40.0).replace('<float name="fov" value="40.0"/>', "")
    lens = (
        '<sensor type="lens_camera"><string name="lens" value="solas-doublet"/><float name="focus_distance" value="5"/>'
    )
    (files / "lens.xml").write_text(text.replace('<sensor type="perspective">', lens))
    _, meta = camera(files, "lens.xml", "global.toml", 0.5, "--pwm-emitter", "led,100,0.1")
    assert meta["f_number"] == pytest.approx(unit_f_number(load(str(files / "lens.xml")).sensors()[0]))
    assert meta["f_number_source"] == "input metadata (lens solas-doublet)"


def test_set_overrides_a_default_of_the_scene(files):
    """--set NAME=VALUE as `render` takes it: a public scene's film size from a <default> ($res in Mitsuba's)."""
    text = scene_xml(40.0).replace('<scene version="3.0.0">', '<scene version="3.0.0">\n<default name="w" value="64"/>')
    (files / "defaults.xml").write_text(text.replace(f'name="width" value="{COLS}"', 'name="width" value="$w"'))
    raw, _ = camera(files, "defaults.xml", "global.toml", 0.5, "--set", "w=24")
    assert raw["RAW"].shape == (ROWS, 24)


def test_a_moving_camera_gives_the_python_apis_frame_and_leans_a_bar(files, variant_llvm_ad_spectral):
    """--camera-motion VX,0,0 for the frame's span (first row's start to last row's end): the RAW of `render_in_time`
    with the camera moved VX × span; its bar leans by the image's speed × line time × rows."""
    mi = variant_llvm_ad_spectral
    exposure = LINES * LINE_S
    span = exposure + (ROWS - 1) * LINE_S
    speed_m_s = 1.0 / span  # 1 m over the frame: the image moves f_px × 1 m / 5 m = 17.6 px
    raw, meta = camera(files, "bar.xml", "rolling.toml", exposure * 1e3, "--camera-motion", f"{speed_m_s!r},0,0")
    scene = mi.load_file(str(files / "bar.xml"))
    end = np.array(scene.sensors()[0].world_transform().matrix).reshape(4, 4)
    end[0, 3] += 1.0
    model = load_sensor(files / "rolling.toml")
    image = render_in_time(scene, 4, Shutter("rolling", LINE_S, time_samples=LINES + ROWS - 1), exposure, None, end)
    assert np.array_equal(raw["RAW"], capture(model, image.image[..., :3].astype(np.float64), exposure, 0))
    assert np.allclose(meta["rendered"]["exposure_windows"]["to_world_end"], end, atol=1e-6)
    assert meta["rendered"]["exposure_windows"]["camera_motion"]["velocity"] == [speed_m_s, 0.0, 0.0]

    signal = raw["RAW"].astype(np.float64) - model.black_level_dn
    x = np.arange(COLS) + 0.5
    slope = np.polyfit(np.arange(ROWS), (signal * x).sum(axis=1) / signal.sum(axis=1), 1)[0]
    f_px = COLS / 2 / math.tan(math.radians(FOV_DEG / 2))
    image_speed = f_px * 1.0 / DISTANCE / span  # px/s, leftwards: the camera moves right
    assert slope * ROWS == pytest.approx(-image_speed * LINE_S * ROWS, abs=0.5)


def test_a_turning_camera_is_the_turn_its_angular_velocity_reaches(files, variant_llvm_ad_spectral):
    """WY deg/s about the world's y through the camera: its end pose is its start turned by WY × span about y."""
    span = 0.5e-3
    _, meta = camera(files, "wall.xml", "global.toml", span * 1e3, "--camera-motion", f"0,0,0,0,{30 / span!r},0")
    end = np.array(meta["rendered"]["exposure_windows"]["to_world_end"])
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    start = np.diag([-1.0, 1.0, -1.0])  # look_at along −z with y up: the camera's x points along the world's −x
    assert np.allclose(end[:3, :3], np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ start, atol=1e-6)
    assert np.allclose(end[:3, 3], [0.0, 0.0, DISTANCE], atol=1e-6)


def test_the_help_names_the_forms_and_units():
    from solas_mi.cli import build_parser

    text = " ".join(build_parser()._subparsers._group_actions[0].choices["camera"].format_help().split())
    assert PWM_FORM in text and MOTION_FORM in text and TURN_UNIT in text and f"{INDEX}N" in text


@pytest.mark.parametrize(
    "scene, extra, word",
    [
        ("wall.xml", ["--pwm-emitter", "led,100"], "--pwm-emitter"),
        ("wall.xml", ["--pwm-emitter", "led,100,1.5"], "duty_cycle"),
        ("wall.xml", ["--pwm-emitter", "nowhere,100,0.1"], "nowhere"),
        ("wall.xml", ["--camera-motion", "1,2"], "--camera-motion"),
        ("wall.xml", ["--camera-motion", "0,0,0,0,1e9,0"], "turns"),
        ("wall.xml", ["--flicker", "0,0,4,4,90,0.1"], "is a scene: its emitters take --pwm-emitter"),
        ("wall.xml", ["--spp", "0"], "samples per pixel"),
        ("in.exr", ["--pwm-emitter", "led,100,0.1"], "--pwm-emitter"),
        ("in.exr", ["--spp", "0"], "--spp go(es) with a scene input"),  # 0 was dropped silently (falsy)
        ("blinding.xml", [], "NaN or infinite"),
    ],
    ids=[
        "form",
        "duty",
        "unknown emitter",
        "motion form",
        "turn",
        "flicker",
        "spp",
        "image input",
        "spp 0 of an image",
        "infinite light",
    ],
)
def test_bad_values_are_one_line_and_write_nothing(files, capsys, scene, extra, word):
    (files / "in.exr").write_bytes(b"")  # refused for its option before it is read
    argv = ["camera", str(files / scene), "--sensor-model", str(files / "global.toml"), "--exposure-ms", "0.5"]
    assert main([*argv, *extra, "-o", str(files / "out.exr")]) == 2
    err = capsys.readouterr().err.strip()
    assert word in err and len(err.splitlines()) == 1
    assert not (files / "out.exr").exists()


def test_auto_exposure_of_a_scene_is_refused(files, capsys):
    argv = ["camera", str(files / "wall.xml"), "--sensor-model", str(files / "global.toml"), "--exposure-ms", "auto"]
    assert main([*argv, "-o", str(files / "out.exr")]) == 2
    assert "auto" in capsys.readouterr().err
