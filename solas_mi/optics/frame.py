"""The camera a frame was taken with (a dataset's or a simulator's): how its pixels map to field angles.

Models (pixel centres at integer coordinates, (0, 0) the top-left pixel's centre; x right, y up in
the scene, rows down):
- "fov": an ideal pinhole frame whose half field of view `fov_deg` spans its width ("x"), height ("y")
  or diagonal, the axis at the frame's centre;
- "pinhole": intrinsics fx, fy (pixels per unit tangent), cx, cy (the axis's column and row), as
  calibrations publish them (OpenCV's camera matrix);
- "kannala-brandt": the fisheye model of Kannala & Brandt (2006), OpenCV's `fisheye` module: the
  ray at angle θ from the axis lands at radius θ_d = θ(1 + k1θ² + k2θ⁴ + k3θ⁶ + k4θ⁸) in normalised
  coordinates, (u, v) = (fx·θ_d·cos φ + cx, fy·θ_d·sin φ + cy);
- "polynomial": the fisheye polynomial automotive datasets publish (e.g. WoodScape): radius in
  pixels r(θ) = a1·θ + a2·θ² + a3·θ³ + a4·θ⁴, (u, v) = (cx + r·cos φ, cy + aspect·r·sin φ).

`field_deg` gives every pixel's field angle (θx, θy) = (atan tan_x, atan tan_y) of its direction, the
convention of `optics.camera` and of PSF grids; `extent_deg` the largest |θx|, |θy| the frame reaches
(at its pixels' outer edges), which the lens's PSF grid must cover.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError

FRAME_MODELS = ("fov", "pinhole", "kannala-brandt", "polynomial")
FOV_AXES = ("x", "y", "diagonal")
FISHEYE = ("kannala-brandt", "polynomial")


@dataclass(frozen=True)
class FrameCamera:
    """A frame's camera: `model` (FRAME_MODELS) and its numbers (see the module docstring)."""

    model: str
    fov_deg: float | None = None
    fov_axis: str = "x"
    intrinsics: tuple[float, float, float, float] | None = None  # fx, fy, cx, cy (pixels)
    coefficients: tuple[float, ...] = ()  # kannala-brandt: k1…k4; polynomial: a1…a4 (then aspect, optional)

    def __post_init__(self):
        if self.model not in FRAME_MODELS:
            raise SolasError(f"frame camera model {self.model!r} must be one of {', '.join(FRAME_MODELS)}")
        if self.model == "fov":
            if not (isinstance(self.fov_deg, (int, float)) and 0 < self.fov_deg < 89):
                raise SolasError(f"frame field of view {self.fov_deg!r} deg must be a half angle in (0, 89)")
            if self.fov_axis not in FOV_AXES:
                raise SolasError(f"field of view axis {self.fov_axis!r} must be one of {', '.join(FOV_AXES)}")
            return
        k = self.intrinsics
        if not (k is not None and len(k) == 4 and all(math.isfinite(v) for v in k) and k[0] > 0 and k[1] > 0):
            raise SolasError(f"frame intrinsics {k!r} must be fx, fy, cx, cy (pixels), fx and fy positive")
        want = {"pinhole": (0, 0), "kannala-brandt": (4, 4), "polynomial": (1, 5)}[self.model]
        if not (want[0] <= len(self.coefficients) <= want[1] and all(math.isfinite(c) for c in self.coefficients)):
            raise SolasError(
                f"{self.model} coefficients {list(self.coefficients)} must be {want[0]}"
                f"{'' if want[0] == want[1] else f' to {want[1]}'} finite numbers"
            )

    def pinhole(self, width: int, height: int) -> tuple[float, float, float, float]:
        """fx, fy, cx, cy of a rectilinear frame of width×height pixels ("fov" or "pinhole")."""
        if self.model == "pinhole":
            return self.intrinsics
        if self.model in FISHEYE:
            raise SolasError(f"a {self.model} frame has no pinhole intrinsics")
        half = {"x": width / 2, "y": height / 2, "diagonal": math.hypot(width, height) / 2}[self.fov_axis]
        f = half / math.tan(math.radians(self.fov_deg))
        return f, f, width / 2 - 0.5, height / 2 - 0.5

    def focal_px(self) -> float:
        """The focal length in pixels on the axis: fx (pixels per unit tangent, or per radian in a fisheye);
        a polynomial's a1. SolasError for "fov" (it depends on the frame's width) and for fx ≠ fy."""
        if self.model == "fov":
            raise SolasError(
                "a frame given by --fov-deg has its focal length in pixels only with its width: give "
                "--intrinsics FX,FY,CX,CY (or --fisheye)"
            )
        if self.model == "polynomial":
            return float(self.coefficients[0])
        fx, fy = self.intrinsics[:2]
        if abs(fx / fy - 1) > 1e-3:
            raise SolasError(f"frame intrinsics fx {fx:g}, fy {fy:g} px: one focal length needs square pixels")
        return float(fx)

    def tangents(
        self, cols: np.ndarray, rows: np.ndarray, width: int, height: int, clamp: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        """The direction (tan_x, tan_y) of pixel positions (cols, rows) (continuous); positions beyond a fisheye
        model's 90 deg are refused, or with `clamp` taken at 90 deg (padding around a frame)."""
        if self.model not in FISHEYE:
            fx, fy, cx, cy = self.pinhole(width, height)
            return (np.asarray(cols) - cx) / fx, (cy - np.asarray(rows)) / fy
        fx, fy, cx, cy = self.intrinsics
        if self.model == "kannala-brandt":
            dx, dy = (np.asarray(cols) - cx) / fx, (np.asarray(rows) - cy) / fy
            theta = _invert(
                lambda t: t * (1 + sum(k * t ** (2 * i + 2) for i, k in enumerate(self.coefficients))),
                np.hypot(dx, dy),
                clamp,
            )
        else:
            a, aspect = self.coefficients[:4], (self.coefficients[4] if len(self.coefficients) > 4 else 1.0)
            dx, dy = np.asarray(cols) - cx, (np.asarray(rows) - cy) / aspect
            theta = _invert(lambda t: sum(c * t ** (i + 1) for i, c in enumerate(a)), np.hypot(dx, dy), clamp)
        r = np.hypot(dx, dy)
        scale = np.divide(np.tan(np.minimum(theta, math.radians(89.9))), r, out=np.zeros_like(r), where=r > 0)
        return dx * scale, -dy * scale

    def pixels(self, tan_x: np.ndarray, tan_y: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """The pixel position (columns, rows) (continuous) of directions (tan_x, tan_y): `tangents` inverted."""
        tan_x, tan_y = np.asarray(tan_x, dtype=np.float64), np.asarray(tan_y, dtype=np.float64)
        if self.model not in FISHEYE:
            fx, fy, cx, cy = self.pinhole(width, height)
            return cx + fx * tan_x, cy - fy * tan_y
        fx, fy, cx, cy = self.intrinsics
        theta, phi = np.arctan(np.hypot(tan_x, tan_y)), np.arctan2(tan_y, tan_x)
        if self.model == "kannala-brandt":
            r = theta * (1 + sum(k * theta ** (2 * i + 2) for i, k in enumerate(self.coefficients)))
            return cx + fx * r * np.cos(phi), cy - fy * r * np.sin(phi)
        a, aspect = self.coefficients[:4], (self.coefficients[4] if len(self.coefficients) > 4 else 1.0)
        r = sum(c * theta ** (i + 1) for i, c in enumerate(a))
        return cx + r * np.cos(phi), cy - aspect * r * np.sin(phi)

    def extent_deg(self, width: int, height: int) -> tuple[float, float]:
        """The largest |θx| and |θy| (degrees) of the frame's pixels, at their outer edges."""
        cs, rs = np.linspace(-0.5, width - 0.5, 2 * width + 1), np.linspace(-0.5, height - 0.5, 2 * height + 1)
        c = np.concatenate([cs, cs, np.full_like(rs, -0.5), np.full_like(rs, width - 0.5)])
        r = np.concatenate([np.full_like(cs, -0.5), np.full_like(cs, height - 0.5), rs, rs])
        tx, ty = self.tangents(c, r, width, height)
        return float(np.degrees(np.arctan(np.abs(tx)).max())), float(np.degrees(np.arctan(np.abs(ty)).max()))

    def meta(self, width: int, height: int) -> dict:
        out = {"model": self.model, "extent_deg": list(self.extent_deg(width, height))}
        if self.model == "fov":
            out.update(fov_deg=self.fov_deg, fov_axis=self.fov_axis)
        out.update(intrinsics_px=list(self.intrinsics if self.model != "fov" else self.pinhole(width, height)))
        if self.coefficients:
            out["coefficients"] = list(self.coefficients)
        return out


def _invert(fn, radius: np.ndarray, clamp: bool = False) -> np.ndarray:
    """θ in [0, π/2] with fn(θ) = radius, fn increasing there (a table, interpolated); SolasError if it is not,
    or if a radius lies beyond fn(π/2) (with `clamp`: π/2 there)."""
    t = np.linspace(0.0, math.pi / 2, 4097)
    r = fn(t)
    if not np.all(np.diff(r) > 0):
        raise SolasError(
            "the fisheye model's radius does not grow with the angle from the axis up to 90 deg: check its coefficients"
        )
    if np.max(radius) > r[-1] and not clamp:
        raise SolasError(
            f"a pixel lies {float(np.max(radius)):.4g} from the axis, beyond the model's 90 deg "
            f"({r[-1]:.4g}): the frame reaches past 90 deg, which no lens of solas-mi covers"
        )
    return np.interp(radius, r, t)


def parse_frame(
    fov: str | None = None, axis: str = "x", intrinsics: str | None = None, fisheye: str | None = None
) -> FrameCamera | None:
    """The command line's frame camera: --fov-deg (with --fov-axis), --intrinsics FX,FY,CX,CY or
    --fisheye MODEL:FX,FY,CX,CY,C1,…, or either as a calibration file (`calibration.files.frame_numbers`: an
    OpenCV pinhole file without distortion; an OpenCV fisheye or WoodScape file); None when none is given."""
    from ..options import floats
    from .calibration.files import frame_numbers

    given = [v for v in (fov, intrinsics, fisheye) if v is not None]
    if len(given) > 1:
        raise SolasError("give one frame camera: --fov-deg, --intrinsics or --fisheye")
    if fov is not None:
        return FrameCamera("fov", fov_deg=float(fov), fov_axis=axis)
    for option, text in (("--intrinsics", intrinsics), ("--fisheye", fisheye)):
        if text is not None and _is_file(text):
            model, numbers, coefficients = frame_numbers(text, option)
            return FrameCamera(model, intrinsics=numbers, coefficients=coefficients)
    if intrinsics is not None:
        values = floats(intrinsics, "--intrinsics")
        if len(values) != 4:
            raise SolasError(f"--intrinsics {intrinsics!r} must be FX,FY,CX,CY (pixels)")
        return FrameCamera("pinhole", intrinsics=tuple(values))
    if fisheye is not None:
        model, _, numbers = fisheye.partition(":")
        values = floats(numbers, "--fisheye")
        if model not in FISHEYE or len(values) < 5:
            raise SolasError(
                f"--fisheye {fisheye!r} must be MODEL:FX,FY,CX,CY,C1,... with MODEL one of {', '.join(FISHEYE)}"
            )
        return FrameCamera(model, intrinsics=tuple(values[:4]), coefficients=tuple(values[4:]))
    return None


def _is_file(text: str) -> bool:
    """Whether a frame option's text names a file (a calibration) rather than numbers."""
    from pathlib import Path

    return Path(text).suffix.lower() in (".yaml", ".yml", ".json", ".txt") and Path(text).exists()
