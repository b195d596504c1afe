"""The camera models a calibration is written in (`MODELS`, a `solas_mi.registry.Registry`: each entry's
function makes its `CameraModel`), each as its ecosystem projects a point: directions (n, 3) in the camera
frame (x right, y down, z forward: OpenCV's) to pixel positions (n, 2) (columns, rows; (0, 0) the centre
of the top-left pixel).

A model's parameters are named as its files name them; its `stages` are the order in which a fit frees
them (`fit.fit`: the first stage always, each later one where the data determine it and it lowers the
residual). `widest_deg`: the widest polar angle the model can hold (a pinhole's image of 90° is at
infinity).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...registry import Registry

MODELS = Registry("calibration model", default="opencv-fisheye", shown=("formats",))
"""The camera models a lens is calibrated to, by name (a `solas_mi.registry.Registry` of `CameraModel`s, with
the file formats each is written as; the [table of models](registries.md))."""


@dataclass(frozen=True)
class CameraModel:
    """A projection with named parameters: `project(values, xyz)` → (n, 2) pixels (NaN where undefined);
    `start(f_px, cx, cy)` the parameters a fit starts from, one set or a list to try (f_px: the lens's focal
    length in pixels, (cx, cy) where the axis lands); `formats` the file extensions it is written as."""

    name: str
    params: tuple[str, ...]
    stages: tuple[tuple[str, ...], ...]
    project: object
    start: object
    formats: tuple[str, ...]
    widest_deg: float = 180.0
    linear: object = (
        None  # (values, xyz, uv, free names) → values: the free linear parameters solved for, the rest kept
    )

    def vector(self, values: dict) -> np.ndarray:
        return np.array([float(values.get(n, 0.0)) for n in self.params])

    def values(self, vector) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.params, vector)}


def _polar(xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The polar angle θ from +z, the distance from the axis ρ = hypot(x, y), and cos φ, sin φ (1, 0 on the axis)."""
    rho = np.hypot(xyz[:, 0], xyz[:, 1])
    cos = np.divide(xyz[:, 0], rho, out=np.ones_like(rho), where=rho > 0)
    sin = np.divide(xyz[:, 1], rho, out=np.zeros_like(rho), where=rho > 0)
    return np.arctan2(rho, xyz[:, 2]), rho, cos, sin


def brown(x: np.ndarray, y: np.ndarray, v: dict) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's distortion of normalised points: radial k1…k6 (rational), tangential p1, p2, thin prism s1…s4
    (coefficients absent: 0)."""
    g = v.get
    r2 = x * x + y * y
    radial = (1 + r2 * (g("k1", 0) + r2 * (g("k2", 0) + r2 * g("k3", 0)))) / (
        1 + r2 * (g("k4", 0) + r2 * (g("k5", 0) + r2 * g("k6", 0)))
    )
    p1, p2 = g("p1", 0), g("p2", 0)
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) + r2 * (g("s1", 0) + r2 * g("s2", 0))
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y + r2 * (g("s3", 0) + r2 * g("s4", 0))
    return xd, yd


def _camera_matrix(v: dict, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.stack([v["fx"] * x + v["cx"], v["fy"] * y + v["cy"]], axis=-1)


def _pinhole(v: dict, xyz: np.ndarray) -> np.ndarray:
    z = np.where(xyz[:, 2] > 0, xyz[:, 2], np.nan)
    return _camera_matrix(v, *brown(xyz[:, 0] / z, xyz[:, 1] / z, v))


def _kannala_brandt(v: dict, xyz: np.ndarray) -> np.ndarray:
    theta, _, cos, sin = _polar(xyz)
    t2 = theta * theta
    td = theta * (1 + t2 * (v["k1"] + t2 * (v["k2"] + t2 * (v["k3"] + t2 * v["k4"]))))
    return _camera_matrix(v, td * cos, td * sin)


def _woodscape(v: dict, xyz: np.ndarray) -> np.ndarray:
    theta, _, cos, sin = _polar(xyz)
    r = theta * (v["k1"] + theta * (v["k2"] + theta * (v["k3"] + theta * v["k4"])))
    return np.stack([v["cx"] + r * cos, v["cy"] + v["aspect_ratio"] * r * sin], axis=-1)


def _double_sphere(v: dict, xyz: np.ndarray) -> np.ndarray:
    x, y, z = xyz.T
    xi, alpha = v["xi"], v["alpha"]
    d1 = np.sqrt(x * x + y * y + z * z)
    zz = xi * d1 + z
    d2 = np.sqrt(x * x + y * y + zz * zz)
    w1 = alpha / (1 - alpha) if alpha <= 0.5 else (1 - alpha) / alpha
    w2 = (w1 + xi) / math.sqrt(2 * w1 * xi + xi * xi + 1) if 2 * w1 * xi + xi * xi + 1 > 0 else np.nan
    den = np.where(z > -w2 * d1, alpha * d2 + (1 - alpha) * zz, np.nan)  # Usenko et al.'s domain of the projection
    return _camera_matrix(v, x / den, y / den)


def _unified(v: dict, xyz: np.ndarray) -> np.ndarray:
    d = np.linalg.norm(xyz, axis=1)
    den = xyz[:, 2] + v["xi"] * d
    den = np.where(den > 0, den, np.nan)
    return _camera_matrix(v, *brown(xyz[:, 0] / den, xyz[:, 1] / den, v))


def ocam_rho(v: dict, xyz: np.ndarray, iterations: int = 30) -> np.ndarray:
    """OCamCalib's radius ρ (pixels, before the affine map) of directions: the root of f(ρ)·sin α + ρ·cos α = 0
    (α the polar angle from the axis; f(ρ) = a0 + a2ρ² + a3ρ³ + a4ρ⁴, the model's direct polynomial, a1 = 0),
    by Newton's method from the equidistant guess; NaN where it does not converge."""
    alpha, _, _, _ = _polar(xyz)
    s, c = np.sin(alpha), np.cos(alpha)
    a = [v["a0"], 0.0, v["a2"], v["a3"], v["a4"]]
    rho = -a[0] * alpha
    for _ in range(iterations):
        f = a[0] + rho * rho * (a[2] + rho * (a[3] + rho * a[4]))
        df = rho * (2 * a[2] + rho * (3 * a[3] + rho * 4 * a[4]))
        g, dg = f * s + rho * c, df * s + c
        rho = rho - np.divide(g, dg, out=np.full_like(g, np.nan), where=dg != 0)
    f = a[0] + rho * rho * (a[2] + rho * (a[3] + rho * a[4]))
    bad = ~(rho >= 0) | (np.abs(f * s + rho * c) > 1e-9 * np.maximum(1.0, np.abs(a[0])))
    return np.where(bad, np.nan, rho)


def ocam_pixels(v: dict, xyz: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """Pixels of directions at OCamCalib radii ρ: its frame is (row, column, −z) of ours; row = c·x + d·y + xc,
    column = e·x + y + yc with (x, y) = ρ·(y, x)/hypot(x, y) of the direction (OCamCalib's world2cam)."""
    _, _, cos, sin = _polar(xyz)
    x, y = rho * sin, rho * cos
    return np.stack([v["e"] * x + y + v["yc"], v["c"] * x + v["d"] * y + v["xc"]], axis=-1)


def _ocam(v: dict, xyz: np.ndarray) -> np.ndarray:
    return ocam_pixels(v, xyz, ocam_rho(v, xyz))


def _ocam_linear(v: dict, xyz: np.ndarray, uv: np.ndarray, free) -> dict:
    """OCamCalib's direct polynomial solved linearly for its free terms (its own first step): each point's
    offset from the centre undone by the affine map gives ρ, and f(ρ)·sin α + ρ·cos α = 0 is linear in them."""
    terms = [k for k in ("a0", "a2", "a3", "a4") if k in free]
    if not terms:
        return v
    a = np.array([[v["c"], v["d"]], [v["e"], 1.0]])
    x, y = np.linalg.solve(a, np.stack([uv[:, 1] - v["xc"], uv[:, 0] - v["yc"]]))
    rho = np.hypot(x, y)
    alpha = np.arctan2(np.hypot(xyz[:, 0], xyz[:, 1]), xyz[:, 2])
    s, c = np.sin(alpha), np.cos(alpha)
    power = {"a0": 0, "a2": 2, "a3": 3, "a4": 4}
    rhs = -rho * c - sum(v[k] * rho ** power[k] * s for k in power if k not in terms)
    columns = np.stack([rho ** power[k] * s for k in terms], -1)
    norms = np.linalg.norm(columns, axis=0)  # ρ⁴ dwarfs 1: scaled, no column is lost to the others' size
    solved = np.linalg.lstsq(columns / norms, rhs, rcond=None)[0] / norms
    return {**v, **dict(zip(terms, map(float, solved)))}


def _centred(**more):
    def start(f: float, cx: float, cy: float) -> dict:
        return {"fx": f, "fy": f, "cx": cx, "cy": cy, **{k: (v * f if k == "fx_scale" else v) for k, v in more.items()}}

    return start


_FOCAL = ("fx", "fy", "cx", "cy")
_SPECS = {
    "opencv-pinhole": dict(
        summary="OpenCV's pinhole camera with Brown–Conrady distortion: radial k1…k6 (k4…k6 the rational model's "
        "denominator), tangential p1, p2, thin prism s1…s4 (cv2.projectPoints); fields below 90 deg only",
        reference="OpenCV calib3d, camera calibration; Brown (1966), Conrady (1919)",
        params=_FOCAL + ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4"),
        stages=(_FOCAL + ("k1",), ("k2",), ("p1", "p2"), ("k3",), ("k4", "k5", "k6"), ("s1", "s2", "s3", "s4")),
        project=_pinhole,
        start=_centred(),
        formats=(".yaml", ".yml", ".json"),
        widest_deg=90.0,
    ),
    "opencv-fisheye": dict(
        summary="OpenCV's fisheye camera, Kannala–Brandt: θd = θ(1 + k1θ² + k2θ⁴ + k3θ⁶ + k4θ⁸) "
        "(cv2.fisheye.projectPoints, which takes points in front of the camera only)",
        reference="Kannala & Brandt, IEEE TPAMI 28(8), 2006; OpenCV calib3d fisheye",
        params=_FOCAL + ("k1", "k2", "k3", "k4"),
        stages=(_FOCAL, ("k1",), ("k2",), ("k3",), ("k4",)),
        project=_kannala_brandt,
        start=_centred(k1=0.0),
        formats=(".yaml", ".yml", ".json"),
    ),
    "ocamcalib": dict(
        summary="Scaramuzza's omnidirectional model (OCamCalib): direction ∝ (x, y, a0 + a2ρ² + a3ρ³ + a4ρ⁴) of the "
        "pixel's affine-corrected offset (c, d, e) from the centre (xc, yc), with the inverse polynomial "
        "(world2cam) beside it",
        reference="Scaramuzza, Martinelli & Siegwart, IROS 2006; OCamCalib toolbox calib_results.txt",
        params=("xc", "yc", "c", "d", "e", "a0", "a2", "a3", "a4"),
        stages=(("xc", "yc", "c", "d", "e", "a0", "a2"), ("a3",), ("a4",)),
        project=_ocam,
        linear=_ocam_linear,
        start=lambda f, cx, cy: {"xc": cy, "yc": cx, "c": 1.0, "d": 0.0, "e": 0.0, "a0": -f, "a2": 0.5 / f},
        formats=(".txt",),
    ),
    "woodscape": dict(
        summary="the WoodScape fisheye polynomial: radius r = k1θ + k2θ² + k3θ³ + k4θ⁴ pixels, "
        "(u, v) = (cx + r cos φ, cy + aspect_ratio · r sin φ)",
        reference="Yogamani et al., WoodScape, ICCV 2019 (scripts/calibration/projection.py)",
        params=("cx", "cy", "aspect_ratio", "k1", "k2", "k3", "k4"),
        stages=(("cx", "cy", "aspect_ratio", "k1"), ("k2",), ("k3",), ("k4",)),
        project=_woodscape,
        start=lambda f, cx, cy: {"cx": cx, "cy": cy, "aspect_ratio": 1.0, "k1": f},
        formats=(".json",),
    ),
    "double-sphere": dict(
        summary="the double sphere model (fx, fy, cx, cy, xi, alpha), written as a Kalibr camera chain (ds)",
        reference="Usenko, Demmel & Cremers, 3DV 2018",
        params=_FOCAL + ("alpha", "xi"),
        stages=(_FOCAL + ("alpha", "xi"),),
        project=_double_sphere,
        start=lambda f, cx, cy: [_centred(alpha=a, xi=x)(f, cx, cy) for a in (0.3, 0.5, 0.7) for x in (-0.3, 0.0, 0.3)],
        formats=(".yaml", ".yml"),
    ),
    "unified": dict(
        summary="the unified camera model of Mei (fx, fy, cx, cy, xi, radial-tangential k1, k2, p1, p2), written as "
        "OpenCV's omnidir calibration (camera_matrix, distortion_coefficients, xi)",
        reference="Mei & Rives, ICRA 2007; Geyer & Daniilidis 2000; OpenCV contrib omnidir",
        params=_FOCAL + ("xi", "k1", "k2", "p1", "p2"),
        stages=(_FOCAL + ("xi",), ("k1",), ("k2",), ("p1", "p2")),
        project=_unified,  # small angles: fx/(1 + xi) pixels per unit tangent, the lens's focal length
        start=lambda f, cx, cy: [
            {"fx": (1 + xi) * f, "fy": (1 + xi) * f, "cx": cx, "cy": cy, "xi": xi} for xi in (0.25, 0.5, 1.0, 2.0, 4.0)
        ],
        formats=(".yaml", ".yml", ".json"),
    ),
}


def _register(name: str, spec: dict) -> None:
    spec = dict(spec)
    summary, reference = spec.pop("summary"), spec.pop("reference")
    model = CameraModel(name, **spec)
    MODELS.register(name, lambda: model, summary=summary, reference=reference, formats=model.formats)


for _name, _spec in _SPECS.items():
    _register(_name, _spec)


def model(name: str) -> CameraModel:
    """The `CameraModel` of `name` (SolasError listing the models)."""
    return MODELS.get(name).function()
