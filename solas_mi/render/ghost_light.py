"""The stray light of a lens camera's ghosts traced from the light sources (`render --ghosts`,
`render.flare`): for each source of the scene (`ghost_sources`: area emitters, delta lights, an
environment map's sun) and each two-reflection path of the lens (`optics.ghost_paths`), rays from the
source into the lens, traced along the path (`optics.ghost_trace`) to the film, each splatted where it
lands with its light.

Why not the camera's own path sampling (`lens_camera` `ghosts` "only", the cross-check): a film pixel
reaches a small source along a ghost path through a small part of the pupil only, and each camera sample
follows one of some 45 paths: at the direct image's spp its ghosts stay several times noisier than the
direct image. Traced from the source, every ray carries the source's light and needs no scene shading,
only one ray cast (occluders shadow the flare), so the rays are cheap and are spent where light is.

Rays: per (source, path), entrance points stratified over a square of the front vertex plane that holds
surface 1's clear aperture (widened by its rim's sag along the source's steepest ray), a CONE source's
directions and every ray's wavelength spread evenly too (a shifted Kronecker sequence over the rays of a
cell), the wavelength drawn from the camera response as the camera draws it (`sample_quantile`, weight
1/p(λ)). The square is cut into `GRID`² cells; the main pass traces only a path's cells where its pilot
rays landed and their neighbours (a path no pilot ray of which lands is not traced further: light that
1024 rays over the aperture all miss). Each ray carries the light per
area of the plane × the cell's area (`ghost_sources.light`) × the path's reflectances and transmittances
× 1/p(λ), in the camera's units (× its `norm`, over the pixel's area): an unbiased estimate of the image
irradiance the camera's samples estimate. It lands on the film plane and is put into a Mitsuba
`ImageBlock` with the film's reconstruction filter, its weights normalised (each ray's light is kept), its
colour the film's (one wavelength in lane 0, `spectrum_to_srgb`).

How many rays (`_counts`): a pilot pass of `PILOT`² rays per (source, path) measures each path's light on
the film E, the share f of its rays in the main pass's cells that land, and the area A (px) its light covers (4π √det of the
landing points' light-weighted covariance: πr² for a uniform disc); the main pass gives (source, path)
`DENSITY` × spp × E / (f b_max) rays, b_max the brightest E/A: the brightest ghost gets `DENSITY` landings
per pixel and sample, a path of brightness b in proportion b/b_max (least summed noise for the rays;
b_max over the paths with `MEASURED` pilot landings at least: a few landings say little of an area);
at least `PILOT`², at most `BUDGET` × pixels × spp in all (scaled down together).
"""

from __future__ import annotations

import math
import time

import drjit as dr
import mitsuba as mi
import numpy as np

from ..optics import ghost_paths, ghost_trace, tracer
from .ghost_sources import CONE, light, opaque, sources

PILOT = 32  # pilot rays per side of the entrance square, per (source, path)
GRID = 16  # cells per side of the entrance square: the main pass traces only those where pilot rays landed
DENSITY = 4.0  # landings per pixel and sample in the brightest ghost
BUDGET = 16.0  # rays at most per pixel and sample, over every source and path
MEASURED = 32  # pilot landings a path needs for its area (and brightness) to count
CHUNK = 1 << 22  # rays traced at once
METHOD = (
    "light-traced: rays from each source (area emitters, delta lights, an environment map's sun) along every "
    "two-reflection path of the lens to the film"
)


def stray_light(scene, sensor, spp: int, seed: int = 0):
    """The stray light of `sensor`'s (a `lens_camera`) ghosts in `scene` at `spp` (module docstring): (the
    image, crop rows × columns × 3 (the film's RGB), float64; what the metadata says of it)."""
    start = time.perf_counter()
    found, skipped = sources(scene, np.array(sensor.world_transform().matrix, dtype=np.float64).reshape(4, 4))
    tracing = Tracing(scene, sensor)
    every = ([np.arange(GRID * GRID)] * tracing.paths, np.full(tracing.paths, PILOT // GRID))
    pilots = [tracing.trace(s, every, (seed, k, 0)) for k, s in enumerate(found)]
    counts = _counts([_in_cells(*p) for p in pilots], spp * tracing.size[0] * tracing.size[1], spp)
    for k, (source, n, (_, cells)) in enumerate(zip(found, counts, pilots)):
        tracing.trace(source, _plan(cells, n), (seed, k, 1), splat=True)
    image = np.array(tracing.block.tensor(), dtype=np.float64)[..., :3]
    meta = {
        "method": METHOD,
        "sources": [s.name for s in found],
        "not_traced": skipped + ["light scattered by the scene's surfaces, a sky without a sun"],
        "rays": int(sum(int(n.sum()) for n in counts)),  # asked for; rounded up per cell
        "seconds": time.perf_counter() - start,
    }
    return np.nan_to_num(image, nan=0.0, posinf=0.0, neginf=0.0), meta


def direct_light(scene, sensor, side: int = 36, seed: int = 0) -> np.ndarray:
    """The direct image of `scene`'s sources (those `stray_light` traces) through `sensor`'s (a `lens_camera`)
    lens, light-traced like its ghosts along the direct path, `side`² rays per cell of the whole entrance
    square: (crop rows × columns × 3, float64). Converged where a camera render of a sun under a pixel is
    not: a reference to weigh a ghost's light by."""
    found, _ = sources(scene, np.array(sensor.world_transform().matrix, dtype=np.float64).reshape(4, 4))
    direct = ghost_trace.direct(sensor.lens)
    tracing = Tracing(scene, sensor, [(direct, direct)])
    for k, source in enumerate(found):
        tracing.trace(source, ([np.arange(GRID * GRID)], np.array([side])), (seed, k, 0), splat=True)
    return np.nan_to_num(np.array(tracing.block.tensor(), dtype=np.float64)[..., :3], nan=0.0, posinf=0.0, neginf=0.0)


def _counts(pilots, pixel_samples: int, spp: int) -> list[np.ndarray]:
    """The main pass's rays per (source, path) from the pilots' (light, landed share, area, landings)
    (module docstring)."""
    if not pilots:
        return []
    light, share, area, landed = (np.array([p[i] for p in pilots]) for i in range(4))
    bright = float(np.where(landed >= MEASURED, light / area, 0.0).max())
    wanted = np.where(light > 0, DENSITY * spp * light / max(bright, 1e-300) / np.maximum(share, 1e-3), 0.0)
    wanted = np.maximum(wanted, PILOT * PILOT)
    wanted *= min(1.0, BUDGET * pixel_samples / wanted.sum())
    return list(np.maximum(np.ceil(wanted), 1).astype(np.int64))


def _in_cells(figures, cells: np.ndarray):
    """The pilot's `figures` with the landed share of the rays in the main pass's `cells` (paths × cells)."""
    light, _, area, landed = figures
    return light, landed / np.maximum(cells.sum(axis=(1, 2)) * (PILOT // GRID) ** 2, 1), area, landed


def _plan(cells: np.ndarray, counts: np.ndarray):
    """The main pass's entrance cells per path (those of `cells`, paths × `GRID` × `GRID`, true) and rays per
    side of each, about `counts`[k] per path in all (a path without a cell: none)."""
    ids = [np.flatnonzero(c) for c in cells]
    sides = np.array([max(1, math.ceil(math.sqrt(n / max(len(c), 1)))) for c, n in zip(ids, counts)])
    return ids, sides


def _dilated(mask: np.ndarray) -> np.ndarray:
    """Each path's cells (…, `GRID`, `GRID`) and their 8 neighbours."""
    out = mask.copy()
    for a in (-1, 0, 1):
        for b in (-1, 0, 1):
            shifted = np.roll(np.roll(mask, a, axis=-2), b, axis=-1)
            if a:
                shifted[..., 0 if a > 0 else -1, :] = False
            if b:
                shifted[..., :, 0 if b > 0 else -1] = False
            out |= shifted
    return out


def _lane0(value):
    """A Mitsuba Spectrum whose colour (`spectrum_to_srgb`, the mean of the lanes') is lane 0's `value`'s."""
    return mi.Spectrum(4.0 * value, 0.0, 0.0, 0.0) if mi.is_spectral else mi.Spectrum(value)


def _stratified(index: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """The `index`-th points of a Kronecker (R_d) sequence in [0, 1)^d, d = len(`shift`), shifted by `shift`
    (Cranley–Patterson: each point uniform, the points of consecutive indices spread evenly); in 32-bit
    fixed point, exact for every index."""
    dims, phi = len(shift), 2.0
    for _ in range(30):
        phi = (1.0 + phi) ** (1.0 / (dims + 1))
    steps = np.array([int((1.0 / phi ** (k + 1)) % 1.0 * 2**32) for k in range(dims)], dtype=np.uint64)
    fixed = (index.astype(np.uint64)[None, :] * steps[:, None] + (shift * 2**32).astype(np.uint64)[:, None]) % 2**32
    return (fixed >> 8).astype(np.float64) * 2.0**-24


class Tracing:
    """Rays of the sources of `scene` along the ghost `paths` ((j, i) 0-based; every one of `ghost_paths`
    by default) of `sensor`'s lens to its film (module docstring): `trace` puts them into `block` or sums
    the pilot's figures."""

    def __init__(self, scene, sensor, paths=None) -> None:
        self.scene, self.sensor, self.lens = scene, sensor, sensor.lens
        film = sensor.film()
        self.size = tuple(int(v) for v in film.crop_size())
        self.block = mi.ImageBlock(
            mi.ScalarVector2u(self.size), mi.ScalarPoint2i(0, 0), 5, film.rfilter(), normalize=True
        )
        every = ghost_paths.paths(self.lens) if paths is None else paths
        self.paths = len(every)
        self.first, self.second = (mi.UInt32([p[k] for p in every]) for k in (0, 1))
        self.to_world = sensor.world_transform()

    def reach(self, source) -> float:
        """Half the side of the entrance square: surface 1's clear aperture, widened by its rim's sag along
        the source's steepest direction (a delta light's: the one at the vertex, + 0.05 rad)."""
        front = self.lens.surfaces[0]
        if source.kind == CONE:
            steepest = math.acos(min(1.0, float(source.axis[2]))) + source.radius
        else:
            d, _ = light(
                self.scene,
                source,
                self.to_world,
                self.sensor.world_unit_mm,
                (mi.Float(0.0), mi.Float(0.0)),
                mi.Point2f(0.5, 0.5),
                _lanes(mi.Float(550.0)),
            )
            steepest = math.acos(float(np.clip(d.z[0], -1.0, 1.0))) + 0.05
        rim = abs(float(front.sag(front.semi_diameter)))
        return 1.02 * front.semi_diameter + rim * min(math.tan(min(steepest, 1.5)), 4.0)

    def trace(self, source, plan, seed: tuple, splat: bool = False):
        """Rays of `source` along each path k, on the entrance cells `plan[0][k]` (ids of the `GRID`² cells
        of the square), `plan[1][k]`² rays in each (stratified): splatted into `block` (`splat`), else the
        pilot's figures (`_pilot_figures`) and the cells whose rays landed."""
        cells, sides = plan
        per_path = np.array([len(c) for c in cells]) * sides * sides
        ends = np.cumsum(per_path)
        flat, first_cell = np.concatenate(cells).astype(np.int64), np.cumsum([0] + [len(c) for c in cells])[:-1]
        reach = self.reach(source)
        rng = np.random.default_rng(list(seed))
        sums = [dr.zeros(mi.Float, self.paths) for _ in range(8)]
        hit = dr.zeros(mi.Float, self.paths * GRID * GRID)
        for lo in range(0, int(ends[-1]), CHUNK):
            hi = min(int(ends[-1]), lo + CHUNK)
            index = np.searchsorted(ends, np.arange(lo, hi), side="right")
            s = sides[index]
            ordinal, sub = np.divmod(np.arange(lo, hi) - (ends - per_path)[index], s * s)  # NumPy: an LLVM
            cell = flat[first_cell[index] + ordinal]  # kernel's integer division may trap
            size = 2.0 * reach / (GRID * s)  # a ray's share of the square, a side
            points = tuple(
                mi.Float(((c * s + v) + rng.random(hi - lo)) * size - reach)
                for c, v in zip(np.divmod(cell, GRID)[::-1], np.divmod(sub, s)[::-1])
            )
            uv, uw, ul = (mi.Float(v) for v in _stratified(ordinal * s * s + sub, rng.random(3)))
            path, size = mi.UInt32(index.astype(np.uint32)), mi.Float(size)
            lam, inverse_pdf = self.sensor.wavelengths.sample_quantile(ul)
            wav = _lanes(lam)
            d, carried = light(
                self.scene, source, self.to_world, self.sensor.world_unit_mm, points, mi.Point2f(uv, uw), wav
            )
            col, row, value, landed = self.land(points, d, lam, path)
            value *= carried * size * size * inverse_pdf
            landed &= value > 0
            if splat:
                self.block.put(mi.Point2f(col, row), wav, _lane0(dr.select(landed, value, 0.0)), 0.0, 0.0, landed)
                dr.eval(self.block.tensor())  # each chunk its own launch of one kernel (else chunks fuse, new kernels)
                continue
            w, one = dr.select(landed, value, 0.0), dr.select(landed, 1.0, 0.0)
            for k, v in enumerate(
                (one + 1.0 - one, one, w, w * col, w * row, w * col * col, w * row * row, w * col * row)
            ):
                dr.scatter_add(sums[k], v, path)
            dr.scatter_add(hit, one, path * (GRID * GRID) + mi.UInt32(cell.astype(np.uint32)))
            dr.eval(sums, hit)
        if splat:
            return None
        return _pilot_figures(np.array([np.array(v, dtype=np.float64) for v in sums]).T), _dilated(
            np.array(hit).reshape(self.paths, GRID, GRID) > 0
        )

    def land(self, points, d, lam, path):
        """Rays through entrance `points` of the vertex plane along lens-frame `d` at wavelengths `lam`
        (nm), traced along their paths (indices `path`) to the film plane: (column, row of the crop window,
        the path's reflectances and transmittances × the camera's `norm` over the pixel's area (mm²),
        whether it landed on the crop window)."""
        sensor, f64 = self.sensor, dr.float64_array_t(mi.Float)
        z0 = tracer.launch_plane_z(self.lens)
        dx, dy, dz = f64(d.x), f64(d.y), f64(dr.select(d.z > 0, d.z, 1.0))
        t = tracer.opaque(-z0, f64) / dz
        start = (f64(points[0]) - t * dx, f64(points[1]) - t * dy, dr.full(f64, z0, dr.width(dz)))
        rays = tracer.Rays(*start, dx, dy, dz, dr.zeros(f64, dr.width(dz)))
        first, second = dr.gather(mi.UInt32, self.first, path), dr.gather(mi.UInt32, self.second, path)
        leaving, ok, power = ghost_trace.trace_paths(self.lens, rays, f64(lam) * 1e-3, first, second)
        ok &= (leaving.dz > 0) & (d.z > 0)
        s = (tracer.opaque(self.lens.image_z, f64) - leaving.z) / dr.select(ok, leaving.dz, 1.0)
        inverse_pitch = opaque(1.0 / sensor.pitch_mm)
        centre = [opaque(0.5 * sensor.film_size[k] - sensor.crop_offset[k]) for k in (0, 1)]
        col = dr.fma(mi.Float(leaving.x + s * leaving.dx), inverse_pitch, centre[0])
        row = centre[1] - mi.Float(leaving.y + s * leaving.dy) * inverse_pitch
        ok = mi.Bool(ok) & (col >= 0) & (col < opaque(self.size[0])) & (row >= 0) & (row < opaque(self.size[1]))
        value = dr.select(ok, mi.Float(power) * opaque(sensor.norm / sensor.pitch_mm**2), 0.0)
        return col, row, value, ok


def _lanes(lam):
    """A Mitsuba Spectrum of wavelengths `lam` in every lane (a mono variant's: none)."""
    return mi.Spectrum(lam) if mi.is_spectral else mi.Color0f()


def _pilot_figures(sums: np.ndarray):
    """(light on the film, landed share, area in px, landings) per path from the pilot's sums (per path:
    rays, landings, Σw, Σw·c, Σw·r, Σw·c², Σw·r², Σw·c·r; w the light, c and r the column and row)."""
    w = np.maximum(sums[:, 2], 1e-300)
    mc, mr = sums[:, 3] / w, sums[:, 4] / w
    vc, vr, vcr = sums[:, 5] / w - mc * mc, sums[:, 6] / w - mr * mr, sums[:, 7] / w - mc * mr
    area = 4.0 * math.pi * np.sqrt(np.maximum(vc * vr - vcr * vcr, 0.0))
    return sums[:, 2], sums[:, 1] / np.maximum(sums[:, 0], 1.0), np.maximum(area, 1.0), sums[:, 1]
