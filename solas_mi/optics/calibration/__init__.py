"""The lens as a calibrated camera: a camera model (`models.MODELS`: OpenCV's pinhole with Brown–Conrady
distortion, OpenCV's fisheye (Kannala–Brandt), OCamCalib, the WoodScape polynomial, double sphere, unified)
fitted to the lens's real chief-ray mapping over a sensor (`mapping`), its residual in pixels (`fit`),
written in the model's own ecosystem's file and read back (`files`). `calibrate` is `solas-mi lens
calibrate`'s work; `describe_camera` the camera block every output records.
"""
from __future__ import annotations

import math

from .mapping import ChiefMap, Sensor, chief_map
from .models import MODELS

__all__ = ["MODELS", "Sensor", "ChiefMap", "chief_map", "calibrate", "describe_camera"]


def calibrate(lens, model: str, sensor: Sensor, wavelengths_nm=None, focus_distance_mm: float | None = None) -> list:
    """`model` (of `MODELS`) fitted to `lens`'s chief-ray mapping over `sensor`, one `fit.Calibration` per
    wavelength of `wavelengths_nm` (None: the lens's primary; several: lateral colour as one calibration
    each), for an object `focus_distance_mm` in front of surface 1 (None: the lens file's; math.inf: infinity)."""
    from .fit import fit

    MODELS.get(model)
    waves = [None] if wavelengths_nm is None else list(wavelengths_nm)
    return [fit(chief_map(lens, sensor, w, focus_distance_mm), model) for w in waves]


def describe_camera(lens, sensor: Sensor, model: str | None, focus_distance_mm: float | None = None,
                    wavelength_nm: float | None = None) -> dict:
    """The camera an output was made with, as its metadata records it: lens, sensor, pitch, focus and the
    fitted calibration of `model` (None: none fitted; `MODELS.default` is the command lines' default)."""
    cmap = chief_map(lens, sensor, wavelength_nm, focus_distance_mm)
    out = {**cmap.describe()}
    if model is not None:
        from .fit import fit

        cal = fit(cmap, model).describe()
        cal.pop("mapping")
        out["calibration"] = cal
    focus = out["focus_distance_mm"]
    out["focus_distance_mm"] = focus if math.isfinite(focus) else "inf"
    return out
