"""PSFs recorded through the Mitsuba scene (the PSF method "render"): a point source — at infinity,
collimated rays; at the lens file's finite object distance, rays from the object point — sends rays
from the tracer's entrance grid (`psf.geometric.entrance_grid`) through the lens as Mitsuba sees it:
float32 cap meshes (`render.scene.lens_parts`), absorbing rims and stop, and the
`sellmeier_dielectric` BSDF in importance transport. Where the rays meet the image plane they are
binned on the tracer's PSF grid (`psf.geometric.bin_hits`), so the result compares directly with
the "geometric" method: the difference is the scene's geometry (mesh chords, float32) alone.

Fresnel losses are off, as in the tracer's radiometry. Lengths in mm, PSF values in 1/µm².
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ..optics import pupil, tracer
from ..psf.base import Computed, centring_warnings, window_centres_um
from ..psf.geometric import bin_hits, entrance_grid, light_offsets_um
from .loop import continue_ray, steps_per_pass
from .scene import lens_parts, write_ply

VARIANT = "llvm_ad_spectral"


def lens_geometry(lens, rings: int | None = None, image_radius: float = 0.0, fresnel: str = "off", **extra):
    """The lens as a Mitsuba scene (mm, lens file's frame): cap meshes of `rings` rings (None:
    `render.mesh.mesh_rings`'s), a barrel holding the image plane out to `image_radius` mm, with `sellmeier_dielectric`
    (`coated_dielectric` on a coated surface; `fresnel`: "off", no Fresnel losses; "sample", reflections
    sampled, ghosts) and absorbing apertures, no
    sensor image and no texture; `extra` scene entries (a sensor, an integrator, objects) are added as given."""
    from .mitsuba import mitsuba

    mi = mitsuba(VARIANT)
    scene = {"type": "scene", "absorber": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}}, **extra}
    with tempfile.TemporaryDirectory(prefix="solas-lens-") as tmp:
        for part in lens_parts(lens, rings, image_radius):
            path = Path(tmp) / f"{part.name}.ply"
            write_ply(path, *part.mesh)
            bsdf = {"type": "ref", "id": "absorber"} if part.int_glass is None else part.bsdf(fresnel)
            scene[part.name] = {"type": "ply", "filename": str(path), "bsdf": bsdf}
        return mi.load_dict(scene)  # the meshes are read here, before the folder goes


def scene_hits(scene, lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, rays: int, chief: pupil.ChiefRays):
    """Per field: image-plane offsets (µm) from the chief ray of the entrance-grid rays that cross the
    scene's lens, and each one's power (fraction of the on-axis entrance-pupil power). A field's rays
    are traced in chunks of bounded time (`loop.steps_per_pass`): a signal is answered between them."""
    import mitsuba as mi

    sampler = mi.load_dict({"type": "independent"})
    depth = 2 * len(lens.surfaces) + 2
    chunk = max(1, steps_per_pass(mi.variant()) // depth)
    hits = []
    for sl, ex, ey, power in entrance_grid(lens, field_deg, wavelength_nm, rays, chief):
        for j, f in enumerate(range(sl.start, sl.stop)):
            exf, eyf = ex[j].ravel(), ey[j].ravel()
            out = [
                _exits(
                    scene,
                    lens,
                    sampler,
                    field_deg[f : f + 1],
                    wavelength_nm[f : f + 1],
                    f,
                    depth,
                    exf[k : k + chunk],
                    eyf[k : k + chunk],
                )
                for k in range(0, len(exf), chunk)
            ]
            ox, oy, oz, vx, vy, vz, w = (np.concatenate(a) for a in zip(*out))
            keep = (vz > 0) & (w > 0)
            s = (lens.image_z - oz[keep]) / vz[keep]
            hits.append(
                (
                    (ox[keep] + s * vx[keep] - chief.image_xy[f, 0]) * 1e3,
                    (oy[keep] + s * vy[keep] - chief.image_xy[f, 1]) * 1e3,
                    power[j][keep] * w[keep],
                )
            )
    return hits


def _exits(scene, lens, sampler, field_deg, wavelength_nm, f: int, depth: int, ex: np.ndarray, ey: np.ndarray):
    """Where the rays of entrance points ex, ey (mm) of field `f` leave the scene's lens: origins,
    directions and weights (numpy), launched as the tracer launches the lens's fields (tangents, or
    polar directions); the field's seed and wavelength are opaque, so every chunk runs one kernel."""
    import drjit as dr
    import mitsuba as mi

    n = len(ex)
    start = pupil.Bundle(lens, field_deg, wavelength_nm, n).launch(tracer.F(ex), tracer.F(ey))
    x, y, z, dx, dy, dz = tracer.to_numpy(start.x, start.y, start.z, start.dx, start.dy, start.dz)
    ray = mi.Ray3f(
        mi.Point3f(x, y, z), mi.Vector3f(dx, dy, dz), 0.0, mi.Spectrum(dr.opaque(mi.Float, float(wavelength_nm[0])))
    )
    sampler.seed(dr.opaque(mi.UInt32, f), n)
    out_o, out_d, out_w = walk(scene, ray, sampler, depth)
    return [np.asarray(a, dtype=np.float64) for a in (out_o.x, out_o.y, out_o.z, out_d.x, out_d.y, out_d.z, out_w)]


def walk(scene, ray, sampler, depth: int, watch=None):
    """Rays through the scene's lens in importance transport, `depth` interactions at most, each BSDF
    sampled: where they leave the scene (origins, directions) and their weights (0: absorbed, or still
    inside). `watch(si, active, ray, next_ray)`, where given, sees every interaction (Dr.Jit values)."""
    import drjit as dr
    import mitsuba as mi

    ctx = mi.BSDFContext(mi.TransportMode.Importance)
    weight, active = mi.Float(1.0), mi.Bool(True)
    out_o, out_d, out_w = mi.Point3f(0.0), mi.Vector3f(0.0), mi.Float(0.0)
    for _ in range(depth):
        si = scene.ray_intersect(ray, active)
        escaped = active & ~si.is_valid()
        out_o, out_d = dr.select(escaped, ray.o, out_o), dr.select(escaped, ray.d, out_d)
        out_w = dr.select(escaped, weight, out_w)
        active &= si.is_valid()
        bs, bw = si.bsdf(ray).sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active), active)
        weight *= bw[0]
        active &= weight != 0.0
        following = continue_ray(si, ray, bs.wo)
        if watch is not None:
            watch(si, active, ray, following)
        ray = following
    return out_o, out_d, out_w


def compute(
    lens,
    field_deg: np.ndarray,
    wavelength_nm: np.ndarray,
    pitch_um: float,
    size: int,
    *,
    shared_origin: bool = False,
    rays: int,
) -> Computed:
    """PSFs of field/wavelength pairs recorded through the Mitsuba scene (the PSF method "render",
    registered in `psf.registry` by this stage's package)."""
    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),)).copy()
    chief = pupil.chief_rays(lens, field_deg, wavelength_nm)
    light = light_offsets_um(lens, field_deg, wavelength_nm, chief)
    center = window_centres_um(chief, light, shared_origin)
    reach = np.hypot(*(chief.image_xy + (0.0 if center is None else center * 1e-3)).T).max() + size * pitch_um * 1e-3
    hits = scene_hits(lens_geometry(lens, image_radius=float(reach)), lens, field_deg, wavelength_nm, rays, chief)
    data, transmission = bin_hits(hits, pitch_um, size, center)
    return Computed(
        data=data,
        chief=chief,
        transmission=transmission,
        vignetted_by=[[] for _ in field_deg],
        warnings=tuple(centring_warnings(chief, light, field_deg)),
        centre_um=center,
    )
