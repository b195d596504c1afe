"""A Mitsuba scene over the sensor's exposure windows (`sensor.rendered`): a PWM emitter of a rendered scene shows
in the closed-form share of frames over random phases (global and rolling shutter), the parts of the light sum to
the scene's own render, and a camera moving during the frame leans a vertical bar by speed × line time × rows
under a rolling shutter and blurs it without lean under a global one."""

import math

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.render.stock import render_scene
from solas_mi.sensor.capture import capture
from solas_mi.sensor.chain import SensorChain, chain_of
from solas_mi.sensor.model import SensorModel
from solas_mi.sensor.poses import pose_at
from solas_mi.sensor.rendered import render_in_time, render_parts
from solas_mi.sensor.timing import PWMSource, Shutter

EXPOSURE_S = 1e-3
LINE_S = 30e-6
ROWS, COLS, LIT = 120, 4, slice(10, 110)  # the LED spans rows 10-109: 100 rows
LEAST_ON_S = 20e-6  # the on-time a row needs for the LED to show in it (the detection threshold below)
DISTANCE, FOV_DEG = 5.0, 40.0  # the camera 5 m in front of the plane z = 0, its horizontal field 40°


def perspective(mi, rows, cols, x=0.0):
    return {
        "type": "perspective",
        "fov": FOV_DEG,
        "to_world": mi.ScalarTransform4f().look_at([x, 0, DISTANCE], [x, 0, 0], [0, 1, 0]),
        "film": {"type": "hdrfilm", "width": cols, "height": rows, "rfilter": {"type": "box"}},
        "sampler": {"type": "stratified", "sample_count": 16},
    }


def pixel_m(cols):
    """The side of a pixel on the plane z = 0 (m)."""
    return 2.0 * DISTANCE * math.tan(math.radians(FOV_DEG / 2)) / cols


def rows_box(mi, first, stop, rows, cols, x=(-10.0, 10.0)):
    """A rectangle on z = 0 covering rows first to stop − 1 exactly (and columns over x, in m)."""
    top, bottom = (rows / 2 - first) * pixel_m(cols), (rows / 2 - stop) * pixel_m(cols)
    return (
        mi.ScalarTransform4f()
        .translate([(x[0] + x[1]) / 2, (top + bottom) / 2, 0])
        .scale([(x[1] - x[0]) / 2, (top - bottom) / 2, 1])
    )


def led_scene(mi, sky=0.0, second=False):
    """An LED (area light "led") over rows LIT, a second one ("tail", in its own rows) and a sky if asked."""
    scene = {
        "type": "scene",
        "integrator": {"type": "direct"},
        "sensor": perspective(mi, ROWS, COLS),
        "led": {
            "type": "rectangle",
            "to_world": rows_box(mi, LIT.start, LIT.stop, ROWS, COLS),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [3.0, 2.0, 0.5]}},
        },
    }
    if second:
        scene["tail"] = {
            "type": "rectangle",
            "to_world": rows_box(mi, 112, 118, ROWS, COLS),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [2.0, 0.1, 0.1]}},
        }
    if sky:
        scene["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": sky}}
    return mi.load_dict(scene)


def chain(shutter):
    base = chain_of(SensorModel(read_noise_e=3.0, full_well_e=20000.0, gain_dn_per_e=0.2, bit_depth=12))
    return SensorChain(base.photons, base.readouts, shutter=shutter)


@pytest.mark.parametrize("shutter", [None, Shutter("rolling", LINE_S)], ids=["global", "rolling"])
def test_a_rendered_pwm_emitter_shows_in_the_closed_form_share_of_frames(variant_llvm_ad_spectral, shutter):
    """As `tests/sensor/test_timing.py` does for a degraded frame, here with the LED an emitter of a rendered
    scene: each frame the render's rows over their windows at a random phase, through a noisy sensor."""
    mi = variant_llvm_ad_spectral
    parts = render_parts(led_scene(mi), 16, shutter, EXPOSURE_S, ["led"])
    lit = parts.alone["led"][0]
    assert (lit[LIT] > 0).all() and not lit[: LIT.start].any() and not lit[LIT.stop :].any()
    scale = 3.0 / lit[LIT].mean()  # W/m² while on: about 1000 e⁻ per pixel in LEAST_ON_S
    sensor = chain(shutter)
    per_second = sensor.photons.mean_electrons(lit * scale, 1.0)[LIT].mean()
    threshold_dn = per_second * LEAST_ON_S * sensor.readouts[0].gain_dn_per_e
    black = sensor.readouts[0].black_level_dn
    rng = np.random.default_rng(7)
    n = 1500
    phases = (np.arange(n) + rng.random(n)) / n  # random phases, one in each n-th of the period
    seen = 0
    for frame, phase in enumerate(phases):
        image = parts.over_windows(shutter, EXPOSURE_S, {"led": PWMSource(90.0, 0.1, phase)}) * scale
        raw = capture(sensor, image, EXPOSURE_S, seed=3, frame=frame).astype(np.float64)
        seen += bool((raw[LIT].mean(axis=1) - black > threshold_dn).any())
    window = EXPOSURE_S + (0 if shutter is None else (LIT.stop - LIT.start - 1) * LINE_S)
    assert seen / n == pytest.approx(PWMSource(90.0, 0.1).visible_probability(window, LEAST_ON_S), rel=0.02)


def test_the_parts_sum_to_the_scenes_own_render(variant_llvm_ad_spectral):
    """Steady light plus each PWM emitter alone (each switched off and on through its parameters) is the scene
    as loaded, within the renders' noise; a source always on gives that, and the scene is left as it was."""
    mi = variant_llvm_ad_spectral
    scene = led_scene(mi, sky=0.2, second=True)
    parts = render_parts(scene, 64, None, EXPOSURE_S, ["led", "tail"])
    whole = render_scene(scene, 64, seed=5).image.astype(np.float64)
    summed = parts.steady[0] + parts.alone["led"][0] + parts.alone["tail"][0]
    assert parts.steady[0, 0].mean() == pytest.approx(whole[0].mean(), rel=0.05)  # the sky alone
    assert parts.alone["led"][0, : LIT.start].max() < 1e-20 and parts.alone["tail"][0, LIT].max() < 1e-20
    assert summed.mean(axis=(0, 1)) == pytest.approx(whole.mean(axis=(0, 1)), rel=0.01)
    on = {"led": PWMSource(90.0, 1.0), "tail": PWMSource(50.0, 1.0, 0.3)}
    assert np.allclose(parts.over_windows(None, EXPOSURE_S, on), summed)
    half = parts.over_windows(None, EXPOSURE_S, {"led": PWMSource(1000.0, 0.5), "tail": PWMSource(1000.0, 1.0)})
    assert np.allclose(half, parts.steady[0] + 0.5 * parts.alone["led"][0] + parts.alone["tail"][0])
    again = render_scene(scene, 64, seed=5).image
    assert np.array_equal(again, whole.astype(np.float32))


def test_a_frame_whose_only_emitter_is_off_is_black(variant_llvm_ad_spectral):
    """A blue LED lighting a green wall, off over the whole exposure: the frame is 0, not the ±1e-33 that the
    switched-off emitter's remainder (`OFF` of its light) gives, negative where its colour leaves the RGB gamut
    (which the camera then announced as values below zero)."""
    mi = variant_llvm_ad_spectral
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path"},
            "sensor": perspective(mi, 24, 24),
            "wall": {
                "type": "rectangle",
                "to_world": mi.ScalarTransform4f().scale([50.0, 50.0, 1.0]),
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.05, 0.9, 0.05]}},
            },
            "led": {
                "type": "sphere",
                "center": [0.0, 3.0, 2.0],
                "radius": 0.5,
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [0.1, 0.2, 5.0]}},
            },
        }
    )
    parts = render_parts(scene, 4, None, EXPOSURE_S, ["led"])
    assert parts.alone["led"].max() > 0.01  # the LED alone lights the wall
    off = parts.over_windows(None, EXPOSURE_S, {"led": PWMSource(100.0, 0.1, phase=0.5)})
    assert not off.any()


@pytest.mark.parametrize("direction", ["top-down", "bottom-up"])
def test_a_crop_windows_rows_keep_their_times_on_the_whole_film(variant_llvm_ad_spectral, direction):
    """A film drawing rows 50-89 of its 120 (its crop window): each row's share of the LED's light is the on-time
    within that row's window of the whole film, not of a film of 40 rows."""
    mi = variant_llvm_ad_spectral
    scene = led_scene(mi)
    params = mi.traverse(scene)
    params["sensor.film.crop_offset"] = mi.ScalarPoint2u(0, 50)
    params["sensor.film.crop_size"] = mi.ScalarPoint2u(COLS, 40)
    params.update()
    shutter, source = Shutter("rolling", LINE_S, direction), PWMSource(90.0, 0.1, 0.95)
    parts = render_parts(scene, 4, shutter, EXPOSURE_S, ["led"])
    frame = parts.over_windows(shutter, EXPOSURE_S, {"led": source})
    share = ((frame - parts.steady[0]) / parts.alone["led"][0])[..., 0].mean(axis=1)
    starts, ends = shutter.windows(ROWS, EXPOSURE_S)
    assert parts.steady.shape[1] == 40
    assert np.allclose(share, source.on_time(starts[50:90], ends[50:90]) / EXPOSURE_S)


def bar_scene(mi, rows, cols, x_end=None):
    """A bright vertical bar 4 pixels wide at the image centre, the camera at x = 0 (or `x_end`)."""
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "direct"},
            "sensor": perspective(mi, rows, cols, 0.0 if x_end is None else x_end),
            "bar": {
                "type": "rectangle",
                "to_world": rows_box(mi, -4, rows + 4, rows, cols, (-2 * pixel_m(cols), 2 * pixel_m(cols))),
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}},
            },
        }
    )


def centres_and_spread(image):
    """Each row's centroid and variance of x (px) of the image's first channel."""
    values = image[..., 0].astype(np.float64)
    x = np.arange(values.shape[1]) + 0.5
    centre = (values * x).sum(axis=1) / values.sum(axis=1)
    return centre, (values * (x - centre[:, None]) ** 2).sum(axis=1) / values.sum(axis=1)


def test_a_camera_moving_during_the_frame_leans_a_bar_under_a_rolling_shutter(variant_llvm_ad_spectral):
    """The camera translates along x during the frame: the bar's image moves at a speed the geometry gives
    (focal length in pixels × camera speed / distance); a rolling shutter's rows at their own times lean it by
    speed × line time × rows, a global shutter blurs it (by the spread of its poses) and does not lean it."""
    mi = variant_llvm_ad_spectral
    rows, cols, lines = 48, 64, 8  # the exposure 8 line times: the rows' windows start and end on slice edges
    exposure = lines * LINE_S
    span = exposure + (rows - 1) * LINE_S
    f_px = cols / 2 / math.tan(math.radians(FOV_DEG / 2))
    shift_m = 1.0  # the camera's travel over the frame's span: the image's, 17.6 px
    speed = f_px * shift_m / DISTANCE / span  # px/s, the image's (leftward: the camera looks along −z)
    end = np.array(bar_scene(mi, rows, cols, shift_m).sensors()[0].world_transform().matrix).reshape(4, 4)
    scene = bar_scene(mi, rows, cols)
    still = centres_and_spread(render_scene(scene, 16).image)
    moved = centres_and_spread(render_scene(bar_scene(mi, rows, cols, shift_m), 16).image)
    assert np.mean(still[0] - moved[0]) == pytest.approx(speed * span, abs=0.05)  # the geometry's speed

    slices = lines + rows - 1
    for direction, sign in (("top-down", -1.0), ("bottom-up", 1.0)):
        rolling = Shutter("rolling", LINE_S, direction, time_samples=slices)
        frame = render_in_time(scene, 16, rolling, exposure, to_world_end=end)
        centres, _ = centres_and_spread(frame.image)
        slope = np.polyfit(np.arange(rows), centres, 1)[0]  # px per row
        assert slope * rows == pytest.approx(sign * speed * LINE_S * rows, abs=0.5)
        assert frame.meta["exposure_windows"]["slices"] == slices

    moving = Shutter(time_samples=slices)
    blurred, spread = centres_and_spread(render_in_time(scene, 16, moving, span, to_world_end=end).image)
    assert abs(np.polyfit(np.arange(rows), blurred, 1)[0] * rows) < 0.5
    travel = speed * span  # px over the exposure: the poses spread evenly over it, one per slice's middle
    added = np.mean(spread - still[1])  # (and a little from the pixels' sampling of the moving edges: 0.14 px²)
    assert added == pytest.approx(travel**2 * (1 - 1 / slices**2) / 12, rel=0.03)


def test_the_lens_camera_moving_during_the_frame_leans_a_bar(variant_llvm_ad_spectral):
    """The same with `lens_camera` (the doublet focused at the bar): its image speed is the shift of the bar
    between still renders at the start and end poses over the span; the rolling shutter leans it by speed ×
    line time × rows."""
    mi = variant_llvm_ad_spectral
    rows, cols, lines = 48, 64, 8
    exposure, span = lines * LINE_S, (lines + rows - 1) * LINE_S

    def scene(x):
        sensor = perspective(mi, rows, cols, x)
        sensor.update(type="lens_camera", lens="solas-doublet", focus_distance=DISTANCE)
        del sensor["fov"]
        bar = mi.ScalarTransform4f().scale([0.01, 1.0, 1.0])
        return mi.load_dict(
            {
                "type": "scene",
                "integrator": {"type": "direct"},
                "sensor": sensor,
                "bar": {"type": "rectangle", "to_world": bar, "emitter": {"type": "area", "radiance": 1.0}},
            }
        )

    start, moved = scene(0.0), scene(0.1)
    begun, ended = (centres_and_spread(render_scene(s, 16).image)[0] for s in (start, moved))
    speed = np.mean(begun - ended) / span
    assert speed * span > 10.0  # px: the bar's image moves left as the camera moves right
    end = np.array(moved.sensors()[0].world_transform().matrix).reshape(4, 4)
    rolling = Shutter("rolling", LINE_S, time_samples=lines + rows - 1)
    centres, _ = centres_and_spread(render_in_time(start, 16, rolling, exposure, to_world_end=end).image)
    assert np.polyfit(np.arange(rows), centres, 1)[0] * rows == pytest.approx(-speed * LINE_S * rows, abs=0.5)


def test_pose_at_turns_and_moves_between_the_ends():
    start = np.eye(4)
    end = np.eye(4)
    end[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]  # 90° about y
    end[:3, 3] = [2.0, 0.0, -4.0]
    half = pose_at(start, end, 0.5)
    c = math.cos(math.pi / 4)
    assert np.allclose(half[:3, :3], [[c, 0, c], [0, 1, 0], [-c, 0, c]])
    assert np.allclose(half[:3, 3], [1.0, 0.0, -2.0])
    assert np.allclose(pose_at(start, end, 0.0), start) and np.allclose(pose_at(start, end, 1.0), end)
    flipped = np.diag([-1.0, 1.0, -1.0, 1.0]) @ np.diag([1.0, 1.0, -1.0, 1.0])  # a mirror
    with pytest.raises(SolasError, match="mirrors"):
        pose_at(start, flipped, 0.5)


@pytest.mark.parametrize(
    "call, word",
    [
        (lambda mi, scene: render_parts(scene, 4, None, EXPOSURE_S, ["nowhere"]), "nowhere"),
        (lambda mi, scene: render_parts(scene, 4, None, 0.0, ["led"]), "exposure_s"),
        (lambda mi, scene: render_parts(scene, 4, None, EXPOSURE_S, (), np.eye(3)), "to_world_end"),
        (
            lambda mi, scene: render_parts(scene, 4, None, EXPOSURE_S, ["led"]).over_windows(
                Shutter("rolling", LINE_S), EXPOSURE_S, {"led": PWMSource(90.0, 0.1)}
            ),
            "reach past",
        ),
        (lambda mi, scene: render_in_time(scene, 4, None, EXPOSURE_S, {"led": 90.0}), "PWMSource"),
    ],
    ids=["unknown emitter", "exposure", "transform", "windows", "source"],
)
def test_bad_values_are_named(variant_llvm_ad_spectral, call, word):
    with pytest.raises(SolasError, match=word):
        call(variant_llvm_ad_spectral, led_scene(variant_llvm_ad_spectral))
