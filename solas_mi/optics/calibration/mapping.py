"""The lens's real chief-ray mapping over a sensor: which direction each pixel sees, traced by the
package's Float64 tracer (`optics.pupil.chief_rays`, each chief ray aimed through the stop centre).

A lens of solas-mi is rotationally symmetric, so its mapping is radial: the chief ray of the direction at
polar angle θ from the axis and azimuth φ lands at h(θ)·(cos φ, sin φ) on the image plane. h(θ) is traced
at polar angles on the y axis, nodes and the midpoints between them (which say how well the cubic
spline through the nodes stands for the lens between them: `interpolation_error_px`); a pixel's
direction is h's inverse at its radius (Newton on the spline). The lens images a direction while its
chief ray passes every aperture (`pupil.widest_field`'s rule): the image circle is the image height of
the widest such direction, found to 1/`EDGE_STEPS` of the table's step, and pixels beyond it
(the corners of a circular fisheye's sensor, or of a sensor larger than the lens's field) are left out.

Conventions (those of OpenCV and of the calibration files): pixel (0, 0) is the centre of the top-left
pixel, columns right, rows down; the sensor is centred on the axis, so the axis lands at
((W − 1)/2, (H − 1)/2) (or at the principal point a sensor names: a frame's intrinsics); directions are unit vectors in the camera frame x right, y down, z forward
(along the lens's axis, toward the scene), from the lens's paraxial entrance pupil (the camera centre;
for an object at a finite distance each field names the direction from there to its object point, as
the tracer's fields do). The image is upright, as solas-mi writes every image.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import SolasError
from ..lens import Lens

NODES = 512  # spline intervals of h(θ) from the axis to the sensor's corner or the image circle
COARSE = 64  # intervals of the table that finds how far that is
EDGE_STEPS = 32  # the image circle's edge: a step of the table cut into this many
MIN_PIXELS = 16  # fewer imaged pixels than this: no mapping to fit
NEWTON_STEPS = 6


@dataclass(frozen=True)
class Sensor:
    """A sensor on the lens's axis, checked when built.

    Parameters
    ----------
    width, height : int
        Pixels, 1 to 65536 each.
    pitch_um : float
        The pixel pitch (µm), below 1e4.
    principal : tuple of float, optional
        (column, row) where the lens's axis lands (a frame's principal point); default: the sensor's centre.

    Raises
    ------
    SolasError
        For a size or pitch out of range, or a principal point that is not two finite numbers.

    Examples
    --------
    >>> from solas_mi.optics.calibration import Sensor
    >>> Sensor(64, 48, 50.0).describe()
    {'sensor_px': [64, 48], 'pitch_um': 50.0, 'principal_px': [31.5, 23.5]}
    """

    width: int
    height: int
    pitch_um: float
    principal: tuple[float, float] | None = None

    def __post_init__(self):
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 1 << 16:
                raise SolasError(f"sensor {name} {value!r} must be a whole number of pixels from 1 to 65536")
        p = self.pitch_um
        if isinstance(p, bool) or not isinstance(p, (int, float)) or not (math.isfinite(p) and 0 < p < 1e4):
            raise SolasError(f"pixel pitch {p!r} um must be a positive number below 1e4")
        c = self.principal
        if c is not None and not (len(c) == 2 and all(isinstance(v, (int, float)) and math.isfinite(v) for v in c)):
            raise SolasError(f"principal point {c!r} must be two finite numbers (column, row) of pixels")

    @property
    def centre(self) -> tuple[float, float]:
        """(column, row) where the axis lands."""
        if self.principal is not None:
            return float(self.principal[0]), float(self.principal[1])
        return (self.width - 1) / 2.0, (self.height - 1) / 2.0

    def reach_px(self) -> float:
        """How far the sensor reaches from the axis.

        Returns
        -------
        float
            The distance (pixels) from the axis to the sensor's farthest pixel centre.
        """
        cx, cy = self.centre
        return max(math.hypot(c - cx, r - cy) for c in (0, self.width - 1) for r in (0, self.height - 1))

    def mm(self, cols: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Image-plane points of pixel positions.

        Parameters
        ----------
        cols, rows : numpy.ndarray
            Pixel positions (pixel (0, 0) the centre of the top-left pixel).

        Returns
        -------
        tuple of numpy.ndarray
            (x right, y up) in mm, the axis at 0.
        """
        cx, cy = self.centre
        return (np.asarray(cols) - cx) * self.pitch_um * 1e-3, (cy - np.asarray(rows)) * self.pitch_um * 1e-3

    def describe(self) -> dict:
        """The sensor as metadata records it.

        Returns
        -------
        dict
            Its size in pixels, pitch and principal point.
        """
        return {"sensor_px": [self.width, self.height], "pitch_um": self.pitch_um,
                "principal_px": list(self.centre)}


@dataclass
class ChiefMap:
    """The chief-ray mapping h(θ) of one lens at one wavelength over one sensor, as `chief_map` traces it.

    Parameters
    ----------
    lens : Lens
        The lens (focused as the mapping was traced).
    wavelength_nm : float
        The wavelength (nm).
    sensor : Sensor
        The sensor.
    focus_distance_mm : float
        The object's distance in front of surface 1 (mm); math.inf: an object at infinity.
    theta : numpy.ndarray
        (NODES + 1,) polar angles (radians), 0 to the widest traced.
    height_mm : numpy.ndarray
        The chief rays' image heights (mm) there.
    circle_mm : float or None
        The image circle's radius (mm); None where every pixel lies inside it.
    interpolation_error_px : float
        The spline's largest error at the midpoints between nodes (pixels).
    entrance_pupil_mm : float
        The camera centre: the paraxial entrance pupil, this far behind surface 1's vertex (mm).
    spline : object, optional
        The cubic spline through the nodes (made when built).
    """

    lens: Lens
    wavelength_nm: float
    sensor: Sensor
    focus_distance_mm: float
    theta: np.ndarray
    height_mm: np.ndarray
    circle_mm: float | None
    interpolation_error_px: float
    entrance_pupil_mm: float
    spline: Any = field(repr=False, default=None)  # h(θ), scipy's CubicSpline (SciPy ships no types)

    def __post_init__(self):
        from scipy.interpolate import CubicSpline

        # h is odd in θ: the mirrored nodes give the spline the right shape at the axis
        t, h = np.concatenate([-self.theta[:0:-1], self.theta]), np.concatenate([-self.height_mm[:0:-1], self.height_mm])
        self.spline = CubicSpline(t, h)

    @property
    def top(self) -> float:
        """The widest polar angle traced (radians)."""
        return float(self.theta[-1])

    def theta_of(self, radius_mm: np.ndarray) -> np.ndarray:
        """The polar angles whose chief rays land at some image heights: h's inverse (Newton on the spline).

        Parameters
        ----------
        radius_mm : numpy.ndarray
            Image heights (mm) within the table's.

        Returns
        -------
        numpy.ndarray
            Polar angles (radians).
        """
        r = np.asarray(radius_mm, dtype=np.float64)
        t = np.interp(r, self.height_mm, self.theta)
        d = self.spline.derivative()
        for _ in range(NEWTON_STEPS):
            t = np.clip(t - (self.spline(t) - r) / d(t), 0.0, self.top)
        return t

    def directions(self, cols: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The directions pixels see.

        Parameters
        ----------
        cols, rows : numpy.ndarray
            (n,) pixel positions.

        Returns
        -------
        directions : numpy.ndarray
            (n, 3) unit vectors (x right, y down, z forward); a pixel outside the image circle gets the axis.
        inside : numpy.ndarray
            (n,) whether the lens images each (inside the image circle).
        """
        x, y = self.sensor.mm(np.ravel(cols), np.ravel(rows))
        r = np.hypot(x, y)
        inside = r <= (self.circle_mm if self.circle_mm is not None else np.inf)
        theta = np.where(inside, self.theta_of(np.minimum(r, self.height_mm[-1])), 0.0)
        scale = np.divide(np.sin(theta), r, out=np.zeros_like(r), where=r > 0)
        return np.stack([x * scale, -y * scale, np.cos(theta)], axis=-1), inside

    def pixels(self, xyz: np.ndarray) -> np.ndarray:
        """Where directions land: the lens's mapping through the spline.

        Parameters
        ----------
        xyz : numpy.ndarray
            (n, 3) directions in the camera frame.

        Returns
        -------
        numpy.ndarray
            (n, 2) pixel positions (column, row).
        """
        xyz = np.asarray(xyz, dtype=np.float64)
        rho = np.hypot(xyz[:, 0], xyz[:, 1])
        h = self.spline(np.arctan2(rho, xyz[:, 2])) / (self.sensor.pitch_um * 1e-3)
        scale = np.divide(h, rho, out=np.zeros_like(rho), where=rho > 0)
        cx, cy = self.sensor.centre
        return np.stack([cx + xyz[:, 0] * scale, cy + xyz[:, 1] * scale], axis=-1)

    def grid(self, stride: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Pixel centres over the sensor.

        Parameters
        ----------
        stride : int, default 1
            Every `stride`-th column and row, the last ones included.

        Returns
        -------
        tuple of numpy.ndarray
            (columns, rows), raveled.
        """
        cs = np.unique(np.r_[np.arange(0, self.sensor.width, stride), self.sensor.width - 1])
        rs = np.unique(np.r_[np.arange(0, self.sensor.height, stride), self.sensor.height - 1])
        c, r = np.meshgrid(cs.astype(np.float64), rs.astype(np.float64))
        return c.ravel(), r.ravel()

    def describe(self) -> dict:
        """What the mapping is, for the metadata of a calibration.

        Returns
        -------
        dict
            Lens, wavelength, focus, sensor, camera centre, image circle (px), widest field (degrees) and the
            interpolation error (px).
        """
        px = self.sensor.pitch_um * 1e-3
        return {"lens": self.lens.name, "lens_hash": self.lens.hash, "wavelength_nm": self.wavelength_nm,
                "focus_distance_mm": self.focus_distance_mm, **self.sensor.describe(),
                "camera_centre": f"the paraxial entrance pupil, {self.entrance_pupil_mm:.6g} mm behind surface 1's vertex",
                "image_circle_radius_px": None if self.circle_mm is None else self.circle_mm / px,
                "widest_field_deg": math.degrees(self.top),
                "interpolation_error_px": self.interpolation_error_px}


def _heights(lens: Lens, theta: np.ndarray, wl: float) -> tuple[np.ndarray, np.ndarray]:
    """Chief-ray image heights (mm) of polar angles `theta` (radians) on the y axis, and whether each
    chief ray passes every aperture."""
    from ..pupil import chief_rays

    deg = np.degrees(theta)
    c = chief_rays(lens, np.stack([np.zeros_like(deg), deg], axis=-1), np.full(len(deg), wl))
    return c.image_xy[:, 1], ~c.vignetted


def _imaged(lens: Lens, wl: float, theta: np.ndarray) -> tuple[np.ndarray, int]:
    """Heights (mm) of a coarse table of polar angles and the index of the last one of the run imaged from the axis."""
    h, ok = _heights(lens, theta, wl)
    return h, int(np.cumprod(ok & np.r_[True, np.diff(h) > 0]).sum()) - 1


def _table(lens: Lens, wl: float, reach_mm: float) -> tuple[np.ndarray, np.ndarray, float | None]:
    """Polar angles (radians) from the axis with their chief rays' image heights (mm), nodes and midpoints
    alternating (2·NODES + 1 values), up to the sensor's half diagonal `reach_mm` or as far as the lens
    images, and the image circle's radius (mm; None where the lens images beyond `reach_mm`). A coarse table
    over the lens's stated field finds how far the table must run; only a sensor beyond it traces out to the
    widest direction any chief ray reaches (slow for a fisheye: its aim near there takes small steps)."""
    from ..aiming import continued_aim
    largest = math.radians(lens.field_type.largest_deg)
    for top in ([min(1.05 * math.radians(lens.field_deg), largest)] if lens.field_deg > 0 else []) + [None]:
        if top is None:
            top = float(continued_aim(lens, np.array([[0.0, math.degrees(largest)]]), np.array([wl]))[1][0]) * largest
        theta = np.linspace(0.0, top, COARSE + 1)
        h, last = _imaged(lens, wl, theta)
        beyond = np.flatnonzero(h[: last + 1] >= reach_mm)
        if len(beyond):  # the sensor lies inside what the lens images: up to its corner
            return _refined(lens, wl, float(theta[beyond[0]])) + (None,)
    edge = float(theta[last])
    if last + 1 < len(theta):  # imaging ends within a step: cut it finer
        fine = np.linspace(theta[last], theta[last + 1], EDGE_STEPS + 1)
        edge = float(fine[_imaged(lens, wl, fine)[1]])
    table, heights = _refined(lens, wl, edge)
    return table, heights, float(heights[-1])


def _refined(lens: Lens, wl: float, top: float) -> tuple[np.ndarray, np.ndarray]:
    """The table (angles, heights) of nodes and midpoints from the axis to `top` (radians)."""
    theta = np.linspace(0.0, top, 2 * NODES + 1)
    return theta, _heights(lens, theta, wl)[0]


def chief_map(lens: Lens, sensor: Sensor, wavelength_nm: float | None = None,
              focus_distance_mm: float | None = math.inf) -> ChiefMap:
    """Trace a lens's real chief-ray mapping over a sensor: which direction each pixel sees.

    Parameters
    ----------
    lens : Lens
        The lens.
    sensor : Sensor
        The sensor, centred on the axis.
    wavelength_nm : float, optional
        The wavelength (nm); default: the lens's primary.
    focus_distance_mm : float or None, default inf
        The lens focused on an object this far in front of surface 1 (mm); math.inf or None: at infinity, and the
        lens file's own object distance where it gives one.

    Returns
    -------
    ChiefMap
        h(θ), its spline and the image circle.

    Raises
    ------
    SolasError
        For a sensor not a `Sensor`, a bad wavelength or focus, a lens imaging under `MIN_PIXELS` of its pixels.

    Examples
    --------
    >>> import numpy as np
    >>> from solas_mi import Lens
    >>> from solas_mi.optics.calibration import Sensor, chief_map
    >>> mapping = chief_map(Lens.load("solas-doublet"), Sensor(64, 48, 50.0))
    >>> directions, inside = mapping.directions(np.array([63.0]), np.array([23.5]))
    >>> mapping.pixels(directions).round(4).tolist(), inside.tolist()
    ([[63.0, 23.5]], [True])
    """
    from ..focus import focused
    from ..paraxial import paraxial

    if not isinstance(sensor, Sensor):
        raise SolasError(f"sensor {sensor!r} must be a solas_mi.optics.calibration.Sensor")
    if focus_distance_mm is not None and not (isinstance(focus_distance_mm, float) and math.isinf(focus_distance_mm)
                                              and lens.at_infinity):
        lens = focused(lens, focus_distance_mm)
    wl = lens.primary_wavelength if wavelength_nm is None else lens.check_wavelength(wavelength_nm)
    px = sensor.pitch_um * 1e-3
    reach = px * sensor.reach_px()
    table, heights, circle = _table(lens, wl, reach)
    theta, h, mid, hm = table[::2], heights[::2], table[1::2], heights[1::2]
    ep = paraxial(lens, wl).entrance_pupil_z_mm - float(lens.vertex_z[0])
    out = ChiefMap(lens, wl, sensor, math.inf if lens.at_infinity else float(lens.object_distance), theta, h, circle,
                   0.0, ep)
    out.interpolation_error_px = float(np.max(np.abs(out.spline(mid) - hm))) / px
    if circle is not None:
        cols, rows = out.grid()
        if np.count_nonzero(np.hypot(*sensor.mm(cols, rows)) <= circle) < MIN_PIXELS:
            raise SolasError(f"sensor {sensor.width}x{sensor.height} px of {sensor.pitch_um:g} um: fewer than "
                             f"{MIN_PIXELS} of its pixels lie inside the image circle of lens {lens.name} "
                             f"({circle:.4g} mm = {circle / px:.4g} px at {wl:g} nm); use a smaller pitch or more pixels")
    return out
