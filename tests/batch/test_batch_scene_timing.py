"""`batch render` of a scene file with a camera and --pwm-emitter / --camera-motion: the scene item rendered through
the lens over the camera's exposure windows (its sensor's shutter, --exposure-ms), its PWM light dark in a phase off
over the exposure and lit in one on, recorded in the outputs and the batch's identity; image items, --labels and an
automatic exposure refused by name."""

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi.cli import main
from solas_mi.imageio import read_exr, write_png
from solas_mi.sensor.files import load_sensor

SCENE = """<scene version="3.0.0">
    <integrator type="direct"/>
    <sensor type="perspective">
        <float name="fov" value="4"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    </sensor>
    <shape type="rectangle" id="led">
        <transform name="to_world"><scale x="20" y="20"/></transform>
        <emitter type="area"><rgb name="radiance" value="1.0"/></emitter>
    </shape>
</scene>
"""


@pytest.fixture
def files(tmp_path):
    (tmp_path / "wall.xml").write_text(SCENE)
    (tmp_path / "sensor.toml").write_text("[sensor]\nread_noise_e = 3.0\nfull_well_e = 20000\ngain_dn_per_e = 0.2\n")
    write_png(tmp_path / "photo.png", np.full((12, 16, 3), 0.5, np.float32))
    return tmp_path


def batch(files, out, source, *extra):
    argv = ["batch", "render", str(files / source), "--lens", "solas-doublet", "--spp", "4", "--workers", "1"]
    camera = ["--sensor-model", str(files / "sensor.toml"), "--exposure-ms", "0.5", "--scale", "1000"]
    return main([*argv, *camera, *extra, "-o", str(files / out)])


def test_a_scene_items_pwm_light_is_dark_off_and_lit_on_over_the_cameras_exposure(files):
    """100 Hz at 10 %: on over the first 1 ms of each period at phase 0 (the whole 0.5 ms exposure), off over it at
    phase 0.5; each batch's identity and its outputs record the sources."""
    assert batch(files, "on", "wall.xml", "--pwm-emitter", "led,100,0.1,0") == 0
    assert batch(files, "off", "wall.xml", "--pwm-emitter", "led,100,0.1,0.5") == 0
    black = load_sensor(files / "sensor.toml").black_level_dn
    lit, dark = (read_exr(files / name / "wall_raw.exr")[0]["RAW"] for name in ("on", "off"))
    assert abs(dark.mean() - black) < 0.5 < 100.0 < lit.mean() - black
    on, off = (strict_loads((files / name / "batch.json").read_text()) for name in ("on", "off"))
    assert on["batch_id"] != off["batch_id"]
    assert on["camera"]["scene_timing"]["pwm_emitters"]["led"]["phase"] == 0.0
    rendered = read_exr(files / "off" / "wall.exr")[1]["exposure_windows"]
    assert rendered["pwm_emitters"] == {"led": {"frequency_hz": 100.0, "duty_cycle": 0.1, "phase": 0.5}}


def test_the_estimate_counts_the_parts_rendered(files):
    """A moving camera and two PWM emitters under a shutter of 8 time samples: 8 slices × (the PWM emitters off, and
    each alone) = 24 renders of the film per item, in the samples and in the peak memory."""
    from solas_mi.batch.render import estimate, plan_render
    from solas_mi.isp.camera import load_camera
    from solas_mi.sensor.scene_input import scene_timing

    (files / "slices.toml").write_text((files / "sensor.toml").read_text() + "\n[sensor.shutter]\ntime_samples = 8\n")
    timing = scene_timing(["led,100,0.1", "#0,50,0.2"], "1,0,0")
    plans = [
        plan_render([files / "wall.xml"], files / name, lens="solas-doublet", spp=4, camera=camera)
        for name, camera in (
            ("still", None),
            ("timed", load_camera(str(files / "slices.toml"), 0.5, None, 0, 1.0, None, timing)),
        )
    ]
    still, timed = (estimate(p, 1) for p in plans)
    assert timed["samples"] == 8 * 3 * still["samples"] == 8 * 3 * 16 * 12 * 4
    # the parts held (float32) and their sum (float64), per channel of the film (R, G, B, A) and pixel
    assert timed["peak_bytes"] - still["peak_bytes"] == (24 * 4 + 8) * 4 * 16 * 12


@pytest.mark.parametrize(
    "source, extra, word",
    [
        ("photo.png", ["--pwm-emitter", "led,100,0.1"], "photo.png"),
        ("wall.xml", ["--pwm-emitter", "led,100,0.1", "--labels", "depth"], "--labels"),
        ("wall.xml", ["--camera-motion", "1,0,0", "--exposure-ms", "auto"], "auto"),
        ("wall.xml", ["--pwm-emitter", "led,100,0.1", "--flicker", "0,0,4,4,90,0.1"], "--flicker"),
        ("wall.xml", ["--pwm-emitter", "led,100,0.1", "--pwm-emitter", "led,50,0.1"], "twice"),
    ],
    ids=["image item", "labels", "auto exposure", "flicker", "twice"],
)
def test_what_a_scene_timing_cannot_go_with_is_refused_by_name(files, capsys, source, extra, word):
    assert batch(files, "out", source, *extra) == 2
    err = capsys.readouterr().err.strip()
    assert word in err and len(err.splitlines()) == 1
    assert not (files / "out" / "batch.json").exists()
