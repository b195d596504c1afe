"""Odd sensor and image-processor files through `solas-mi camera`: every key with a value of the wrong
type (a string, a NaN written as a string, a bool, a list, a table), out of its physical range (negative,
zero, huge, tiny), or one that overflowed later in the chain, is one line naming the key and what is
allowed, and nothing is written; frames too small to demosaic likewise, and the smallest that can be
demosaiced (2×2) is developed."""

import re

import numpy as np
import pytest

from solas_mi.cli import main
from solas_mi.imageio import write_exr
from solas_mi.sensor.model import SensorModel

SENSOR_KEYS = (
    "pixel_pitch_um",
    "qe_r",
    "qe_g",
    "qe_b",
    "qe_c",
    "dark_current_e_s",
    "read_noise_e",
    "prnu",
    "dsnu_e",
    "full_well_e",
    "gain_dn_per_e",
    "bit_depth",
    "black_level_dn",
    "cfa",
    "wavelengths_nm",
)
WRONG_TYPES = ('"1.0"', '"nan"', "true", "[]", "{}")


def camera(folder, capsys, sensor="imx490", isp=None, image="in.exr", extra=()):
    """Exit status and stderr of `camera` on `image` (written nothing when refused: checked here)."""
    before = sorted(p.name for p in folder.iterdir())
    argv = [
        "camera",
        str(folder / image),
        "--sensor-model",
        sensor,
        "--exposure-ms",
        "5",
        *extra,
        *(["--isp", isp] if isp else []),
        "-o",
        str(folder / "out.exr"),
    ]
    code = main(argv)
    err = capsys.readouterr().err
    if code != 0:
        assert len(err.strip().splitlines()) == 1, err
        assert sorted(p.name for p in folder.iterdir()) == before
    return code, err


@pytest.fixture
def folder(tmp_path):
    image = np.empty((12, 16, 3), np.float32)
    image[...] = (0.02, 0.03, 0.01)
    write_exr(tmp_path / "in.exr", dict(zip("RGB", np.moveaxis(image, -1, 0))))
    return tmp_path


def _sensor(folder, text):
    (folder / "s.toml").write_text(text)
    return str(folder / "s.toml")


@pytest.mark.parametrize("key", SENSOR_KEYS)
@pytest.mark.parametrize("value", WRONG_TYPES)
def test_every_sensor_key_of_the_wrong_type_is_named(folder, capsys, key, value):
    code, err = camera(folder, capsys, _sensor(folder, f"[sensor]\n{key} = {value}\n"))
    assert code == 2 and f"{key} = " in err and "must be" in err, err


# values that passed as finite numbers and overflowed later (tracebacks), or gave a black or meaningless
# frame without a word: each outside what a sensor can be
@pytest.mark.parametrize(
    "key, value, allowed",
    [
        ("pixel_pitch_um", "1e300", r"\[0.1, 1000\]"),  # (pitch · 1e-6)² overflowed: OverflowError
        ("pixel_pitch_um", "1e-300", r"\[0.1, 1000\]"),  # a pixel area of 0: a black frame
        ("full_well_e", "1e300", r"\[1, 1e\+09\]"),  # Poisson means past NumPy's range
        ("full_well_e", "0.5", r"\[1, 1e\+09\]"),  # a well of half an electron
        ("dark_current_e_s", "1e300", r"\[0, 1e\+09\]"),
        ("read_noise_e", "1e300", r"\[0, 1e\+09\]"),
        ("dsnu_e", "1e300", r"\[0, 1e\+09\]"),
        ("gain_dn_per_e", "1e300", r"\(0, 4095\]"),
        ("gain_dn_per_e", "1e-300", "at least 1 DN"),  # the full well spans no ADC code: every pixel black
        ("wavelengths_nm", "[1, 2, 3]", r"\[380, 780\]"),
        ("wavelengths_nm", "[1e300, 1e300, 1e300]", r"\[380, 780\]"),
        ("cfa", "5", "must be one of RGGB"),
        ("qe_curve", '""', "qe_curve = '' must name a CSV file"),  # "QE curve '<the sensor's folder>' is a folder"
    ],
)
def test_sensor_values_outside_physics_are_refused(folder, capsys, key, value, allowed):
    code, err = camera(folder, capsys, _sensor(folder, f"[sensor]\n{key} = {value}\n"))
    assert code == 2 and key in err and re.search(allowed, err), err


@pytest.mark.parametrize(
    "columns, blind",
    [
        ("R = [0, 0]\nG = [0, 0]\nB = [0, 0]", "R, G, B"),  # "SVD did not converge" with --isp
        ("R = [0.5, 0.5]\nG = [0, 0]\nB = [0.5, 0.5]", "G"),
        # a curve wholly outside 380-780 nm: no response to the image's light
        ("R = [0.5, 0.5]\nG = [0.5, 0.5]\nB = [0.5, 0.5]\nwavelength_nm = [900, 1000]", "R, G, B"),
    ],
)
def test_a_filter_blind_to_the_image_is_refused(folder, capsys, columns, blind):
    wavelengths = "" if "wavelength_nm" in columns else "wavelength_nm = [400, 700]\n"
    sensor = _sensor(folder, f"[sensor]\n[sensor.qe_curve]\n{wavelengths}{columns}\n")
    for isp in (None, "default"):
        code, err = camera(folder, capsys, sensor, isp)
        assert code == 2 and f"filter(s) {blind} of the colour filter array have zero quantum efficiency" in err, err


def test_the_limits_admit_every_preset_and_the_extremes_of_real_sensors():
    """The ranges refuse no sensor made: 0.56 µm pixels with a 6000 e⁻ well, 200 µm flat-panel pixels with a
    2 Me⁻ well, a 16-bit ADC at 0.03 DN/e⁻, a camera at 8 bits and 20 DN/e⁻ (a well of 12 e⁻ spans its codes)."""
    from solas_mi.sensor.files import load_sensor, preset_names

    assert [load_sensor(name).cfa for name in preset_names()]
    SensorModel(pixel_pitch_um=0.56, full_well_e=6000.0)
    SensorModel(pixel_pitch_um=200.0, full_well_e=2e6, gain_dn_per_e=0.03, bit_depth=16, dark_current_e_s=1e5)
    SensorModel(bit_depth=8, black_level_dn=16, gain_dn_per_e=20.0, full_well_e=12.0, wavelengths_nm=(700, 500, 400))


@pytest.mark.parametrize(
    "toml, says",
    [
        # a string read as true: the frame of refining_step = true, silently
        (
            'demosaic = "Menon2007"\ndemosaic_options = {refining_step = "false"}',
            "refining_step = 'false' must be true or false",
        ),
        ('demosaic = "Menon2007"\ndemosaic_options = {refining_step = 1}', "refining_step = 1 must be true or false"),
        # not a method's name nor a table of gains: grey world, silently
        ("white_balance = 2.5", "white_balance 2.5 must be one of daylight, grey-world, grey-card, none"),
        ("white_balance = true", "white_balance True must be one of"),
        ("white_balance = [1, 2, 3]", r"white_balance \[1, 2, 3\] must be one of"),
        ("white_balance = {R = 1e300, G = 1, B = 1}", r"numbers in \(0, 65536\]"),
        ('white_balance = {R = "2", G = 1, B = 1}', r"numbers in \(0, 65536\]"),
        # the six tracebacks of a malformed grey card
        ('white_balance = "grey-card"\ngrey_card = "false"', "grey_card = 'false' must be four integers"),
        ('white_balance = "grey-card"\ngrey_card = 3', "grey_card = 3 must be four integers"),
        ('white_balance = "grey-card"\ngrey_card = [0, 0, 8]', r"grey_card = \[0, 0, 8\] must be four integers"),
        ('white_balance = "grey-card"\ngrey_card = [0, 0, 8, 8, 9]', "must be four integers"),
        ('white_balance = "grey-card"\ngrey_card = [0.5, 0, 8, 8]', "must be four integers"),
        ('white_balance = "grey-card"\ngrey_card = ["a", "b", "c", "d"]', "must be four integers"),
        ('white_balance = "grey-card"\ngrey_card = [[0], [0], [8], [8]]', "must be four integers"),
        ('white_balance = "grey-card"\ngrey_card = [8, 8, 0, 0]', "x0 \\+ 2 <= x1"),
        ('white_balance = "grey-card"\ngrey_card = [0, 0, 100, 100]', "must be inside the 16x12 frame"),
        # demosaicing options and methods of the wrong type
        ("demosaic_options = 0", "demosaicing options 0 must be a table"),
        ("demosaic_options = []", "demosaicing options \\[\\] must be a table"),
        ('demosaic = "Menon2007"\ndemosaic_options = ["refining_step"]', "must be a table of option = true/false"),
        ("demosaic = []", "demosaicing method \\[\\] must be one of"),
        ('demosaic = "none"\nccm = "none"\ndemosaic_options = 0', 'demosaic = "none" gives a grey frame'),
        ("ccm = [[1, 0, 0], [0, 1, 0], [0, 0, 1e300]]", "3 rows of 3 numbers within ±65536"),
        ("ccm = [[1, 0, 0], [0, 1, 0], [0, 0, true]]", "3 rows of 3 numbers"),
        # a gamma without its tone curve: ignored, silently
        ("gamma = 2.5", 'isp gamma = 2.5 goes with tone = "gamma"'),
    ],
)
def test_isp_values_of_the_wrong_type_are_named(folder, capsys, toml, says):
    (folder / "isp.toml").write_text(f"[isp]\n{toml}\n")
    code, err = camera(folder, capsys, isp=str(folder / "isp.toml"))
    assert code == 2 and re.search(says, err), err


def test_gains_for_other_filters_are_refused_before_the_frame(folder, capsys, monkeypatch):
    """White-balance gains naming G for an RCCB sensor: refused before the RAW is taken (develop refused
    them after the sensor's work; a batch, every item after its convolution or render)."""
    from solas_mi.sensor import capture

    monkeypatch.setattr(capture, "capture", lambda *args, **kwargs: pytest.fail("a frame was taken"))
    (folder / "sensor.toml").write_text('[sensor]\ncfa = "RCCB"\n')
    (folder / "isp.toml").write_text("[isp]\nwhite_balance = {R = 1.9, G = 1, B = 1.5}\n")
    code, err = camera(folder, capsys, str(folder / "sensor.toml"), str(folder / "isp.toml"))
    assert code == 2 and "each filter of RCCB: R, B, C" in err


def test_menon_refining_step_is_a_switch(folder, capsys):
    """refining_step = true and = false develop different frames (the option reaches the demosaicer)."""
    import imageio.v3 as iio

    image = np.random.default_rng(1).uniform(0.0, 0.05, (12, 16, 3)).astype(np.float32)
    write_exr(folder / "in.exr", dict(zip("RGB", np.moveaxis(image, -1, 0))))
    frames = []
    for step in ("true", "false"):
        (folder / "isp.toml").write_text(
            f'[isp]\ndemosaic = "Menon2007"\ndemosaic_options = {{refining_step = {step}}}\n'
        )
        assert camera(folder, capsys, isp=str(folder / "isp.toml"))[0] == 0
        frames.append(iio.imread(folder / "out.png"))
        (folder / "out.exr").unlink()
        (folder / "out.png").unlink()
    assert not np.array_equal(*frames)


@pytest.mark.parametrize("rows, cols", [(1, 1), (1, 8), (8, 1), (1, 2), (2, 1)])
@pytest.mark.parametrize("isp", ["default", "grey-world"])
def test_frames_without_a_whole_cfa_tile_are_refused(folder, capsys, rows, cols, isp):
    """IndexError in demosaicing before: a frame of one row or column has no site of some filter."""
    write_exr(folder / "small.exr", {c: np.full((rows, cols), 0.02, np.float32) for c in "RGB"})
    if isp != "default":
        (folder / "isp.toml").write_text(f'[isp]\nwhite_balance = "{isp}"\n')
        isp = str(folder / "isp.toml")
    code, err = camera(folder, capsys, isp=isp, image="small.exr")
    assert (
        code == 2
        and f"needs a frame of at least 2x2 pixels (one whole tile of the colour filter array), got {cols}x{rows}"
        in err
    )


def test_the_smallest_whole_tile_is_developed(folder, capsys):
    import imageio.v3 as iio

    write_exr(folder / "small.exr", {c: np.full((2, 2), 0.02, np.float32) for c in "RGB"})
    for method in ("bilinear", "Malvar2004", "Menon2007"):
        (folder / "isp.toml").write_text(f'[isp]\ndemosaic = "{method}"\nwhite_balance = "grey-world"\n')
        assert camera(folder, capsys, isp=str(folder / "isp.toml"), image="small.exr")[0] == 0
        assert iio.imread(folder / "out.png").shape == (2, 2, 3)
        (folder / "out.exr").unlink()
        (folder / "out.png").unlink()
    # without demosaicing a one-row frame is a grey frame
    write_exr(folder / "row.exr", {c: np.full((1, 5), 0.02, np.float32) for c in "RGB"})
    (folder / "isp.toml").write_text('[isp]\ndemosaic = "none"\nccm = "none"\n')
    assert camera(folder, capsys, isp=str(folder / "isp.toml"), image="row.exr")[0] == 0


@pytest.mark.parametrize(
    "extra, says",
    [
        (["--f-number", "1e300"], "f-number 1e\\+300 must be a number from 0.5"),  # E = 0: a black frame
        (["--f-number", "0.3"], "f-number 0.3 must be a number from 0.5"),  # faster than any lens in air
        (["--scale", "1e300", "--exposure-ms", "1e300"], "more photons per pixel than a float64 holds"),
        (["--scale", "1e308"], "--scale 1e\\+308 times the image's largest value 1e\\+06 passes the largest float64"),
        # auto-exposure meters one second of light: it said "an exposure of 1 s", which nobody gave
        (
            ["--scale", "1e300", "--exposure-ms", "auto"],
            "^solas-mi camera: error: auto-exposure: irradiance up to 1e\\+306",
        ),
    ],
)
def test_camera_values_that_overflowed_are_refused(folder, capsys, extra, says):
    write_exr(folder / "bright.exr", {c: np.full((4, 4), 1e6, np.float32) for c in "RGB"})
    code, err = camera(folder, capsys, image="bright.exr", extra=extra)
    assert code == 2 and re.search(says, err), err
