"""PSF grid nodes laid out on the sensor (image-plane positions in mm) instead of on field angles.

A wide lens maps field angles to image heights far from f·tan θ (a fisheye reaches 90° at a finite
height), so a grid even in field tangents crowds or leaves gaps on the sensor, and beyond 90° there
are no tangents at all. A sensor layout puts the nodes at the centres of ny×nx equal cells of a
width×height mm sensor centred on the axis (row 0 = top = largest y), and gives each node the field
whose real chief ray (at the reference wavelength) lands there. The lens is rotationally symmetric,
so this is one radial inversion: chief-ray image height h(θ) is traced on a table of polar angles θ
and inverted by interpolation; the node's azimuth is the field's. The node's PSF is centred on its
real chief ray (the grid's chief_ray_mm), which lies on the node up to the interpolation error
(nm) at the reference wavelength and off it by the lateral colour at the others.
"""

from __future__ import annotations

import numpy as np

from ..errors import SolasError
from ..optics.lens import Lens

TABLE_STEPS = 256  # polar angles in the h(θ) table
REACH = 1.05  # the table runs to this multiple of the lens's field (capped below 180° or 89°)


def node_mm(sensor_mm: tuple[float, float], ny: int, nx: int) -> np.ndarray:
    """(ny, nx, 2) image-plane points (mm): centres of ny×nx equal cells of the sensor, row 0 on top."""
    w, h = sensor_mm
    x = (np.arange(nx) + 0.5 - nx / 2) * (w / nx)  # exactly antisymmetric: mirrored nodes, mirrored fields
    y = (ny / 2 - np.arange(ny) - 0.5) * (h / ny)
    return np.stack(np.meshgrid(x, y), axis=-1)


def height_table(lens: Lens, wavelength_nm: float) -> tuple[np.ndarray, np.ndarray]:
    """Polar angles θ (degrees) and real chief-ray image heights h (mm) at `wavelength_nm`, from the
    axis to REACH × the lens's field, stopping before heights stop increasing."""
    from ..optics.pupil import chief_rays  # Dr.Jit: loaded only when a grid is computed

    top = min(REACH * lens.field_deg, lens.field_type.largest_deg)
    theta = np.linspace(0.0, top, TABLE_STEPS)
    h = chief_rays(lens, np.stack([np.zeros_like(theta), theta], axis=-1), np.full(len(theta), wavelength_nm)).image_xy[
        :, 1
    ]
    rising = np.flatnonzero(np.diff(h) <= 0)
    end = rising[0] + 1 if len(rising) else len(h)
    return theta[:end], h[:end]


def fields_for_points(lens: Lens, points_mm: np.ndarray, wavelength_nm: float) -> np.ndarray:
    """Fields (…, 2) in degrees, in the lens's field convention (polar or tangent), whose chief rays at
    `wavelength_nm` land at image points (…, 2) mm. SolasError for a point beyond the largest height."""
    theta, h = height_table(lens, wavelength_nm)
    p = np.asarray(points_mm, dtype=np.float64)
    ax, ay = np.abs(p[..., 0]), np.abs(p[..., 1])  # mirror-symmetric nodes get bit-identical fields
    r = np.hypot(ax, ay)
    if r.max() > h[-1]:
        raise SolasError(
            f"image point at {r.max():.4g} mm from the axis lies beyond the lens's image circle: its "
            f"chief rays reach {h[-1]:.4g} mm (at {theta[-1]:.4g} deg); use a smaller sensor"
        )
    t = np.radians(np.interp(r, h, theta))
    with np.errstate(invalid="ignore", divide="ignore"):
        c, s = np.where(r > 0, ax / r, 1.0), np.where(r > 0, ay / r, 0.0)
    fx, fy = lens.field_type.field_of(t, c, s)
    return np.stack([np.copysign(fx, p[..., 0]), np.copysign(fy, p[..., 1])], axis=-1)


def default_sensor_mm(lens: Lens) -> tuple[float, float]:
    """The square inscribed in the lens's image circle (its [image] diameter), mm."""
    if lens.image_diameter <= 0:
        raise SolasError(f"lens {lens.name} has no [image] diameter: give the sensor size (mm) for a sensor layout")
    side = lens.image_diameter / np.sqrt(2.0)
    return side, side


def check_sensor_mm(sensor_mm) -> tuple[float, float]:
    """(width, height) in mm, both positive and finite."""
    try:
        w, h = (float(v) for v in sensor_mm)
    except (TypeError, ValueError):
        raise SolasError(f"sensor size {sensor_mm!r} must be two lengths (width, height) in mm") from None
    if not (np.isfinite(w) and np.isfinite(h) and w > 0 and h > 0):
        raise SolasError(f"sensor size ({w:g}, {h:g}) mm: width and height must be positive")
    return w, h
