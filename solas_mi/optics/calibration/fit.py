"""A camera model fitted to a lens's chief-ray mapping (`mapping.ChiefMap`) by least squares on the pixel
residual (SciPy's Levenberg–Marquardt, MINPACK), and the residual over every pixel the lens images.

The fit frees the model's parameters stage by stage (`models.CameraModel.stages`): the first stage always;
each later one is kept where the data determine it (the Jacobian of the residual, its columns scaled to
unit length, has a condition number below `MAX_CONDITION`) and it lowers the RMS residual by more than
`GAIN` (a rotationally symmetric lens leaves tangential and thin-prism terms at 0: they lower nothing);
the others stay 0 and `Calibration.fixed` says why. A model that cannot hold the field is refused by name:
one whose `widest_deg` the field reaches (a pinhole at 90°), and one whose fitted projection is undefined
or folds back (its radius stops growing with the angle) inside the field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...errors import SolasError
from .mapping import ChiefMap
from .models import MODELS, CameraModel
from .models import model as get_model

FIT_SIDE = 64  # fit on about this many pixels along the sensor's longer side
MAX_CONDITION = 1e10
GAIN = 0.01  # a stage must lower the RMS residual by more than this fraction
EXACT_PX = 1e-9  # below this RMS residual (px) nothing is left to explain
CHUNK = 1 << 18  # pixels per block of the residual over the whole sensor


@dataclass
class Calibration:
    """A model's parameters fitted to a lens's mapping, and how well they hold it."""

    model: str
    values: dict[str, float]
    fitted: list[str]
    fixed: dict[str, str]  # parameter → why it stays 0
    rms_px: float
    max_px: float
    max_at_px: list[float]  # (column, row) of the largest residual
    max_at_deg: float  # its polar angle from the axis
    pixels: int  # imaged pixels the residual was taken over
    mapping: dict = field(default_factory=dict)  # `ChiefMap.describe()`
    extra: dict = field(default_factory=dict)  # what a model's file needs beyond its values (OCamCalib's inverse)
    projection: object = None  # (values, xyz) → pixels as the model's users compute them; None: the model's own

    def describe(self) -> dict:
        """The calibration as metadata (JSON values)."""
        return {
            "model": self.model,
            "parameters": dict(self.values),
            "fitted": list(self.fitted),
            "fixed_at_zero": dict(self.fixed),
            "rms_residual_px": self.rms_px,
            "max_residual_px": self.max_px,
            "max_residual_at_px": list(self.max_at_px),
            "max_residual_at_deg": self.max_at_deg,
            "pixels": self.pixels,
            "mapping": dict(self.mapping),
            **self.extra,
        }


def _solve(m: CameraModel, start: np.ndarray, free: list[int], xyz: np.ndarray, uv: np.ndarray):
    """Least squares over the parameters `free` (indices) from `start` (its linear ones first solved for, where
    the model has such: `CameraModel.linear`): (vector, RMS px, condition number)."""
    from scipy.optimize import least_squares

    if m.linear is not None:
        start = m.vector(m.linear(m.values(start), xyz, uv, [m.params[i] for i in free]))

    def residual(q):
        p = start.copy()
        p[free] = q
        r = (m.project(m.values(p), xyz) - uv).ravel()
        return np.where(np.isfinite(r), r, 1e6)

    got = least_squares(
        residual,
        start[free],
        method="lm",
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=100 * (len(free) + 1),
    )
    p = start.copy()
    p[free] = got.x
    jac = got.jac / np.maximum(np.linalg.norm(got.jac, axis=0), 1e-300)
    s = np.linalg.svd(jac, compute_uv=False)
    return p, float(np.sqrt(np.mean(got.fun**2) * 2)), float(s[0] / s[-1]) if s[-1] > 0 else math.inf


def fit_points(m: CameraModel, xyz: np.ndarray, uv: np.ndarray, start) -> tuple[dict, list[str], dict]:
    """The parameters of `m` fitted to directions `xyz` (n, 3) landing at pixels `uv` (n, 2), from `start` (a
    dict, or a list of them: the first stage from each, the best kept): (values, fitted names, fixed → why).
    A stage that lowers nothing alone is held and tried again with the next (radial terms that only together
    with the next one reach past a centre's or ξ's share); kept with it only if leaving it out again costs."""
    first = [m.params.index(n) for n in m.stages[0]]
    tried = [_solve(m, m.vector(s), first, xyz, uv) for s in (start if isinstance(start, list) else [start])]
    p, rms, _ = min(tried, key=lambda t: t[1] if math.isfinite(t[1]) else math.inf)
    free, fixed, held = list(first), {}, []
    for stage in m.stages[1:]:
        if rms < EXACT_PX:
            fixed.update(dict.fromkeys(stage, f"the fit already holds to {rms:.1e} px"))
            continue
        trial = free + [m.params.index(n) for n in [*held, *stage]]
        q, rms_q, condition = _solve(m, p, trial, xyz, uv)
        if condition > MAX_CONDITION:
            fixed.update(dict.fromkeys(stage, f"not determined by the mapping (condition number {condition:.1e})"))
        elif not rms_q < (1 - GAIN) * rms:
            held += stage
            fixed.update(
                dict.fromkeys(
                    stage, f"lowers the RMS residual by less than {100 * GAIN:g} % ({rms:.3g} to {rms_q:.3g} px)"
                )
            )
        else:
            p, rms, free = q, rms_q, trial
            for n in held:
                del fixed[n]
            p, rms, free = _drop_held(m, p, rms, free, held, xyz, uv, fixed)
            held = []
    values = m.values(p)
    for n in fixed:
        values[n] = 0.0
    return values, [m.params[i] for i in sorted(free)], fixed


def _drop_held(m: CameraModel, p, rms, free, held, xyz, uv, fixed):
    """Each held parameter left out again (at 0) where that costs less than GAIN of the RMS residual."""
    for n in held:
        i = m.params.index(n)
        without = [j for j in free if j != i]
        q = p.copy()
        q[i] = 0.0
        q, rms_q, _ = _solve(m, q, without, xyz, uv)
        if rms_q < (1 + GAIN) * rms:
            p, rms, free = q, rms_q, without
            fixed[n] = f"adds less than {100 * GAIN:g} % to the RMS residual when left out ({rms_q:.3g} px)"
    return p, rms, free


def check_holds(m: CameraModel, cmap: ChiefMap, widest_rad: float) -> None:
    """SolasError naming the model when the field reaches its `widest_deg`."""
    if math.degrees(widest_rad) >= m.widest_deg:
        wider = [n for n in MODELS if get_model(n).widest_deg > math.degrees(widest_rad)]
        raise SolasError(
            f"calibration model {m.name} cannot hold the field of lens {cmap.lens.name} on this sensor: it "
            f"reaches {math.degrees(widest_rad):.4g} deg from the axis, and {m.name} holds less than "
            f"{m.widest_deg:g} deg; choose a model that holds it: {', '.join(wider)}"
        )


def _check_fitted(m: CameraModel, values: dict, cmap: ChiefMap, widest_rad: float) -> None:
    """SolasError naming the model when its fitted projection is undefined or folds back inside the field."""
    theta = np.linspace(0.0, widest_rad, 2049)
    for azimuth in (0.0, math.pi / 2):
        xyz = np.stack([np.sin(theta) * math.cos(azimuth), np.sin(theta) * math.sin(azimuth), np.cos(theta)], -1)
        uv = m.project(values, xyz)
        radius = np.hypot(*(uv - uv[0]).T)
        if not np.all(np.isfinite(uv)) or not np.all(np.diff(radius) > 0):
            bad = int(np.argmax(~np.isfinite(uv).all(axis=1) | np.r_[False, np.diff(radius) <= 0]))
            raise SolasError(
                f"calibration model {m.name} cannot hold the field of lens {cmap.lens.name}: fitted to it, "
                f"its projection is {'undefined' if not np.isfinite(uv[bad]).all() else 'folded back'} "
                f"at {math.degrees(theta[bad]):.4g} deg of the {math.degrees(widest_rad):.4g} deg the "
                "sensor reaches; choose another model"
            )


def residual_map(m: CameraModel, values: dict, cmap: ChiefMap, project=None) -> np.ndarray:
    """The residual (px) of `values` at every pixel (H×W; NaN outside the image circle), in blocks of CHUNK
    pixels. `project(values, xyz)`: the projection the model's users compute (default: the model's)."""
    project = m.project if project is None else project
    w, h = cmap.sensor.width, cmap.sensor.height
    out = np.full((h, w), np.nan)
    step = max(1, CHUNK // w)
    for r0 in range(0, h, step):
        c, r = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(r0, min(h, r0 + step), dtype=np.float64))
        xyz, inside = cmap.directions(c.ravel(), r.ravel())
        err = np.full(inside.shape, np.nan)
        err[inside] = np.hypot(*(project(values, xyz[inside]) - np.stack([c.ravel(), r.ravel()], -1)[inside]).T)
        out[r0 : r0 + c.shape[0]] = np.where(inside & ~np.isfinite(err), np.inf, err).reshape(c.shape)
    return out


def residuals(m: CameraModel, values: dict, cmap: ChiefMap, project=None) -> dict:
    """RMS and largest residual (px) of `values` over every pixel the lens images, where the largest lies
    (pixel, polar angle) and how many pixels (`residual_map`)."""
    err = residual_map(m, values, cmap, project)
    imaged = ~np.isnan(err)
    k = np.unravel_index(int(np.argmax(np.where(imaged, err, -1.0))), err.shape)
    xyz, _ = cmap.directions(np.array([float(k[1])]), np.array([float(k[0])]))
    return {
        "rms_px": float(np.sqrt(np.mean(err[imaged] ** 2))),
        "max_px": float(err[k]),
        "max_at_px": [float(k[1]), float(k[0])],
        "max_at_deg": math.degrees(math.acos(min(1.0, xyz[0, 2]))),
        "pixels": int(imaged.sum()),
    }


def fit(cmap: ChiefMap, model_name: str) -> Calibration:
    """`model_name` (of `models.MODELS`) fitted to the lens's mapping `cmap`, its residual over every imaged pixel."""
    from .files import extra_for

    m = get_model(model_name)
    stride = max(1, math.ceil(max(cmap.sensor.width, cmap.sensor.height) / FIT_SIDE))
    cols, rows = cmap.grid(stride)
    xyz, inside = cmap.directions(cols, rows)
    widest = float(np.max(np.arccos(np.clip(xyz[inside, 2], -1.0, 1.0))))
    check_holds(m, cmap, widest)
    focal_px = float(cmap.spline(1e-3) / 1e-3) / (cmap.sensor.pitch_um * 1e-3)
    values, fitted, fixed = fit_points(
        m, xyz[inside], np.stack([cols, rows], -1)[inside], m.start(focal_px, *cmap.sensor.centre)
    )
    _check_fitted(m, values, cmap, widest)
    extra, project = extra_for(m, values, widest)
    stats = residuals(m, values, cmap, project)
    return Calibration(
        model_name,
        values,
        fitted,
        fixed,
        stats["rms_px"],
        stats["max_px"],
        stats["max_at_px"],
        stats["max_at_deg"],
        stats["pixels"],
        cmap.describe(),
        extra,
        project,
    )
