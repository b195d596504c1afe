"""Camera models fitted to the lens's real chief-ray mapping (`optics.calibration`): against OpenCV's own
projection of the written files (a test-only dependency), fitted back from their own data, their files
read back as written, and bad inputs refused by name with nothing written."""

import math

import cv2  # a test-only dependency: the test extra of pyproject.toml, requirements.lock
import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.optics.calibration import Sensor, chief_map
from solas_mi.optics.calibration.files import read, write_text
from solas_mi.optics.calibration.fit import fit, fit_points
from solas_mi.optics.calibration.models import MODELS, model
from solas_mi.optics.camera import film_pitch_um
from solas_mi.optics.frame import parse_frame
from solas_mi.optics.lens import Lens, shipped_lenses
from solas_mi.optics.pupil import chief_rays

COLUMNS, ROWS = 320, 240

# coefficients of each model, every one nonzero, of a camera of about 100 deg half field (the pinhole 60)
TRUTH = {
    "opencv-pinhole": dict(
        fx=800.0,
        fy=805.0,
        cx=160.3,
        cy=119.6,
        k1=-0.28,
        k2=0.09,
        p1=1e-3,
        p2=-5e-4,
        k3=-0.012,
        k4=0.05,
        k5=0.01,
        k6=0.002,
        s1=2e-4,
        s2=-1e-4,
        s3=3e-4,
        s4=-2e-4,
    ),
    "opencv-fisheye": dict(fx=400.0, fy=402.0, cx=160.3, cy=119.6, k1=0.02, k2=-0.01, k3=0.003, k4=-0.0005),
    "ocamcalib": dict(xc=119.6, yc=160.3, c=1.002, d=0.001, e=-0.0015, a0=-400.0, a2=8e-4, a3=-2e-7, a4=3e-10),
    "woodscape": dict(cx=160.3, cy=119.6, aspect_ratio=1.003, k1=400.0, k2=-10.0, k3=5.0, k4=-1.0),
    "double-sphere": dict(fx=300.0, fy=301.0, cx=160.3, cy=119.6, alpha=0.6, xi=-0.2),
    "unified": dict(fx=700.0, fy=702.0, cx=160.3, cy=119.6, xi=0.8, k1=-0.1, k2=0.02, p1=1e-3, p2=-5e-4),
}


def sphere(top_deg: float, rings: int = 40, spokes: int = 36) -> np.ndarray:
    """Unit directions (camera frame: z forward) on rings of polar angle up to `top_deg`."""
    theta, phi = np.meshgrid(
        np.radians(np.linspace(0.0, top_deg, rings)[1:]), np.linspace(0.0, 2 * np.pi, spokes, endpoint=False)
    )
    theta, phi = theta.ravel(), phi.ravel()
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)


@pytest.mark.parametrize("name", MODELS.names())
def test_data_made_by_a_model_is_fitted_back_to_its_coefficients(name):
    m, truth = model(name), TRUTH[name]
    assert set(truth) == set(m.params)
    xyz = sphere(60.0 if m.widest_deg <= 90 else 100.0)
    uv = m.project(truth, xyz)
    assert np.isfinite(uv).all()
    got, fitted, fixed = fit_points(m, xyz, uv, m.start(400.0, (COLUMNS - 1) / 2, (ROWS - 1) / 2))
    assert not fixed and sorted(fitted) == sorted(m.params)
    for k, v in truth.items():
        assert got[k] == pytest.approx(v, rel=1e-6), k


@pytest.fixture(scope="module")
def maps():
    """Each shipped lens's chief-ray mapping over a 320x240 sensor whose width spans its field."""
    out = {}
    for name in shipped_lenses():
        lens = Lens.load(name)
        out[name] = chief_map(lens, Sensor(COLUMNS, ROWS, film_pitch_um(lens, COLUMNS)))
    return out


def traced(cmap, count: int = 400, seed: int = 1):
    """Directions (camera frame) and the tracer's own chief-ray pixels of random fields inside what the
    sensor sees: an independent route from the fit's table."""
    rng = np.random.default_rng(seed)
    lens, px = cmap.lens, cmap.sensor.pitch_um * 1e-3
    cols, rows = cmap.grid(8)
    xyz, inside = cmap.directions(cols, rows)
    top = math.degrees(np.arccos(xyz[inside, 2]).max())
    theta, phi = np.radians(rng.uniform(0, top, count)), rng.uniform(0, 2 * np.pi, count)
    fields = np.stack(lens.field_type.field_of(theta, np.cos(phi), np.sin(phi)), -1)
    chief = chief_rays(lens, fields, np.full(count, cmap.wavelength_nm))
    keep = ~chief.vignetted & (np.hypot(*chief.image_xy.T) <= (cmap.circle_mm or np.inf))
    cx, cy = cmap.sensor.centre
    uv = np.stack([cx + chief.image_xy[:, 0] / px, cy - chief.image_xy[:, 1] / px], -1)
    d = np.stack([np.sin(theta) * np.cos(phi), -np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    inside = (uv[:, 0] >= 0) & (uv[:, 0] <= COLUMNS - 1) & (uv[:, 1] >= 0) & (uv[:, 1] <= ROWS - 1)
    return d[keep & inside], uv[keep & inside]


def opencv_file(cal, tmp_path, suffix):
    path = tmp_path / f"{cal.model}{suffix}"
    path.write_text(write_text(cal, suffix))
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    k, dist = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
    fs.release()
    return k, dist


@pytest.mark.parametrize("lens_name", shipped_lenses())
def test_opencv_projects_the_written_calibrations_onto_the_tracers_chief_rays(lens_name, maps, tmp_path):
    cmap = maps[lens_name]
    xyz, uv = traced(cmap)
    assert len(xyz) > 100
    for name, project in (("opencv-pinhole", cv2.projectPoints), ("opencv-fisheye", cv2.fisheye.projectPoints)):
        try:
            cal = fit(cmap, name)
        except SolasError as exc:  # the pinhole cannot hold a field past 90 deg: refused by name
            assert name == "opencv-pinhole" and cmap.lens.field_type.sideways and name in str(exc)  # noqa: PT017 -- per model
            continue
        for suffix in (".yaml", ".json"):
            k, dist = opencv_file(cal, tmp_path, suffix)
            front = xyz[:, 2] > 1e-6  # OpenCV's projections take points in front of the camera
            got = project(xyz[front].reshape(-1, 1, 3), np.zeros(3), np.zeros(3), k, dist)[0].reshape(-1, 2)
            err = np.hypot(*(got - uv[front]).T)
            bound = cal.max_px + 10 * cal.mapping["interpolation_error_px"] + 1e-6
            assert err.max() <= bound, (name, suffix, err.max(), cal.max_px)


@pytest.mark.parametrize("name", MODELS.names())
def test_every_file_reads_back_as_written(name, tmp_path):
    from solas_mi.optics.calibration.fit import Calibration

    m = model(name)
    extra = {"inverse_polynomial": [1.0, 2.0, 3.0]} if name == "ocamcalib" else {}
    cal = Calibration(
        name,
        dict(TRUTH[name]),
        list(m.params),
        {},
        0.1,
        0.2,
        [1.0, 2.0],
        3.0,
        4,
        {"lens": "test", "sensor_px": [COLUMNS, ROWS], "wavelength_nm": 587.6},
        extra,
    )
    for suffix in m.formats:
        path = tmp_path / f"c{suffix}"
        path.write_text(write_text(cal, suffix))
        got_model, values, size, _ = read(path)
        assert got_model == name and size == (COLUMNS, ROWS)
        assert {k: values[k] for k in m.params} == TRUTH[name]  # bit for bit


@pytest.mark.parametrize(
    "name, option", [("opencv-fisheye", "--fisheye"), ("woodscape", "--fisheye"), ("opencv-pinhole", "--intrinsics")]
)
def test_the_frame_options_read_the_files_as_the_model_projects(name, option, tmp_path):
    from solas_mi.optics.calibration.fit import Calibration

    m = model(name)
    values = dict(TRUTH[name])
    if name == "opencv-pinhole":  # --intrinsics: a pinhole without distortion
        values.update(dict.fromkeys(m.params[4:], 0.0))
    cal = Calibration(name, values, list(m.params), {}, 0.1, 0.2, [1.0, 2.0], 3.0, 4, {"sensor_px": [COLUMNS, ROWS]})
    path = tmp_path / f"c{m.formats[-1]}"
    path.write_text(write_text(cal, m.formats[-1]))
    frame = parse_frame(**{option.lstrip("-"): str(path)})
    xyz = sphere(80.0)
    cols, rows = frame.pixels(xyz[:, 0] / xyz[:, 2], -xyz[:, 1] / xyz[:, 2], COLUMNS, ROWS)
    assert np.stack([cols, rows], -1) == pytest.approx(m.project(values, xyz), abs=1e-9)
    if name == "opencv-pinhole":
        values["k1"] = 0.1
        path.write_text(
            write_text(Calibration(name, values, [], {}, 0, 0, [0, 0], 0, 0, {"sensor_px": [1, 1]}), ".json")
        )
        with pytest.raises(SolasError, match="k1 0.1"):
            parse_frame(**{option.lstrip("-"): str(path)})


def test_bad_inputs_are_refused_by_name_and_nothing_is_written(tmp_path, capsys):
    from solas_mi.cli import main

    out = tmp_path / "cal.yaml"
    cases = [
        (["nikkor-fisheye", "--model", "opencv-pinhole", "--sensor", "320x240", "--pitch-um", "90"], "opencv-pinhole"),
        (["solas-doublet", "--model", "opencv-fisheye", "--sensor", "4x4", "--pitch-um", "9000"], "fewer than 16"),
        (
            [
                "solas-doublet",
                "--model",
                "opencv-fisheye",
                "--sensor",
                "64x48",
                "--pitch-um",
                "5",
                "--wavelength-nm",
                "-3",
            ],
            "-3",
        ),
        (["solas-doublet", "--model", "opencv-fisheye", "--sensor", "64x48", "--pitch-um", "0"], "pitch 0"),
        (["solas-doublet", "--model", "woodscape", "--sensor", "64x48", "--pitch-um", "5"], ".json"),
        (
            [
                "solas-doublet",
                "--model",
                "opencv-fisheye",
                "--sensor",
                "64x48",
                "--pitch-um",
                "5",
                "--focus-distance",
                "-1",
            ],
            "-1",
        ),
    ]
    for args, named in cases:
        assert main(["lens", "calibrate", *args, "-o", str(out)]) == 2
        assert named in capsys.readouterr().err
        assert list(tmp_path.iterdir()) == []


def test_degrade_frame_options_take_the_written_file_as_the_numbers(tmp_path):
    """`--fisheye FILE` gives the frame camera of `--fisheye kannala-brandt:FX,FY,CX,CY,K1..K4` with the file's
    numbers, bit for bit (a fit of the fisheye lens's own mapping, written as OpenCV writes it)."""
    lens = Lens.load("nikkor-fisheye")
    cal = fit(chief_map(lens, Sensor(COLUMNS, ROWS, film_pitch_um(lens, COLUMNS))), "opencv-fisheye")
    path = tmp_path / "kb.yaml"
    path.write_text(write_text(cal, ".yaml"))
    v = cal.values
    numbers = ",".join(repr(v[k]) for k in ("fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"))
    assert parse_frame(fisheye=str(path)) == parse_frame(fisheye=f"kannala-brandt:{numbers}")
