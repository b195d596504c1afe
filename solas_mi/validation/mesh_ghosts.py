"""The sequential ghosts (`psf.stray_light`) against brute force: the same rays through the lens as Mitsuba
meshes with `sellmeier_dielectric` sampling each reflection with probability R (`fresnel` "sample", a real
interface's Monte Carlo), every path followed as it happens. Each ray that leaves the lens toward the
image is sorted by its reflections (where the direction's z turns, the surface nearest the hit point):
none, the direct image; two, the ghost (j, i). Per ghost: its energy relative to the direct image's and
its centroid on the image plane, as `stray_light.ghosts` gives them; a coated lens's caps are
`coated_dielectric`, its coatings' R and T. Lengths in mm.
"""

from __future__ import annotations

import numpy as np

from ..optics import ghost_paths
from ..psf.stray_light import launch
from ..render.psf import lens_geometry, walk


def mesh_ghosts(
    lens, field_deg, wavelength_nm: float, rays: int, passes: int, seed: int = 0, traced_rays_only: bool = False
) -> dict:
    """Per path (None: direct; (j, i), 0-based, as `ghost_paths.paths`), from `passes` Monte Carlo passes
    of the rays × rays grid: the power that took it in the meshes ("observed", summed over passes; each ray's
    weight 1, or a coating's T/(1 − R) per sampled refraction), the sequential trace's expectation of it (its
    weights: the chance of each ray to take that path, times `passes`), the rays counted, and the distances
    (µm) between each ray's landing point in the meshes and in the sequential trace of the same ray along the
    same path ("shifts_um"; inf where the sequential trace lost that ray). `traced_rays_only`: launch only
    the grid's rays that the sequential trace carries to the image along some path (the rest reach it along
    none, unless meshes and trace disagree, which the whole grid checks): a coated lens's ghosts are rare
    (5.9e-4 of the triplet's direct image at 10°, 83 % of its grid blocked), so this buys statistics."""
    import mitsuba as mi  # noqa: F401 (lens_geometry sets the variant)

    start = launch(lens, tuple(field_deg), rays)
    sequential = ghost_paths.trace_all(lens, start, wavelength_nm)
    if traced_rays_only:
        keep = np.unique(np.concatenate([r.ids for r in sequential.values()]))
        fields = (start.x, start.y, start.z, start.dx, start.dy, start.dz, start.power, start.alive)
        start = ghost_paths.Rays(*(a[keep] for a in fields))
        sequential = ghost_paths.trace_all(lens, start, wavelength_nm)
    reach = 2.0 * max(abs(lens.image_z), max(s.semi_diameter for s in lens.surfaces)) + 10.0
    scene = lens_geometry(lens, image_radius=reach, fresnel="sample")
    out = {
        k: {"observed": 0.0, "expected": passes * float(r.power.sum()), "shifts_um": [], "rays": 0}
        for k, r in sequential.items()
    }
    for p in range(passes):
        x, y, w, ids, j, i = _pass(scene, lens, start, wavelength_nm, seed + p)
        for jj, ii in set(zip(j.tolist(), i.tolist())):
            m = (j == jj) & (i == ii)
            k = None if jj < 0 else (jj, ii)
            row = out.setdefault(k, {"observed": 0.0, "expected": 0.0, "shifts_um": [], "rays": 0})
            row["observed"] += float((start.power[ids[m]] * w[m]).sum())
            row["rays"] += int(m.sum())
            row["shifts_um"].extend(_shifts_um(lens, sequential.get(k), ids[m], x[m], y[m]))
    return out


def _shifts_um(lens, seq, ids: np.ndarray, x: np.ndarray, y: np.ndarray) -> list[float]:
    """The distances (µm) between rays' landing points and the sequential trace's of the same rays (inf
    where the sequential trace lost one, or has no such path)."""
    if seq is None:
        return [float("inf")] * len(ids)
    t = (lens.image_z - seq.z) / seq.dz
    where = np.full(max(int(ids.max(initial=0)), int(seq.ids.max(initial=0))) + 1, -1)
    where[seq.ids] = np.arange(len(seq.ids))
    n = where[ids]
    m = np.maximum(n, 0)
    shift = 1e3 * np.hypot(x - seq.x[m] - t[m] * seq.dx[m], y - seq.y[m] - t[m] * seq.dy[m])
    return np.where(n >= 0, shift, np.inf).tolist()


def _pass(scene, lens, start, wavelength_nm: float, seed: int):
    """One Monte Carlo pass: image-plane x, y, weight (1, or a coating's T/(1 − R) per refraction), launch
    index and path (the surfaces j, i of the two reflections; -1, -1 for none) of each ray that leaves toward
    the image with no reflection or two."""
    import drjit as dr
    import mitsuba as mi

    n = len(start.x)
    ray = mi.Ray3f(
        mi.Point3f(start.x, start.y, start.z),
        mi.Vector3f(start.dx, start.dy, start.dz),
        0.0,
        mi.Spectrum(dr.opaque(mi.Float, float(wavelength_nm))),
    )
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(dr.opaque(mi.UInt32, seed), n)
    turned_at = {"count": mi.UInt32(0), "first": mi.Point3f(dr.nan), "second": mi.Point3f(dr.nan)}

    def watch(si, active, ray, following):  # where each ray turned back (the z of its direction changed sign)
        turned = active & (following.d.z * ray.d.z < 0)
        turned_at["first"] = dr.select(turned & (turned_at["count"] == 0), si.p, turned_at["first"])
        turned_at["second"] = dr.select(turned & (turned_at["count"] == 1), si.p, turned_at["second"])
        turned_at["count"] += dr.select(turned, 1, 0)

    out_o, out_d, out_w = walk(scene, ray, sampler, 3 * len(lens.surfaces) + 6, watch)
    count, first, second = turned_at["count"], turned_at["first"], turned_at["second"]
    outputs = (out_o.x, out_o.y, out_o.z, out_d.x, out_d.y, out_d.z, out_w, count, *first, *second)
    dr.eval(*outputs)  # one kernel for all: each conversion alone ran the whole walk again
    ox, oy, oz, dx, dy, dz, w, turns, *points = (np.asarray(a, dtype=np.float64) for a in outputs)
    keep = (dz > 0) & (w > 0) & ((turns == 0) | (turns == 2))
    sel = np.flatnonzero(keep)
    t = (lens.image_z - oz[sel]) / dz[sel]
    ghost = turns[sel] == 2
    j, i = (np.where(ghost, _surfaces(lens, *(p[sel] for p in points[3 * m : 3 * m + 3])), -1) for m in (0, 1))
    return ox[sel] + t * dx[sel], oy[sel] + t * dy[sel], w[sel], sel, j, i


def _surfaces(lens, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The reflecting surface (0-based) nearest each hit point along z."""
    surfaces = ghost_paths.reflecting(lens)
    r = np.hypot(x, y)
    gaps = [np.abs(z - lens.vertex_z[k] - lens.surfaces[k].sag(r)) for k in surfaces]
    return np.asarray(surfaces)[np.argmin(gaps, axis=0)]
