"""A frame's pixels as the lens's fields and the lens's image points as the frame's pixels (`FrameFields`): what
placing ghosts on a degraded frame needs (`convolution.ghosts`), by the same cameras the convolution uses."""

from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError
from ..optics.frame import FISHEYE, FrameCamera

TABLE_SAMPLES = 129  # polar angles of the fisheye lens's chief-ray table (image height over polar angle)
STEP_MM = 1e-3  # the step of the mapping's local size (finite differences)
LARGEST_DEG = 89.9  # a fisheye frame's directions: below 90 deg (tangents)


class FrameFields:
    """The camera of a width×height frame degraded by `psf_grid` (a rectilinear frame: `kernels.grid_camera`; a
    fisheye `frame`: its calibration and `lens`'s chief rays at the grid's reference wavelength)."""

    def __init__(self, lens, psf_grid, width: int, height: int, frame: FrameCamera | None = None) -> None:
        from .kernels import grid_camera

        if psf_grid.meta.get("layout") == "sensor":
            raise SolasError(
                "ghosts: a PSF grid laid out on the sensor takes the sensor image, whose pixels' fields are not "
                "stated; give a grid over field angle (psf-grid without --sensor)"
            )
        self.field_type, self.width, self.height = lens.field_type, int(width), int(height)
        self.wavelength_nm = float(psf_grid.meta["reference_wavelength_nm"])  # the grid's chief rays' wavelength
        self.fisheye = frame if frame is not None and frame.model in FISHEYE else None
        if self.fisheye is None:
            camera = grid_camera(psf_grid, width, height, frame)
            self.centre, self.pitch_mm, self.focal_mm = camera.centre, camera.pitch_mm, camera.focal_mm
            return
        from ..optics.pupil import chief_rays

        fields = np.asarray(psf_grid.fields_deg, dtype=np.float64).reshape(-1, 2)
        largest = max(lens.field_type.polar(f)[0] for f in fields)
        self.theta = np.linspace(0.0, largest, TABLE_SAMPLES)
        fx, fy = lens.field_type.field_of(self.theta, np.ones_like(self.theta), np.zeros_like(self.theta))
        rays = chief_rays(lens, np.stack([fx, fy], axis=-1), np.full(len(self.theta), self.wavelength_nm))
        self.rho = np.asarray(rays.image_xy, dtype=np.float64)[:, 0]
        if not np.all(np.diff(self.rho) > 0):
            raise SolasError(
                f"ghosts: lens {lens.name}'s chief ray's image height does not grow with the field up to "
                f"{math.degrees(largest):g} deg: its image points cannot be mapped to the fisheye frame"
            )

    def tangents(self, cols: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The directions (tan x, tan y) of pixel positions (columns, rows)."""
        if self.fisheye is not None:
            return self.fisheye.tangents(cols, rows, self.width, self.height, clamp=True)
        cx, cy = self.centre
        scale = self.pitch_mm / self.focal_mm
        return (np.asarray(cols) - cx) * scale, (cy - np.asarray(rows)) * scale

    def field_deg(self, cols: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """The lens's fields (…, 2) in degrees of pixel positions (columns, rows)."""
        tx, ty = self.tangents(cols, rows)
        theta, phi = np.arctan(np.hypot(tx, ty)), np.arctan2(ty, tx)
        return np.stack(self.field_type.field_of(theta, np.cos(phi), np.sin(phi)), axis=-1)

    def clamped(self, field_deg, largest_deg: float) -> tuple[float, float]:
        """`field_deg` with its polar angle at most `largest_deg` (a source beyond the ghost grid's last node, within
        the frame's last cell, takes the ghosts at that node's polar angle)."""
        theta, phi = self.field_type.polar(field_deg)
        theta = min(theta, math.radians(largest_deg))
        fx, fy = self.field_type.field_of(theta, math.cos(phi), math.sin(phi))
        return float(fx), float(fy)

    def _pixel(self, x_mm: np.ndarray, y_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.fisheye is None:
            cx, cy = self.centre
            return cx + x_mm / self.pitch_mm, cy - y_mm / self.pitch_mm
        rho = np.hypot(x_mm, y_mm)
        slope = (self.rho[-1] - self.rho[-2]) / (self.theta[-1] - self.theta[-2])  # beyond the table: its last slope
        theta = np.where(
            rho <= self.rho[-1], np.interp(rho, self.rho, self.theta), self.theta[-1] + (rho - self.rho[-1]) / slope
        )
        tangent = np.tan(np.minimum(theta, math.radians(LARGEST_DEG)))
        phi = np.arctan2(y_mm, x_mm)
        return self.fisheye.pixels(tangent * np.cos(phi), tangent * np.sin(phi), self.width, self.height)

    def pixel(self, xy_mm) -> tuple[tuple[float, float], float]:
        """An image point's (mm) pixel position (column, row) in the frame, and the mapping's size there (pixels per
        mm: the root of its Jacobian's determinant)."""
        x, y = float(xy_mm[0]), float(xy_mm[1])
        h = STEP_MM
        xs, ys = np.array([x, x + h, x - h, x, x]), np.array([y, y, y, y + h, y - h])
        cols, rows = (np.asarray(v, dtype=np.float64) for v in self._pixel(xs, ys))
        jacobian = np.array([[cols[1] - cols[2], cols[3] - cols[4]], [rows[1] - rows[2], rows[3] - rows[4]]]) / (2 * h)
        return (float(cols[0]), float(rows[0])), math.sqrt(abs(float(np.linalg.det(jacobian))))
