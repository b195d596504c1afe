"""The camera both degradation engines share: a lens, a sensor on its image plane, and the ideal
(pinhole) image that an input image stands for.

An input image is the scene as seen through an ideal rectilinear lens: its width spans ±fov_deg
horizontally and its pixels are square in tangent space, so the pixel at (column c, row r) of a W×H
image is the direction with tangents

    tan_x = (c + 0.5 − W/2)·t,   tan_y = (H/2 − r − 0.5)·t,   t = tan(fov_deg)/(W/2).

The ideal image of direction (tan_x, tan_y) on the image plane is focal_mm·(tan_x, tan_y). The pinhole
focal length is the real lens's: the real chief ray of field (fov_deg, 0) at the reference
wavelength lands at focal_mm·tan(fov_deg), so the ideal and the real image agree at the middle of the
left and right edges; everywhere else the real chief ray's offset from the ideal point is the lens's
distortion and lateral colour. The sensor is W×H pixels of pitch_um centred on the axis, row 0 at the
top (+y); by default it is the input image's grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from .lens import Lens

DEFAULT_SENSOR = (960, 1280)  # rows, columns
# What lies outside the input image, for both engines: the border repeated, mirrored, or black.
BOUNDARIES = ("edge", "reflect", "zero")
# How an input image maps to directions (plugins/image_object.py); rectilinear is the ideal pinhole image above.
MAPPINGS = ("rectilinear", "equidistant", "equisolid", "equirectangular")


@dataclass(frozen=True)
class Camera:
    """A sensor (width×height pixels of pitch_um) and the ideal image's pinhole focal length (mm)."""

    width: int
    height: int
    pitch_um: float
    focal_mm: float
    fov_deg: float  # half the horizontal field the default input image spans
    wavelength_nm: float  # reference wavelength of focal_mm
    # "rectilinear": the input image is the ideal pinhole image above; "sensor": it is already the
    # sensor image in the lens's own projection (PSF grids laid out on the sensor; focal_mm, fov_deg unused);
    # "frame": a fisheye frame's pixels, mapped to field angles by its calibration (`convolution.curved`)
    projection: str = "rectilinear"
    principal: tuple[float, float] | None = None  # (column, row) of the axis; None: the centre (W/2 − ½, H/2 − ½)

    @property
    def centre(self) -> tuple[float, float]:
        return self.principal if self.principal is not None else (self.width / 2 - 0.5, self.height / 2 - 0.5)

    @property
    def pitch_mm(self) -> float:
        return self.pitch_um * 1e-3

    def pixel_x_mm(self) -> np.ndarray:
        """Column centres on the image plane (mm), left to right."""
        return (np.arange(self.width) + 0.5 - self.width / 2) * self.pitch_mm

    def pixel_y_mm(self) -> np.ndarray:
        """Row centres on the image plane (mm), top (+y) to bottom."""
        return (self.height / 2 - np.arange(self.height) - 0.5) * self.pitch_mm

    def ideal_mm(self, field_deg: np.ndarray) -> np.ndarray:
        """Ideal image points (…, 2) in mm of fields (…, 2) in degrees."""
        return self.focal_mm * np.tan(np.radians(np.asarray(field_deg, dtype=np.float64)))

    def ideal_pixel(self, field_deg: np.ndarray) -> np.ndarray:
        """Ideal image points of fields (…, 2) as (column, row) pixel coordinates (continuous; the centre
        of pixel (c, r) is (c, r))."""
        xy = self.ideal_mm(field_deg) / self.pitch_mm
        cx, cy = self.centre
        return np.stack([xy[..., 0] + cx, cy - xy[..., 1]], axis=-1)

    def input_tangent_pitch(self, input_width: int, fov_deg: float | None = None) -> float:
        """Tangent-space size of one pixel of an input image `input_width` wide spanning ±fov_deg."""
        return math.tan(math.radians(self.fov_deg if fov_deg is None else fov_deg)) / (input_width / 2)

    def meta(self) -> dict:
        if self.projection == "sensor":
            return {
                "sensor": [self.width, self.height],
                "pitch_um": self.pitch_um,
                "reference_wavelength_nm": self.wavelength_nm,
                "projection": "sensor: the input image is the sensor image in the lens's own projection; PSF grid "
                "nodes sit at their chief rays' image points",
            }
        if self.projection == "frame":
            return {
                "sensor": [self.width, self.height],
                "pitch_um_at_axis": self.pitch_um,
                "pinhole_focal_mm": self.focal_mm,
                "reference_wavelength_nm": self.wavelength_nm,
                "principal_px": list(self.centre),
                "projection": "frame: each pixel's field angle from the frame's camera (frame_camera)",
            }
        return {
            "sensor": [self.width, self.height],
            "pitch_um": self.pitch_um,
            "pinhole_focal_mm": self.focal_mm,
            "fov_deg": self.fov_deg,
            "reference_wavelength_nm": self.wavelength_nm,
            "principal_px": list(self.centre),
            "projection": "rectilinear: ideal point = pinhole_focal_mm * (tan x, tan y); image width spans +-fov_deg",
        }


def check_fov(fov_deg: float) -> float:
    if not (isinstance(fov_deg, (int, float)) and 0.0 < fov_deg < 89.0):
        raise SolasError(f"field of view {fov_deg!r} deg must be a half angle in (0, 89) degrees")
    return float(fov_deg)


def pinhole_focal_mm(lens: Lens, fov_deg: float, wavelength_nm: float | None = None) -> float:
    """Focal length (mm) of the pinhole whose image of field (fov_deg, 0) meets the real chief ray's."""
    from .pupil import chief_rays

    w = lens.primary_wavelength if wavelength_nm is None else lens.check_wavelength(wavelength_nm)
    x = float(chief_rays(lens, np.array([[check_fov(fov_deg), 0.0]]), np.array([w])).image_xy[0, 0])
    return x / math.tan(math.radians(fov_deg))


def film_pitch_um(lens: Lens, columns: int, fov_deg: float | None = None, wavelength_nm: float | None = None) -> float:
    """The pixel pitch (µm) of a film `columns` pixels wide that spans the lens's field: its width meets
    the real chief rays of ±fov_deg (default: the lens's field) at `wavelength_nm` (default: the primary)
    for a lens of pinhole fields; the lens's [image] diameter for one of polar fields (a fisheye).
    SolasError where the lens sets none."""
    if lens.field_type.pinhole:
        fov = check_fov(lens.field_deg if fov_deg is None else fov_deg)
        return 2e3 * pinhole_focal_mm(lens, fov, wavelength_nm) * math.tan(math.radians(fov)) / columns
    if lens.image_diameter <= 0:
        raise SolasError(f"lens {lens.name} has no [image] diameter: give the pixel pitch (um)")
    return 1e3 * lens.image_diameter / columns


def camera_for(
    lens: Lens,
    sensor: tuple[int, int] = DEFAULT_SENSOR,
    fov_deg: float | None = None,
    pitch_um: float | None = None,
    wavelength_nm: float | None = None,
) -> Camera:
    """The camera of `lens` with a sensor of (rows, columns) pixels. The default input image spans
    ±fov_deg horizontally (default: the lens's field); the default pitch makes the sensor's width span
    exactly that field."""
    rows, cols = sensor
    fov = check_fov(lens.field_deg if fov_deg is None else fov_deg)
    w = lens.primary_wavelength if wavelength_nm is None else lens.check_wavelength(wavelength_nm)
    focal = pinhole_focal_mm(lens, fov, w)
    if pitch_um is None:
        pitch_um = film_pitch_um(lens, cols, fov, w)
    elif not (isinstance(pitch_um, (int, float)) and 0.0 < pitch_um < 1e4):
        raise SolasError(f"pixel pitch {pitch_um!r} um must be a positive number below 1e4")
    return Camera(cols, rows, float(pitch_um), focal, fov, w)
