"""Real rays through chosen points of the pupil, for the ray fans, the OPD fans, the wavefront and
field curvature: each aimed at its point of the stop (normalised pupil coordinates (Px, Py): the stop
point (Px, Py) × the stop's radius, as Zemax's and optiland's real ray aiming), traced to the image
plane and to the reference sphere about the chief ray's image point.

OPD convention (as Zemax and optiland): W = OPL(chief ray) − OPL(ray) to the reference sphere, in
waves: positive where the wavefront leads the reference sphere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..optics import tracer
from ..optics.pupil import Bundle, ChiefRays, chief_rays, stop_aim


@dataclass(frozen=True)
class PupilRays:
    """Rays of n field/wavelength pairs, m each, (n, m) arrays: image-plane points (mm), image-space
    unit directions, the wavefront W (waves, module docstring) and which arrived (aimed, inside every
    aperture, on the sphere)."""

    x_mm: np.ndarray
    y_mm: np.ndarray
    direction: tuple[np.ndarray, np.ndarray, np.ndarray]
    wavefront_waves: np.ndarray
    ok: np.ndarray
    chief: ChiefRays


def pupil_rays(lens, fields_deg, wavelengths_nm, px: np.ndarray, py: np.ndarray, sphere_radius_mm=None) -> PupilRays:
    """Rays at normalised pupil points `px`, `py` ((n, m) or (m,), shared) for the y fields `fields_deg`
    (n,) at `wavelengths_nm` (n,). `sphere_radius_mm` (n,): another reference sphere's radius than the
    chief ray's distance from its exit-pupil crossing (`optics.pupil.ChiefRays.sphere_radius`), to compare
    with a tool that takes the axial exit-pupil point (optiland)."""
    fields = np.stack([np.zeros(len(fields_deg)), np.asarray(fields_deg, dtype=np.float64)], axis=-1)
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    n = len(fields)
    px, py = (np.broadcast_to(np.atleast_2d(a), (n, np.shape(a)[-1])) for a in (px, py))
    chief = chief_rays(lens, fields, wl)
    b = Bundle(lens, fields, wl, px.shape[1])
    r_stop = lens.surfaces[lens.stop_index].semi_diameter
    _, _, tr, converged = stop_aim(b, chief, tracer.F(px.ravel() * r_stop), tracer.F(py.ravel() * r_stop))
    x, y, _ = tracer.to_plane(tr, lens.image_z)
    cx, cy = b.per_ray(chief.image_xy[:, 0]), b.per_ray(chief.image_xy[:, 1])
    radius = chief.sphere_radius if sphere_radius_mm is None else np.asarray(sphere_radius_mm, dtype=np.float64)
    _, _, _, opl, hit = tracer.to_sphere(tr, cx, cy, lens.image_z, b.per_ray(radius))
    r = tr.rays
    arrays = tracer.to_numpy(x, y, r.dx, r.dy, r.dz, opl, converged & tr.ok & (tr.clipped_by == 0) & hit)
    x, y, dx, dy, dz, opl, ok = (a.reshape(px.shape) for a in arrays)
    chief_opl = chief.opl + chief.n_image * (chief.sphere_radius - radius)  # along the chief ray, through the centre
    waves = (chief_opl[:, None] - opl) / (wl[:, None] * 1e-6)
    return PupilRays(x, y, (dx, dy, dz), np.where(ok, waves, np.nan), ok.astype(bool), chief)
