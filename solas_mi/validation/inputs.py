"""The cross-validation's input image: read, checked and resampled to the sensor's grid, and the
cos³θ weight of its pixels.

The input is the ideal (pinhole) image spanning ±fov_deg horizontally; its pixel grid is the sensor
(`optics.camera`). Values are linear (PNG/JPEG are sRGB-decoded unless declared linear), H×W×3
float64, in arbitrary radiance units L that the engines' outputs carry on.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError


def load_input(
    image: str | np.ndarray, sensor: tuple[int, int] | None = None, scale: float | None = None, linear: bool = False
) -> np.ndarray:
    """The linear H×W×3 float64 input image, resampled (area average) to sensor (rows, columns) or by
    `scale`. PNG/JPEG are sRGB-decoded unless `linear`; a one-channel image is repeated as R, G, B."""
    from ..imageio import read_image

    if isinstance(image, np.ndarray):
        arr = np.asarray(image, dtype=np.float64)
    else:
        arr = read_image(image, linearize=not linear)
    if arr.ndim == 2:
        arr = np.repeat(arr[..., None], 3, axis=-1)
    if arr.ndim != 3 or arr.shape[-1] != 3 or min(arr.shape[:2]) < 8:
        raise SolasError(f"input image of shape {arr.shape} must be H×W (grey) or H×W×3 (RGB), at least 8×8 px")
    if not np.all(np.isfinite(arr)) or arr.min() < 0:
        raise SolasError("input image must hold finite, non-negative linear values")
    if sensor is not None and scale is not None:
        raise SolasError("give either a sensor size or a scale, not both")
    if scale is not None:
        if not (isinstance(scale, (int, float)) and 0 < scale <= 1):
            raise SolasError(f"scale {scale!r} must lie in (0, 1]")
        sensor = (max(8, round(arr.shape[0] * scale)), max(8, round(arr.shape[1] * scale)))
    if sensor is not None and tuple(sensor) != arr.shape[:2]:
        arr = resample(arr, sensor)
    return arr


def resample(arr: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Area-average resampling to (rows, columns): exact block means for integer factors."""
    h, w = arr.shape[:2]
    rows, cols = shape
    if rows > h or cols > w:
        raise SolasError(f"sensor {cols}x{rows} is larger than the image ({w}x{h}); only downscaling is supported")
    if h % rows == 0 and w % cols == 0:
        fy, fx = h // rows, w // cols
        return arr.reshape(rows, fy, cols, fx, arr.shape[2]).mean(axis=(1, 3))
    from skimage.transform import resize

    return resize(arr, (rows, cols, arr.shape[2]), order=1, anti_aliasing=True, preserve_range=True)


def tangent_cos3(width: int, height: int, fov_deg: float) -> np.ndarray:
    """cos³θ (H, W) of each input pixel's direction: (1 + tx² + ty²)^−3/2 with camera.py's tangents
    (the solid angle of a texel uniform in tangent space, relative to the axis's)."""
    t = math.tan(math.radians(fov_deg)) / (width / 2)
    tx = (np.arange(width) + 0.5 - width / 2) * t
    ty = (height / 2 - np.arange(height) - 0.5) * t
    return (1.0 + tx[None, :] ** 2 + ty[:, None] ** 2) ** -1.5
