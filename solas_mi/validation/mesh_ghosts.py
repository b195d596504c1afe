"""The sequential ghosts (`psf.stray_light`) against brute force: the same rays through the lens as Mitsuba
meshes with `sellmeier_dielectric` sampling each reflection with probability R (`fresnel` "sample", a real
interface's Monte Carlo), every path followed as it happens. Each ray that leaves the lens toward the
image is sorted by its reflections (where the direction's z turns, the surface nearest the hit point):
none, the direct image; two, the ghost (j, i). Per ghost: its energy relative to the direct image's and
its centroid on the image plane, as `stray_light.ghosts` gives them for uncoated lenses (the meshes have
bare glass). Lengths in mm.
"""

from __future__ import annotations

import numpy as np

from ..optics import ghost_paths
from ..psf.stray_light import launch
from ..render.psf import lens_geometry, walk


def mesh_ghosts(lens, field_deg, wavelength_nm: float, rays: int, passes: int, seed: int = 0) -> dict:
    """Per path (None: direct; (j, i), 0-based, as `ghost_paths.paths`), from `passes` Monte Carlo passes
    of the rays × rays grid: the power that took it in the meshes ("observed", summed over passes), the
    sequential trace's expectation of it (its weights: the chance of each ray to take that path, times
    `passes`), the rays counted, and the distances (µm) between each ray's landing point in the meshes and
    in the sequential trace of the same ray along the same path ("shifts_um"; inf where the sequential
    trace lost that ray)."""
    import mitsuba as mi  # noqa: F401 (lens_geometry sets the variant)

    start = launch(lens, tuple(field_deg), rays)
    sequential = ghost_paths.trace_all(lens, start, wavelength_nm)
    reach = 2.0 * max(abs(lens.image_z), max(s.semi_diameter for s in lens.surfaces)) + 10.0
    scene = lens_geometry(lens, image_radius=reach, fresnel="sample")
    out = {
        k: {"observed": 0.0, "expected": passes * float(r.power.sum()), "shifts_um": [], "rays": 0}
        for k, r in sequential.items()
    }
    for p in range(passes):
        x, y, ids, keys = _pass(scene, lens, start, wavelength_nm, seed + p)
        for k in set(keys):
            m = np.array([kk == k for kk in keys], dtype=bool)
            row = out.setdefault(k, {"observed": 0.0, "expected": 0.0, "shifts_um": [], "rays": 0})
            row["observed"] += float(start.power[ids[m]].sum())
            row["rays"] += int(m.sum())
            row["shifts_um"].extend(_shifts_um(lens, sequential.get(k), ids[m], x[m], y[m]))
    return out


def _shifts_um(lens, seq, ids: np.ndarray, x: np.ndarray, y: np.ndarray) -> list[float]:
    """The distances (µm) between rays' landing points and the sequential trace's of the same rays (inf
    where the sequential trace lost one, or has no such path)."""
    if seq is None:
        return [float("inf")] * len(ids)
    t = (lens.image_z - seq.z) / seq.dz
    where = {int(i): n for n, i in enumerate(seq.ids)}
    out = []
    for i, px, py in zip(ids, x, y):
        n = where.get(int(i))
        out.append(
            float("inf")
            if n is None
            else 1e3 * float(np.hypot(px - seq.x[n] - t[n] * seq.dx[n], py - seq.y[n] - t[n] * seq.dy[n]))
        )
    return out


def _pass(scene, lens, start, wavelength_nm: float, seed: int):
    """One Monte Carlo pass: image-plane x, y, launch index and path key of each ray that leaves toward the
    image with no reflection or two."""
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
    ox, oy, oz, dx, dy, dz, w, turns, *points = (
        np.asarray(a, dtype=np.float64)
        for a in (
            out_o.x,
            out_o.y,
            out_o.z,
            out_d.x,
            out_d.y,
            out_d.z,
            out_w,
            count,
            first.x,
            first.y,
            first.z,
            second.x,
            second.y,
            second.z,
        )
    )
    keep = (dz > 0) & (w > 0) & ((turns == 0) | (turns == 2))
    t = (lens.image_z - oz) / np.where(keep, dz, 1.0)
    sel = np.flatnonzero(keep)
    keys = [
        None
        if turns[i] == 0
        else (
            _surface(lens, points[0][i], points[1][i], points[2][i]),
            _surface(lens, points[3][i], points[4][i], points[5][i]),
        )
        for i in sel
    ]
    return ox[sel] + t[sel] * dx[sel], oy[sel] + t[sel] * dy[sel], sel, keys


def _surface(lens, x: float, y: float, z: float) -> int:
    """The reflecting surface (0-based) nearest a hit point along z."""
    surfaces = ghost_paths.reflecting(lens)
    r = float(np.hypot(x, y))
    return surfaces[int(np.argmin([abs(z - lens.vertex_z[k] - float(lens.surfaces[k].sag(r))) for k in surfaces]))]
