"""A calibration in its ecosystem's file, and back: OpenCV FileStorage YAML or JSON (OpenCV's pinhole and
fisheye models, and the unified model as OpenCV's omnidir writes it), OCamCalib's calib_results.txt,
WoodScape's JSON (`woodscape`) and a Kalibr camera chain (`double-sphere`). Every file carries what it
was fitted to (lens, wavelength, sensor, pitch, focus, residual) beside its parameters: a `solas_mi` map,
or comments after OCamCalib's numbers (its reader stops before them).

`write_text(calibration, suffix)` is the file's text; `read(path)` gives (model, values, (width, height),
metadata) of a file written by solas-mi or by the ecosystem's own tool; `frame_numbers(path, option)` the
frame's camera (`optics.frame.FrameCamera`'s numbers) of a file that the frame options `--fisheye` and
`--intrinsics` take: the parameters as written, so the round trip is exact.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...errors import SolasError
from .filestorage import Matrix, dumps_json, dumps_yaml, loads
from .models import MODELS, CameraModel, ocam_pixels, ocam_rho

OPENCV_DISTORTION = {
    "opencv-pinhole": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4"),
    "opencv-fisheye": ("k1", "k2", "k3", "k4"),
    "unified": ("k1", "k2", "p1", "p2"),
}
INVERSE_TOLERANCE_PX = 1e-4  # OCamCalib's inverse polynomial against its direct one, over the field
MAX_INVERSE_DEGREE = 24
META_KEYS = (
    "lens",
    "lens_hash",
    "wavelength_nm",
    "focus_distance_mm",
    "sensor_px",
    "pitch_um",
    "principal_px",
    "image_circle_radius_px",
    "camera_centre",
    "interpolation_error_px",
)


def ocam_inverse(values: dict, widest_rad: float) -> tuple[list[float], float]:
    """OCamCalib's inverse polynomial (world2cam: ρ = Σ pᵢ tᵢ, t = atan(z/hypot(x, y)) in its frame) over polar
    angles 0 … `widest_rad`: the lowest degree within INVERSE_TOLERANCE_PX of the direct model, and its error (px)."""
    alpha = np.linspace(0.0, widest_rad, 4001)[1:]
    xyz = np.stack([np.sin(alpha), np.zeros_like(alpha), np.cos(alpha)], -1)
    rho = ocam_rho(values, xyz)
    t = alpha - math.pi / 2  # OCamCalib's elevation: its z is our −z
    best = None
    for degree in range(2, MAX_INVERSE_DEGREE + 1):
        coef = np.polynomial.Polynomial.fit(t, rho, degree).convert().coef
        err = float(np.max(np.abs(np.polynomial.polynomial.polyval(t, coef) - rho)))
        if best is None or err < best[1]:
            best = ([float(c) for c in coef], err)
        if err < INVERSE_TOLERANCE_PX:
            break
    return best


def ocam_world2cam(values: dict, xyz: np.ndarray) -> np.ndarray:
    """OCamCalib's world2cam: pixels of directions through the inverse polynomial `values["invpol"]`."""
    t = np.arctan2(np.hypot(xyz[:, 0], xyz[:, 1]), xyz[:, 2]) - math.pi / 2
    return ocam_pixels(values, xyz, np.polynomial.polynomial.polyval(t, values["invpol"]))


def extra_for(m: CameraModel, values: dict, widest_rad: float):
    """What a model's file needs beyond its values, and the projection its users compute (None: the model's)."""
    if m.name == "ocamcalib":
        inverse, err = ocam_inverse(values, widest_rad)
        return (
            {"inverse_polynomial": inverse, "inverse_polynomial_error_px": err},
            lambda v, xyz: ocam_world2cam({**v, "invpol": inverse}, xyz),
        )
    if m.name == "opencv-fisheye" and widest_rad >= math.pi / 2:
        return {
            "note": "cv2.fisheye.projectPoints takes points in front of the camera (z > 0) only; the model's "
            f"own formula holds to {math.degrees(widest_rad):.4g} deg"
        }, None
    return {}, None


def _meta(cal) -> dict:
    m = cal.mapping
    out = {k: m[k] for k in META_KEYS if k in m}
    out.update(
        model=cal.model,
        rms_residual_px=cal.rms_px,
        max_residual_px=cal.max_px,
        max_residual_at_px=cal.max_at_px,
        max_residual_at_deg=cal.max_at_deg,
        fitted=list(cal.fitted),
        fixed_at_zero=list(cal.fixed),
    )
    return out


def _opencv(cal) -> dict:
    v, (w, h) = cal.values, cal.mapping["sensor_px"]
    doc = {
        "model": cal.model,
        "image_width": w,
        "image_height": h,
        "camera_matrix": Matrix(3, 3, (v["fx"], 0.0, v["cx"], 0.0, v["fy"], v["cy"], 0.0, 0.0, 1.0)),
        "distortion_coefficients": Matrix(
            1, len(OPENCV_DISTORTION[cal.model]), tuple(v[k] for k in OPENCV_DISTORTION[cal.model])
        ),
    }
    if cal.model == "unified":
        doc["xi"] = Matrix(1, 1, (v["xi"],))
    return doc


def _ocam_text(cal) -> str:
    v, (w, h) = cal.values, cal.mapping["sensor_px"]
    ss = [v["a0"], 0.0, v["a2"], v["a3"], v["a4"]]
    inv = cal.extra["inverse_polynomial"]
    lines = [
        "#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in MATLAB). These are used by "
        "cam2world",
        "",
        " ".join([str(len(ss))] + [repr(c) for c in ss]),
        "",
        "#polynomial coefficients for the inverse mapping function (ocam_model.invpol in MATLAB). These are used "
        "by world2cam",
        "",
        " ".join([str(len(inv))] + [repr(c) for c in inv]),
        "",
        '#center: "row" and "column", starting from 0 (C convention)',
        "",
        f"{v['xc']!r} {v['yc']!r}",
        "",
        '#affine parameters "c", "d", "e"',
        "",
        f"{v['c']!r} {v['d']!r} {v['e']!r}",
        "",
        '#image size: "height" and "width"',
        "",
        f"{h} {w}",
        "",
    ]
    lines += [f"#solas_mi {k}: {val}" for k, val in _meta(cal).items()]
    return "\n".join(lines) + "\n"


def _woodscape(cal) -> dict:
    v, (w, h) = cal.values, cal.mapping["sensor_px"]
    return {
        "extrinsic": {"quaternion": [0.0, 0.0, 0.0, 1.0], "translation": [0.0, 0.0, 0.0]},
        "intrinsic": {
            "aspect_ratio": v["aspect_ratio"],
            "cx_offset": v["cx"] - (0.5 * w - 0.5),
            "cy_offset": v["cy"] - (0.5 * h - 0.5),
            "height": h,
            "width": w,
            **{k: v[k] for k in ("k1", "k2", "k3", "k4")},
            "model": "radial_poly",
            "poly_order": 4,
        },
        "name": cal.mapping.get("lens", ""),
        "solas_mi": _meta(cal),
    }


def _kalibr(cal) -> dict:
    v = cal.values
    return {
        "cam0": {
            "camera_model": "ds",
            "intrinsics": [v[k] for k in ("xi", "alpha", "fx", "fy", "cx", "cy")],
            "distortion_model": "none",
            "distortion_coeffs": [],
            "resolution": list(cal.mapping["sensor_px"]),
        },
        "solas_mi": _meta(cal),
    }


def check_suffix(model_name: str, path) -> str:
    """The suffix of `path` if `model_name`'s files take it; SolasError naming both otherwise."""
    formats = MODELS.get(model_name).extra["formats"]
    suffix = Path(path).suffix.lower()
    if suffix not in formats:
        raise SolasError(
            f"calibration file {str(path)!r}: a {model_name} calibration is written as {', '.join(formats)}"
        )
    return suffix


def write_text(cal, suffix: str) -> str:
    """The text of `cal`'s file of `suffix` (one of its model's formats)."""
    if cal.model == "ocamcalib":
        return _ocam_text(cal)
    if cal.model == "woodscape":
        return dumps_json(_woodscape(cal))
    if cal.model == "double-sphere":
        return dumps_yaml(_kalibr(cal), header="")
    doc = {**_opencv(cal), "solas_mi": _meta(cal)}
    return dumps_json(doc) if suffix == ".json" else dumps_yaml(doc)


def _numbers(line: str, where: str, number: int) -> list[float]:
    try:
        return [float(t) for t in line.split()]
    except ValueError:
        raise SolasError(
            f"{where}: its line of numbers {number} holds other text (OCamCalib calib_results.txt)"
        ) from None


def _read_ocam(text: str, where: str):
    rows = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if len(rows) < 5:
        raise SolasError(f"{where}: an OCamCalib calib_results.txt has 5 lines of numbers; found {len(rows)}")
    ss, inv, centre, affine, size = (_numbers(r, where, i) for i, r in enumerate(rows[:5], 1))
    if (
        len(ss) < 3
        or int(ss[0]) != len(ss) - 1
        or len(ss) > 6
        or len(centre) != 2
        or len(affine) != 3
        or len(size) != 2
    ):
        raise SolasError(
            f"{where}: the OCamCalib numbers are not ss (its length first, at most 5 terms), invpol, "
            "centre (row, column), affine (c, d, e), size (height, width)"
        )
    a = ss[1:] + [0.0] * (5 - len(ss[1:]))
    if a[1] != 0.0:
        raise SolasError(f"{where}: the direct polynomial's a1 is {a[1]:g}; OCamCalib's model has a1 = 0")
    values = {
        "xc": centre[0],
        "yc": centre[1],
        "c": affine[0],
        "d": affine[1],
        "e": affine[2],
        "a0": a[0],
        "a2": a[2],
        "a3": a[3],
        "a4": a[4],
        "invpol": inv[1:],
    }
    return "ocamcalib", values, (int(size[1]), int(size[0])), {}


def _from_document(doc: dict, where: str, expect: str | None):
    """(model, values, (width, height), metadata) of a FileStorage, WoodScape or Kalibr document."""
    meta = doc.get("solas_mi", {})
    if "intrinsic" in doc:
        i = doc["intrinsic"]
        w, h = int(i["width"]), int(i["height"])
        values = {
            "cx": i["cx_offset"] + 0.5 * w - 0.5,
            "cy": i["cy_offset"] + 0.5 * h - 0.5,
            "aspect_ratio": i.get("aspect_ratio", 1.0),
            **{k: float(i.get(k, 0.0)) for k in ("k1", "k2", "k3", "k4")},
        }
        return "woodscape", values, (w, h), meta
    if "cam0" in doc:
        cam = doc["cam0"]
        if cam.get("camera_model") != "ds" or len(cam.get("intrinsics", [])) != 6:
            raise SolasError(
                f"{where}: a Kalibr camera chain of the double sphere model (camera_model ds, six intrinsics)"
                f" is read; found camera_model {cam.get('camera_model')!r}"
            )
        values = dict(zip(("xi", "alpha", "fx", "fy", "cx", "cy"), map(float, cam["intrinsics"])))
        return "double-sphere", values, tuple(cam.get("resolution", (0, 0))), meta
    name = doc.get("model", expect)
    k, dist = doc.get("camera_matrix"), doc.get("distortion_coefficients")
    if name not in OPENCV_DISTORTION or not isinstance(k, Matrix) or k.rows * k.cols != 9:
        raise SolasError(
            f"{where}: an OpenCV calibration has camera_matrix (3x3) and distortion_coefficients; "
            f"its model ({', '.join(OPENCV_DISTORTION)}) in `model` or by the option that reads it"
        )
    coefs = list(dist.data) if isinstance(dist, Matrix) else []
    names = OPENCV_DISTORTION[name]
    if len(coefs) > len(names) and any(coefs[len(names) :]):
        raise SolasError(
            f"{where}: {len(coefs)} distortion coefficients; a {name} calibration has at most {len(names)}"
        )
    values = {
        "fx": k.data[0],
        "fy": k.data[4],
        "cx": k.data[2],
        "cy": k.data[5],
        **dict(zip(names, coefs + [0.0] * (len(names) - len(coefs)))),
    }
    if name == "unified":
        xi = doc.get("xi")
        values["xi"] = float(xi.data[0] if isinstance(xi, Matrix) else xi)
    return name, values, (int(doc.get("image_width", 0)), int(doc.get("image_height", 0))), meta


def read(path, expect: str | None = None):
    """(model, values, (width, height), solas-mi's metadata or {}) of a calibration file; `expect`: the model
    an OpenCV file that does not name one holds."""
    from ...userfiles import read_text

    where = f"calibration file {str(path)!r}"
    text = read_text(path, "calibration file")
    if Path(path).suffix.lower() == ".txt":
        return _read_ocam(text, where)
    try:
        return _from_document(loads(text, where), where, expect)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise SolasError(f"{where}: a parameter is missing or not a number ({type(exc).__name__})") from None


def frame_numbers(path, option: str) -> tuple[str, tuple[float, ...], tuple[float, ...]]:
    """The frame camera's model, intrinsics and coefficients (`optics.frame.FrameCamera`'s) of the calibration
    file `path` given to `option` (--fisheye: an OpenCV fisheye or WoodScape file; --intrinsics: an OpenCV
    pinhole file without distortion)."""
    model, v, _, _ = read(path, "opencv-fisheye" if option == "--fisheye" else "opencv-pinhole")
    if option == "--fisheye" and model == "opencv-fisheye":
        return "kannala-brandt", (v["fx"], v["fy"], v["cx"], v["cy"]), tuple(v[k] for k in ("k1", "k2", "k3", "k4"))
    if option == "--fisheye" and model == "woodscape":
        return (
            "polynomial",
            (v["k1"], v["k1"], v["cx"], v["cy"]),
            tuple(v[k] for k in ("k1", "k2", "k3", "k4")) + (v["aspect_ratio"],),
        )
    if option == "--intrinsics" and model == "opencv-pinhole":
        bent = {k: v[k] for k in OPENCV_DISTORTION[model] if v[k] != 0.0}
        if bent:
            raise SolasError(
                f"{option} {str(path)!r}: its distortion ({', '.join(f'{k} {x:g}' for k, x in bent.items())})"
                " is not a pinhole's; --intrinsics takes a calibration without distortion"
            )
        return "pinhole", (v["fx"], v["fy"], v["cx"], v["cy"]), ()
    takes = "opencv-fisheye, woodscape" if option == "--fisheye" else "opencv-pinhole"
    raise SolasError(f"{option} {str(path)!r} holds a {model} calibration; {option} takes {takes}")
