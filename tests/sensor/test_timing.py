"""Exposure in time (`sensor.timing`): LED flicker over random phases against the closed-form overlap
probability under a global and a rolling shutter, and a rolling shutter's lean of a moving vertical bar."""

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.errors import SolasError
from solas_mi.imageio import read_exr, write_exr
from solas_mi.sensor.capture import as_chain, capture
from solas_mi.sensor.chain import SensorChain, chain_of
from solas_mi.sensor.files import load_sensor
from solas_mi.sensor.model import SensorModel
from solas_mi.sensor.timing import FlickeringScene, PWMSource, Shutter, exposed_irradiance

EXPOSURE_S = 1e-3
LINE_S = 30e-6
ROWS, LIT = 120, slice(10, 110)  # the LED spans rows 10-109: 100 rows
LEAST_ON_S = 20e-6  # the on-time a row needs for the LED to show in it (the detection threshold below)


def chain(shutter):
    base = chain_of(SensorModel(read_noise_e=3.0, full_well_e=20000.0, gain_dn_per_e=0.2, bit_depth=12))
    return SensorChain(base.photons, base.readouts, shutter=shutter)


def led_fraction(sensor, phases, source_of):
    """The share of frames in which some row of the LED shows: its row mean above black by the electrons of
    `LEAST_ON_S` of its light (the photon conversion's own count of them)."""
    light = np.zeros((ROWS, 4, 3))
    light[LIT] = 3.0  # W/m² while on: about 1000 e⁻ per pixel in LEAST_ON_S
    per_second = sensor.photons.mean_electrons(light, 1.0)[LIT].mean()
    threshold_dn = per_second * LEAST_ON_S * sensor.readouts[0].gain_dn_per_e
    black = sensor.readouts[0].black_level_dn
    seen = 0
    for frame, phase in enumerate(phases):
        scene = FlickeringScene(np.zeros_like(light), light, source_of(phase))
        raw = capture(sensor, scene, EXPOSURE_S, seed=3, frame=frame).astype(np.float64)
        seen += bool((raw[LIT].mean(axis=1) - black > threshold_dn).any())
    return seen / len(phases)


@pytest.mark.parametrize("shutter", [None, Shutter("rolling", LINE_S)], ids=["global", "rolling"])
def test_led_shows_in_the_closed_form_share_of_frames(shutter):
    source_of = lambda phase: PWMSource(90.0, 0.1, phase)  # noqa: E731 (a 90 Hz LED on 10 % of the time)
    rng = np.random.default_rng(7)
    n = 1500
    phases = (np.arange(n) + rng.random(n)) / n  # random phases, one in each n-th of the period
    window = EXPOSURE_S + (0 if shutter is None else (LIT.stop - LIT.start - 1) * LINE_S)
    expected = source_of(0.0).visible_probability(window, LEAST_ON_S)
    got = led_fraction(chain(shutter), phases, source_of)
    assert got == pytest.approx(expected, rel=0.02)


def test_rolling_and_global_shutters_differ_as_predicted():
    source = PWMSource(90.0, 0.1)
    rows = LIT.stop - LIT.start
    global_p = source.visible_probability(EXPOSURE_S)
    rolling_p = source.visible_probability(EXPOSURE_S + (rows - 1) * LINE_S)
    # (D T + t)/T and (D T + t + (n - 1) L)/T: the rolling shutter's rows add their spread of starts
    assert rolling_p - global_p == pytest.approx((rows - 1) * LINE_S * 90.0)
    # under a global shutter every row sees one on-time; under a rolling one each row its own
    scene = FlickeringScene(np.zeros((ROWS, 2, 3)), np.ones((ROWS, 2, 3)), PWMSource(90.0, 0.1, 0.95))
    flat = exposed_irradiance(None, scene, EXPOSURE_S)[:, 0, 0]
    rolled = exposed_irradiance(Shutter("rolling", LINE_S), scene, EXPOSURE_S)[:, 0, 0]
    assert np.ptp(flat) == 0.0 and np.ptp(rolled) > 0.5


def bar(speed_px_s, width=200, x0=40.0, bar_px=6.0):
    """A bright vertical bar, its left edge at x0 + speed × t (box-filtered onto the pixels)."""
    edges = np.arange(width + 1, dtype=np.float64)

    def scene(t):
        left = x0 + speed_px_s * t
        cover = np.clip(np.minimum(edges[1:], left + bar_px) - np.maximum(edges[:-1], left), 0.0, None)
        return np.broadcast_to((5.0 * cover)[None, :, None], (ROWS, width, 3)).copy()

    return scene


@pytest.mark.parametrize("direction", ["top-down", "bottom-up"])
def test_moving_bar_leans_by_speed_times_line_time_times_rows(direction):
    speed = 20000.0  # px/s: 0.6 px per line time, 72 px over the rows
    shutter = Shutter("rolling", LINE_S, direction, time_samples=512)
    sensor = chain(shutter)
    raw = capture(sensor, bar(speed), 2e-4, seed=1).astype(np.float64) - sensor.readouts[0].black_level_dn
    x = np.arange(raw.shape[1]) + 0.5
    centres = (raw * x).sum(axis=1) / raw.sum(axis=1)
    slope = np.polyfit(np.arange(ROWS), centres, 1)[0]  # px per row
    sign = 1.0 if direction == "top-down" else -1.0
    assert slope * ROWS == pytest.approx(sign * speed * LINE_S * ROWS, abs=0.5)
    # a global shutter: no lean (every row averages the same window)
    still = capture(chain(Shutter(time_samples=512)), bar(speed), 2e-4, seed=1).astype(np.float64)
    still -= sensor.readouts[0].black_level_dn
    assert abs(np.polyfit(np.arange(ROWS), (still * x).sum(axis=1) / still.sum(axis=1), 1)[0] * ROWS) < 0.5


def test_static_image_unchanged_by_a_shutter():
    image = np.random.default_rng(0).random((8, 6, 3))
    plain = capture(load_sensor("ar0132at"), image, 0.01, seed=2)
    sensor = as_chain(load_sensor("ar0132at"))
    rolled = SensorChain(sensor.photons, sensor.readouts, shutter=Shutter("rolling", LINE_S))
    assert np.array_equal(capture(rolled, image, 0.01, seed=2), plain)


@pytest.mark.parametrize(
    "values, word",
    [
        ({"mode": "sliding"}, "mode"),
        ({"mode": "rolling"}, "line_time_s"),
        ({"line_time_s": 1e-5}, "line_time_s"),
        ({"mode": "rolling", "line_time_s": 1e-5, "direction": "left"}, "direction"),
        ({"time_samples": 0}, "time_samples"),
    ],
)
def test_bad_shutter_values_are_named(values, word):
    with pytest.raises(SolasError, match=word):
        Shutter(**values)


def test_shutter_from_a_sensor_table():
    sensor = SensorChain.from_dict({"pixel_pitch_um": 3.0, "shutter": {"mode": "rolling", "line_time_s": 1e-5}})
    assert sensor.shutter == Shutter("rolling", 1e-5)
    assert sensor.describe()["stages"][1] == {
        "stage": "shutter",
        "mode": "rolling",
        "line_time_s": 1e-5,
        "direction": "top-down",
        "time_samples": 64,
    }


def test_a_moving_scene_of_the_wrong_shape_is_named():
    with pytest.raises(SolasError, match=r"moving scene's image at t = .* must be \(H, W, 3\)"):
        capture(chain(Shutter("rolling", LINE_S)), lambda t: np.zeros((ROWS + (t > 0), 4, 3)), 1e-3, seed=1)


@pytest.mark.parametrize(
    "values, word", [((0.0, 0.5), "frequency_hz"), ((90.0, 1.5), "duty_cycle"), ((90.0, 0.5, 1.0), "phase")]
)
def test_bad_pwm_values_are_named(values, word):
    with pytest.raises(SolasError, match=word):
        PWMSource(*values)


def test_on_time_of_a_window_is_the_duty_cycle_over_whole_periods():
    source = PWMSource(100.0, 0.25, 0.3)
    assert source.on_time(np.array([0.0]), np.array([0.05]))[0] == pytest.approx(5 * 0.25 * 0.01)
    with pytest.raises(SolasError, match="least_on_s"):
        source.visible_probability(1e-3, 2e-3)


def camera(folder, *extra, toml="sensor.toml"):
    assert (
        main(
            [
                "camera",
                str(folder / "in.exr"),
                "--sensor-model",
                str(folder / toml),
                "--exposure-ms",
                "1",
                "--seed",
                "5",
                "-o",
                str(folder / "raw.exr"),
                *extra,
            ]
        )
        == 0
    )
    return read_exr(folder / "raw.exr")


@pytest.fixture
def led(tmp_path):
    image = np.full((ROWS, 16, 3), 2.0, dtype=np.float32)
    write_exr(tmp_path / "in.exr", dict(zip("RGB", np.moveaxis(image, -1, 0))))
    (tmp_path / "sensor.toml").write_text("[sensor]\npixel_pitch_um = 3.0\nfull_well_e = 100000\n")
    (tmp_path / "rolling.toml").write_text(
        "[sensor]\npixel_pitch_um = 3.0\nfull_well_e = 100000\n\n"
        f'[sensor.shutter]\nmode = "rolling"\nline_time_s = {LINE_S}\n'
    )
    return tmp_path


def test_camera_flicker_box_is_on_or_off_as_its_phase_says(led):
    plain, _ = camera(led)
    # 90 Hz at 10 %: on for the first 1.11 ms of the period, so over all of the 1 ms exposure at phase 0
    on, meta = camera(led, "--flicker", "4,10,12,30,90,0.1,0")
    assert np.array_equal(on["RAW"], plain["RAW"])
    assert meta["flicker"] == {"box": [4, 10, 12, 30], "frequency_hz": 90.0, "duty_cycle": 0.1, "phase": 0.0}
    off, _ = camera(led, "--flicker", "4,10,12,30,90,0.1,0.5")  # on from 5.6 ms: dark over the exposure
    outside = np.ones(plain["RAW"].shape, bool)
    outside[10:30, 4:12] = False
    assert np.array_equal(off["RAW"][outside], plain["RAW"][outside])
    black = load_sensor(led / "sensor.toml").black_level_dn
    assert abs(off["RAW"][10:30, 4:12].mean() - black) < 2.0 < plain["RAW"][10:30, 4:12].mean() - black


def test_camera_flicker_under_a_rolling_shutter_bands_the_rows(led):
    # phase 0.95: on over the last 5 % of the period, 0.56 ms before the first row starts, through 0.56 ms
    raw, _ = camera(led, "--flicker", "0,0,16,120,90,0.1,0.95", toml="rolling.toml")
    source = PWMSource(90.0, 0.1, 0.95)
    starts, ends = Shutter("rolling", LINE_S).windows(ROWS, 1e-3)
    share = source.on_time(starts, ends) / 1e-3  # each row's share of the light: falls from 0.56 to 0
    black = load_sensor(led / "sensor.toml").black_level_dn
    rows = raw["RAW"].mean(axis=1) - black
    assert np.corrcoef(rows, share)[0, 1] > 0.99 and share[0] > 0.5 and share[-1] == 0.0


def test_camera_image_motion_leans_a_bar_under_a_rolling_shutter(tmp_path):
    image = bar(0.0)(0.0).astype(np.float32)  # the bar standing at x0 = 40
    write_exr(tmp_path / "in.exr", dict(zip("RGB", np.moveaxis(image, -1, 0))))
    sensor = "[sensor]\nread_noise_e = 3.0\nfull_well_e = 20000\ngain_dn_per_e = 0.2\n\n[sensor.shutter]\n"
    (tmp_path / "rolling.toml").write_text(sensor + f'mode = "rolling"\nline_time_s = {LINE_S}\ntime_samples = 512\n')
    speed = 20000.0
    assert (
        main(
            [
                "camera",
                str(tmp_path / "in.exr"),
                "--sensor-model",
                str(tmp_path / "rolling.toml"),
                "--exposure-ms",
                "0.2",
                "--image-motion",
                f"{speed},0",
                "-o",
                str(tmp_path / "raw.exr"),
            ]
        )
        == 0
    )
    channels, meta = read_exr(tmp_path / "raw.exr")
    raw = channels["RAW"].astype(np.float64) - load_sensor(tmp_path / "rolling.toml").black_level_dn
    x = np.arange(raw.shape[1]) + 0.5
    slope = np.polyfit(np.arange(ROWS), (raw * x).sum(axis=1) / raw.sum(axis=1), 1)[0]
    assert slope * ROWS == pytest.approx(speed * LINE_S * ROWS, abs=0.5) and meta["image_motion_px_s"] == [speed, 0]


BAD_FLICKER = ["1,2,3", "4,10,2,30,90,0.1", "a,b,c,d,90,0.1", "0,0,4,4,90", "0,0,4,4,-5,0.1", "0,0,999,4,90,0.1"]


@pytest.mark.parametrize(
    "extra",
    [["--flicker", value] for value in BAD_FLICKER]
    + [["--image-motion", "5"], ["--image-motion", "1,inf"], ["--image-motion", "1,2", "--flicker", "0,0,4,4,90,0.1"]],
)
def test_bad_scene_in_time_is_one_line_and_writes_nothing(led, capsys, extra):
    assert (
        main(
            [
                "camera",
                str(led / "in.exr"),
                "--sensor-model",
                str(led / "sensor.toml"),
                "--exposure-ms",
                "1",
                "-o",
                str(led / "raw.exr"),
                *extra,
            ]
        )
        == 2
    )
    assert len(capsys.readouterr().err.strip().splitlines()) == 1 and not (led / "raw.exr").exists()
