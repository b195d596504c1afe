"""Sampling a ray from a film point toward the exit pupil, for the sensors that look through a lens
(in every Mitsuba variant; `tables` holds the lookups).

`PupilSampler` tabulates the exit-pupil bounds of `solas_mi.optics.exit_pupil.pupil_bounds` per film
radius and draws a point uniformly inside the bound of a film position: in its rectangle, or in the
inscribed ellipse where that holds every passing ray. A ray from film point x toward a point of the
bound (area A, on a plane a distance d from the film) weighs A·cos⁴θ/d², θ its angle to the axis, as
in pbrt-v4's RealisticCamera (M. Pharr, W. Jakob, G. Humphreys, "Physically Based Rendering: From
Theory to Implementation", 4th ed., MIT Press, 2023). Lengths in mm, the lens file's frame.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np
from solas_mi.plugins.tables import lookup, table

from solas_mi.optics.exit_pupil import pupil_bounds
from solas_mi.optics.lens import Lens


class PupilSampler:
    """Exit-pupil bounds of `lens` for film radii up to `max_radius_mm`, over `wavelengths_nm`."""

    def __init__(self, lens: Lens, max_radius_mm: float, wavelengths_nm) -> None:
        bounds = pupil_bounds(lens, max_radius_mm, wavelengths_nm=wavelengths_nm)
        union = np.stack([bounds.at(r) for r in bounds.radius_mm[:-1]])  # rows i and i + 1
        self.bounds = bounds
        self.radius_step = float(bounds.radius_mm[1] - bounds.radius_mm[0])
        self.rows = len(union)
        self.tables = [table(union[:, k]) for k in range(5)]
        self.plane_z = bounds.plane_z
        self.image_z = lens.image_z

    def sample(self, film: mi.Point2f, sample: mi.Point2f, active=True) -> tuple[mi.Point2f, mi.Float]:
        """A point (x, y) on the bound's plane z = `plane_z` for the film point (x, y) at z = `image_z`,
        from a uniform `sample` in [0, 1]², and the weight A·cos⁴θ/d² of the ray between them."""
        x, y = film.x, film.y
        r = dr.sqrt(x * x + y * y)
        inv = dr.select(r > 0, dr.rcp(r), 0.0)
        cos_p, sin_p = dr.select(r > 0, x * inv, 1.0), y * inv
        row = dr.minimum(mi.UInt32(r / self.radius_step), self.rows - 1)
        u0, u1, v0, v1, ellipse = (lookup(b, row, active) for b in self.tables)
        ellipse = ellipse > 0.5
        disk = mi.warp.square_to_uniform_disk_concentric(sample)
        su = dr.select(ellipse, 0.5 * (disk.x + 1.0), sample.x)
        sv = dr.select(ellipse, 0.5 * (disk.y + 1.0), sample.y)
        u, v = dr.fma(su, u1 - u0, u0), dr.fma(sv, v1 - v0, v0)
        px, py = u * cos_p - v * sin_p, u * sin_p + v * cos_p
        dz = self.plane_z - self.image_z
        dist2 = dr.square(px - x) + dr.square(py - y) + dz * dz
        cos4 = dr.square(dz * dz / dist2)
        area = (u1 - u0) * (v1 - v0) * dr.select(ellipse, 0.25 * dr.pi, 1.0)
        return mi.Point2f(px, py), area * cos4 / (dz * dz)
