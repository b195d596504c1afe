"""The lens as a calibrated camera: a camera model (`models.MODELS`: OpenCV's pinhole with Brown–Conrady
distortion, OpenCV's fisheye (Kannala–Brandt), OCamCalib, the WoodScape polynomial, double sphere, unified)
fitted to the lens's real chief-ray mapping over a sensor (`mapping`), its residual in pixels (`fit`),
written in the model's own ecosystem's file and read back (`files`). `calibrate` is `solas-mi lens
calibrate`'s work; `describe_camera` the camera block every output records, fitted once per lens, sensor and model and kept in the
user's cache folder (`caches.RecordCache`).
"""

from __future__ import annotations

import math

from ...caches import RecordCache
from .mapping import ChiefMap, Sensor, chief_map
from .models import MODELS

# the version of the chief-ray table and the fit: raise it when a change makes `describe_camera` record another
# block for the same lens and sensor (the cache of fitted cameras keys its records by it)
FIT_VERSION = 1

CAMERAS = RecordCache("cameras", "camera fit")  # the cache of fitted cameras: `describe_camera`'s blocks

__all__ = ["MODELS", "Sensor", "ChiefMap", "chief_map", "calibrate", "describe_camera"]


def calibrate(lens, model: str, sensor: Sensor, wavelengths_nm=None, focus_distance_mm: float | None = None) -> list:
    """Fit a camera model to a lens's chief-ray mapping over a sensor (``solas-mi lens calibrate``).

    Parameters
    ----------
    lens : Lens
        The lens.
    model : str
        A name of `MODELS`.
    sensor : Sensor
        The sensor.
    wavelengths_nm : sequence of float, optional
        One calibration per wavelength (lateral colour as one calibration each); default: the lens's primary.
    focus_distance_mm : float, optional
        The object's distance in front of surface 1 (mm; math.inf: infinity); default: the lens file's.

    Returns
    -------
    list of fit.Calibration
        One per wavelength: the model's fitted values and its residual (px).

    Examples
    --------
    >>> from solas_mi import Lens
    >>> from solas_mi.optics.calibration import Sensor, calibrate
    >>> [fitted] = calibrate(Lens.load("solas-doublet"), "opencv-pinhole", Sensor(64, 48, 50.0))
    >>> fitted.model, fitted.rms_px < 0.01
    ('opencv-pinhole', True)
    """
    from .fit import fit

    MODELS.get(model)
    waves = [None] if wavelengths_nm is None else list(wavelengths_nm)
    return [fit(chief_map(lens, sensor, w, focus_distance_mm), model) for w in waves]


def describe_camera(
    lens, sensor: Sensor, model: str | None, focus_distance_mm: float | None = None, wavelength_nm: float | None = None
) -> dict:
    """The camera an output was made with, as its metadata records it.

    Parameters
    ----------
    lens : Lens
        The lens.
    sensor : Sensor
        The sensor.
    model : str or None
        The calibration model fitted (`MODELS`; its default is the command lines'); None: none.
    focus_distance_mm : float, optional
        The object's distance in front of surface 1 (mm); default: the lens file's.
    wavelength_nm : float, optional
        The wavelength (nm); default: the lens's primary.

    Returns
    -------
    dict
        Lens, sensor, pitch, focus ("inf" at infinity), the mapping's description and the fitted
        calibration (without its mapping), as JSON reads it back: fitted once and kept in the cache of
        fitted cameras (``cameras`` in `caches.cache_root`, keyed by `camera_key`), read back after.
    """
    block, _ = CAMERAS.get(
        camera_key(lens, sensor, model, focus_distance_mm, wavelength_nm),
        lambda: _camera_block(lens, sensor, model, focus_distance_mm, wavelength_nm),
    )
    return block


def camera_cached(
    lens, sensor: Sensor, model: str | None, focus_distance_mm: float | None = None, wavelength_nm: float | None = None
) -> bool:
    """Whether `describe_camera` of these arguments reads its block back from the cache (fits nothing)."""
    return CAMERAS.holds(camera_key(lens, sensor, model, focus_distance_mm, wavelength_nm))


def camera_key(
    lens, sensor: Sensor, model: str | None, focus_distance_mm: float | None, wavelength_nm: float | None
) -> dict:
    """Everything `describe_camera`'s block depends on, the key of its record in the cache of fitted cameras:
    the lens (its name, the hash of its prescription and what else its mapping reads: its stated field, image
    diameter and wavelengths), the sensor, model, focus, wavelength, `FIT_VERSION` and solas-mi's version."""
    from ...resources import installed_version

    return {
        "fit_version": FIT_VERSION,
        "solas_mi": installed_version(),
        "lens": {
            "name": lens.name,
            "hash": lens.hash,
            "field_deg": lens.field_deg,
            "image_diameter": lens.image_diameter,
            "wavelengths_nm": list(lens.wavelengths_nm),
        },
        "sensor": sensor.describe(),
        "model": model,
        "focus_distance_mm": focus_distance_mm,
        "wavelength_nm": wavelength_nm,
    }


def _camera_block(
    lens, sensor: Sensor, model: str | None, focus_distance_mm: float | None, wavelength_nm: float | None
) -> dict:
    """`describe_camera`'s block, traced and fitted."""
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
