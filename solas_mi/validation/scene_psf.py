"""Geometric PSFs traced through the Mitsuba scene: the bridge showing that the scene's meshes and
plugins describe the same lens as the Float64 tracer.

Collimated rays of one field and wavelength start on the tracer's entrance grid (`psf.geometric`), cross
the scene's caps through `sellmeier_dielectric` (importance transport), and are binned where they
meet the image plane, on the tracer's PSF grid centred on the tracer's chief ray.
"""
from __future__ import annotations

import numpy as np

from ..optics import tracer as T
from ..optics.lens import Lens, check_field
from ..optics.pupil import chief_rays
from ..psf import base as S
from ..psf.geometric import entrance_half_width
from ..render.loop import continue_ray


def scene_psf(scene, lens: Lens, field_deg, wavelength_nm: float, pitch_um: float = S.DEFAULT_PITCH_UM,
              size: int = S.DEFAULT_SIZE, rays: int = S.DEFAULT_GEOMETRIC_RAYS) -> S.PSF:
    """Geometric PSF (unit sum) of field (x, y) degrees at one wavelength through `scene`'s geometry.
    meta holds the rays' landing centroid and RMS radius (µm from the chief ray) and the
    transmitted fraction of the launched power."""
    import drjit as dr
    import mitsuba as mi

    field = np.array([check_field(field_deg)])
    S.check_grid(pitch_um, size)
    wl = np.array([lens.check_wavelength(wavelength_nm)])
    chief = chief_rays(lens, field, wl)
    half = float(entrance_half_width(lens, field, wl, chief)[0])
    t = (np.arange(rays) + 0.5) / rays * 2.0 - 1.0
    ex = (chief.entrance[0, 0] + half * t)[None, :].repeat(rays, axis=0).ravel()
    ey = (chief.entrance[0, 1] + half * t)[:, None].repeat(rays, axis=1).ravel()
    tan = T.field_tangents(field)[0]
    n = len(ex)
    start = T.launch(lens, T.F(np.full(n, tan[0])), T.F(np.full(n, tan[1])), T.F(ex), T.F(ey))
    x, y, z, dx, dy, dz = T.to_numpy(start.x, start.y, start.z, start.dx, start.dy, start.dz)
    lam = mi.Spectrum(float(wl[0])) if mi.is_spectral else mi.Spectrum(0.0)
    ray = mi.Ray3f(mi.Point3f(x, y, z), mi.Vector3f(dx, dy, dz), 0.0, lam)
    ctx = mi.BSDFContext(mi.TransportMode.Importance)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(0, n)
    weight, active = mi.Float(1.0), mi.Bool(True)
    out_o, out_d, out_w = mi.Point3f(0.0), mi.Vector3f(0.0), mi.Float(0.0)
    for _ in range(2 * len(lens.surfaces) + 2):
        si = scene.ray_intersect(ray, active)
        escaped = active & ~si.is_valid()
        out_o, out_d = dr.select(escaped, ray.o, out_o), dr.select(escaped, ray.d, out_d)
        out_w = dr.select(escaped, weight, out_w)
        active &= si.is_valid()
        bs, bw = si.bsdf(ray).sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active), active)
        weight *= bw[0]
        active &= weight != 0.0
        ray = continue_ray(si, ray, bs.wo)
    ox, oy, oz, vx, vy, vz, w = (np.asarray(a, dtype=np.float64) for a in
                                 (out_o.x, out_o.y, out_o.z, out_d.x, out_d.y, out_d.z, out_w))
    keep = (vz > 0) & (w > 0)
    s = (lens.image_z - oz[keep]) / vz[keep]
    px = (ox[keep] + s * vx[keep] - chief.image_xy[0, 0]) * 1e3  # µm from the chief ray
    py = (oy[keep] + s * vy[keep] - chief.image_xy[0, 1]) * 1e3
    w = w[keep]
    edges = (np.arange(size + 1) - size // 2 - 0.5) * pitch_um
    hist, _, _ = np.histogram2d(-py, px, bins=(edges, edges), weights=w)
    cx, cy = np.average(px, weights=w), np.average(py, weights=w)
    rms = float(np.sqrt(np.average((px - cx) ** 2 + (py - cy) ** 2, weights=w)))
    meta = S.describe(lens, "scene-geometric", "sum", {"rays": rays}, size)
    meta.update({"centroid_um": [float(cx), float(cy)], "rms_radius_um": rms,
                 "transmission": float(w.sum() / n), "chief_ray_mm": chief.image_xy[0].tolist()})
    return S.PSF(S.normalize(hist, "sum"), float(pitch_um), tuple(field[0]), (float(wl[0]),), (1.0,),
                 tuple(chief.image_xy[0].tolist()), "scene-geometric", "sum", meta)
