"""Geometric PSFs traced through a loaded Mitsuba scene: the bridge showing that the scene's meshes and
plugins describe the same lens as the Float64 tracer.

Collimated rays of one field and wavelength start on the tracer's entrance grid (`psf.geometric`),
cross the scene's caps through `sellmeier_dielectric` (importance transport, `render.psf.scene_hits`)
and are binned where they meet the image plane, on the tracer's PSF grid centred on the tracer's
chief ray. Lengths in mm, offsets in µm.
"""

from __future__ import annotations

import numpy as np

from ..optics.lens import Lens
from ..optics.pupil import chief_rays
from ..psf import base
from ..psf.geometric import bin_hits
from ..psf.registry import DEFAULT_GEOMETRIC_RAYS
from ..render.psf import scene_hits


def scene_psf(
    scene,
    lens: Lens,
    field_deg,
    wavelength_nm: float,
    pitch_um: float = base.DEFAULT_PITCH_UM,
    size: int = base.DEFAULT_SIZE,
    rays: int = DEFAULT_GEOMETRIC_RAYS,
) -> base.PSF:
    """Geometric PSF (unit sum) of field (x, y) degrees at one wavelength through `scene`'s geometry.
    meta holds the rays' landing centroid and RMS radius (µm from the chief ray) and the transmitted
    power (fraction of the on-axis entrance-pupil power)."""
    field = np.array([lens.field_type.check(field_deg)])
    base.check_grid(pitch_um, size)
    wl = np.array([lens.check_wavelength(wavelength_nm)])
    chief = chief_rays(lens, field, wl)
    hits = scene_hits(scene, lens, field, wl, rays, chief)
    px, py, w = hits[0]
    data, transmission = bin_hits(hits, pitch_um, size)
    cx, cy = np.average(px, weights=w), np.average(py, weights=w)
    rms = float(np.sqrt(np.average((px - cx) ** 2 + (py - cy) ** 2, weights=w)))
    meta = base.describe(lens, "scene-geometric", "sum", {"rays": rays}, size)
    meta.update(
        {
            "centroid_um": [float(cx), float(cy)],
            "rms_radius_um": rms,
            "transmission": float(transmission[0]),
            "chief_ray_mm": chief.image_xy[0].tolist(),
        }
    )
    return base.PSF(
        base.normalize(data[0], "sum"),
        float(pitch_um),
        tuple(field[0]),
        (float(wl[0]),),
        (1.0,),
        tuple(chief.image_xy[0].tolist()),
        "scene-geometric",
        "sum",
        meta,
    )
