"""A ghost ray's pupil point drawn toward the scene's bright emitters (`ghost_sampling`, `lens_camera`
option `ghosts`): a film pixel reaches a small emitter along a ghost path through a small part of the
pupil only, which uniform pupil sampling seldom finds.

The emitters: the scene's area emitters in front of the lens (`bright_emitters`: the direction of each
one's bounding sphere's centre, its angular radius, its radiance at the middle of its texture). Each one's
light is traced forward through the lens along every ghost path (`optics.ghost_trace`, at one wavelength):
`GUIDE_RAYS`² rays per emitter and path, collimated, their directions uniform in the emitter's cone and
their entrance points stratified over surface 1's clear aperture. Where a ray lands on the film, its line
crosses the pupil plane (the plane of the ghost sampler's square, ±`reach`) at the point from which the
camera's ray of that film point, traced back along the path, leaves toward the emitter. Each ghost path
and film tile (`TILE_PX` pixels a side) keeps the histogram of those crossings over `CELLS`² cells of the
square, weighted by the rays' flux (radiance × the cone's solid angle × the path's reflectances and
transmittances).

A pupil point is drawn, from one uniform sample, from the mixture of the uniform square (share
`UNIFORM_SHARE`) and its (path, tile)'s histogram (a cell by its weight, uniform within it); its density is
the mixture's at the point, whichever part drew it, and the sample's weight divides by it: the estimate is
unbiased, and the uniform share reaches every pupil point (light that no traced emitter sends). A tile
without a histogram draws uniformly. Sparse: only the cells that rays reach are stored (sorted per
(path, tile)), found by binary search.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from solas_mi.optics import ghost_trace, tracer
from solas_mi.optics.lens import Lens

GUIDE_RAYS = 192  # rays per side of each emitter's beam, per ghost path
TILE_PX = 2  # film pixels per side of a tile with its own pupil histogram
CELLS = 64  # cells per side of the pupil square
UNIFORM_SHARE = 0.2  # the uniform square's share of the mixture where a tile has a histogram
SPREAD = 1  # each crossing counts in the cells this many on each side of its own too
CHUNK = 1 << 20  # rays traced at once


def bright_emitters(scene, to_world: np.ndarray) -> list[tuple[np.ndarray, float, float]]:
    """The area emitters of `scene` in front of the camera of 4×4 `to_world` (world units): (the direction
    their light travels in the lens's frame, their angular radius (rad), their radiance) each."""
    found = []
    to_local = np.linalg.inv(to_world)
    for emitter in scene.emitters():
        shape = emitter.get_shape()
        if shape is None:  # a delta light (point, spot, directional) or an environment: no camera ray meets it
            continue
        box = shape.bbox()
        centre = (to_local @ np.append(np.array(box.center(), dtype=np.float64), 1.0))[:3]
        distance = float(np.linalg.norm(centre))
        radius = 0.5 * float(np.linalg.norm(np.array(box.extents(), dtype=np.float64)))
        if centre[2] <= 0 or distance <= radius:
            continue
        # the camera frame is the lens's (x, −y, −z); the light travels from the emitter to the lens
        found.append(
            (np.array([-centre[0], centre[1], centre[2]]) / distance, math.asin(radius / distance), _radiance(emitter))
        )
    return [e for e in found if e[2] > 0]


def _radiance(emitter) -> float:
    """The mean radiance of an area emitter, seen head-on at the middle of its texture."""
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.wi = mi.Vector3f(0.0, 0.0, 1.0)
    si.uv = mi.Point2f(0.5, 0.5)
    if mi.is_spectral:
        si.wavelengths = dr.full(mi.Spectrum, 550.0)
    value = np.array(emitter.eval(si), dtype=np.float64)
    return float(np.nan_to_num(value).mean())


def _cone(axis: np.ndarray, radius: float, count: int, rng) -> np.ndarray:
    """`count` unit directions uniform in the cone of half-angle `radius` about `axis` (3 × count)."""
    cos_t = 1.0 - rng.random(count) * (1.0 - math.cos(radius))
    sin_t, phi = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0)), 2.0 * math.pi * rng.random(count)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    return axis[:, None] * cos_t + u[:, None] * (sin_t * np.cos(phi)) + v[:, None] * (sin_t * np.sin(phi))


def crossings(lens: Lens, paths, emitters, wavelength_nm: float, planes: tuple[float, float], seed: int = 0):
    """Each emitter's light traced forward along each of `paths` ((j, i) 0-based of `lens`): per arriving
    ray (its path's index, x and y on the planes z = planes[0] (the film) and planes[1] (the pupil), its
    flux); the rays come uniform over the emitter's cone, `GUIDE_RAYS`² per emitter and path."""
    rng = np.random.default_rng(seed)
    n = GUIDE_RAYS
    reach = lens.surfaces[0].semi_diameter * 1.01
    grid = (np.arange(n) + 0.5) / n * 2.0 - 1.0
    out = []
    for axis, radius, radiance in emitters:
        per_ray = radiance * 2.0 * math.pi * (1.0 - math.cos(radius)) * (2.0 * reach) ** 2 / (n * n)
        index = np.repeat(np.arange(len(paths)), n * n)
        ex, ey = (np.tile(g.ravel(), len(paths)) * reach for g in np.meshgrid(grid, grid))
        ex, ey = ex + rng.uniform(-reach / n, reach / n, ex.size), ey + rng.uniform(-reach / n, reach / n, ey.size)
        d = _cone(axis, radius, ex.size, rng)
        for lo in range(0, ex.size, CHUNK):
            part = slice(lo, lo + CHUNK)
            rays = tracer.launch_direction(
                lens,
                *(tracer.F(v) for v in (d[0][part], d[1][part], d[2][part])),
                tracer.F(ex[part]),
                tracer.F(ey[part]),
            )
            first = tracer.UInt32(np.array([p[0] for p in paths], dtype=np.uint32)[index[part]])
            second = tracer.UInt32(np.array([p[1] for p in paths], dtype=np.uint32)[index[part]])
            leaving, ok, power = ghost_trace.trace_paths(
                lens, rays, tracer.F(np.full(ex[part].size, wavelength_nm * 1e-3)), first, second
            )
            x, y, z, dx, dy, dz, ok, power = tracer.to_numpy(
                *(getattr(leaving, a) for a in ("x", "y", "z", "dx", "dy", "dz")), ok, power
            )
            ok = ok & (dz > 0)
            at = [((p - z) / np.where(ok, dz, 1.0)) for p in planes]
            out.append((index[part][ok], *(v[ok] for t in at for v in (x + t * dx, y + t * dy)), power[ok] * per_ray))
    return [np.concatenate(parts) for parts in zip(*out)] if out else None


class GhostGuide:
    """The pupil histograms of every film tile over (ghost path, cell) (module docstring), from
    `crossings`: film of `film_size` pixels of `pitch_mm`, the pupil square ±`reach` mm, `paths` paths."""

    def __init__(self, hits, paths: int, film_size, pitch_mm: float, reach: float) -> None:
        index, fx, fy, px, py, flux = hits
        self.tiles = tuple(-(-n // TILE_PX) for n in film_size)
        self.film_size, self.pitch_mm, self.reach = film_size, pitch_mm, reach
        self.cell = 2.0 * reach / CELLS
        col, row = fx / pitch_mm + 0.5 * film_size[0], 0.5 * film_size[1] - fy / pitch_mm
        cx, cy = np.floor((px + reach) / self.cell), np.floor((py + reach) / self.cell)
        on = (col >= 0) & (col < film_size[0]) & (row >= 0) & (row < film_size[1]) & (flux > 0)
        on &= (cx >= 0) & (cx < CELLS) & (cy >= 0) & (cy < CELLS)
        self.flux = np.bincount(index[on], weights=flux[on], minlength=paths)  # per path, on the film
        tile = (row[on] // TILE_PX).astype(np.int64) * self.tiles[0] + (col[on] // TILE_PX).astype(np.int64)
        span = paths * CELLS * CELLS  # (path, cell) keys of a tile
        keys, weight = _summed(
            tile * span
            + index[on].astype(np.int64) * CELLS * CELLS
            + cy[on].astype(np.int64) * CELLS
            + cx[on].astype(np.int64),
            flux[on],
        )
        keys, weight = _spread(keys, weight)
        tiles, starts, counts = np.unique(keys // span, return_index=True, return_counts=True)
        pmf = weight / np.repeat(np.add.reduceat(weight, starts), counts) if len(keys) else weight
        cdf = np.cumsum(pmf) - np.repeat(np.arange(len(counts)), counts)  # each tile's own, from 0 to 1
        cdf[np.cumsum(counts) - 1] = 1.0
        dense_start = np.zeros(self.tiles[0] * self.tiles[1], np.uint32)
        dense_count = np.zeros_like(dense_start)
        dense_start[tiles], dense_count[tiles] = starts, counts
        self.start, self.count = mi.UInt32(dense_start), mi.UInt32(dense_count)
        self.keys = mi.UInt32((keys % span).astype(np.uint32))
        self.pmf, self.cdf = mi.Float(pmf), mi.Float(cdf)
        self.steps = max(1, math.ceil(math.log2(max(int(counts.max()) if len(counts) else 1, 1))) + 1)

    def sample(self, film: mi.Point2f, sample: mi.Point2f, paths) -> tuple:
        """A ghost path and pupil point for film point `film` (mm) from uniform `sample`: from the film tile's
        histogram with probability 1 − `UNIFORM_SHARE` (where it has one), else a path from `paths`
        (`PathChoice`) and a point uniform on the square; (the path's index, the point, the mixture's
        density of the two (per mm²))."""
        col = dr.clip(film.x / self.pitch_mm + 0.5 * self.film_size[0], 0, self.film_size[0] - 1)
        row = dr.clip(0.5 * self.film_size[1] - film.y / self.pitch_mm, 0, self.film_size[1] - 1)
        tile = mi.UInt32(row / TILE_PX) * self.tiles[0] + mi.UInt32(col / TILE_PX)
        start, count = dr.gather(mi.UInt32, self.start, tile), dr.gather(mi.UInt32, self.count, tile)
        share = dr.select(count > 0, 1.0 - UNIFORM_SHARE, 0.0)
        guided = sample.x < share
        u = dr.clip(dr.select(guided, sample.x / share, (sample.x - share) / (1.0 - share)), 0.0, 1.0 - 2**-24)
        k = self._search(self.cdf, mi.Float, start, count, lambda v: v <= u)
        hi = dr.gather(mi.Float, self.cdf, start + k, guided)
        lo = dr.select(k > 0, dr.gather(mi.Float, self.cdf, start + k - 1, guided & (k > 0)), 0.0)
        key = dr.gather(mi.UInt32, self.keys, start + k, guided)
        ux = dr.clip((u - lo) / dr.maximum(hi - lo, 1e-30), 0.0, 1.0 - 2**-24)
        cell = key % (CELLS * CELLS)
        uniform_path, p, v = paths.choose(u)
        path = dr.select(guided, key // (CELLS * CELLS), uniform_path)
        x = dr.select(guided, (mi.Float(cell % CELLS) + ux) * self.cell, v * 2.0 * self.reach) - self.reach
        y = (
            dr.select(guided, (mi.Float(cell // CELLS) + sample.y) * self.cell, sample.y * 2.0 * self.reach)
            - self.reach
        )
        at = dr.clip(mi.UInt32((y + self.reach) / self.cell), 0, CELLS - 1) * CELLS
        at = dr.select(guided, cell, at + dr.clip(mi.UInt32((x + self.reach) / self.cell), 0, CELLS - 1))
        at += path * (CELLS * CELLS)
        j = self._search(self.keys, mi.UInt32, start, count, lambda v: v < at)
        found = (count > 0) & (dr.gather(mi.UInt32, self.keys, start + j, count > 0) == at)
        q = dr.select(found, dr.gather(mi.Float, self.pmf, start + j, found), 0.0)
        p = dr.select(guided, paths.probability(path), p)
        density = (1.0 - share) * p / (4.0 * self.reach * self.reach) + share * q / (self.cell * self.cell)
        return path, mi.Point2f(x, y), density

    def _search(self, values, kind, start, count, below):
        """The first k < `count` with `below`(values[start + k]) false in a run sorted so (`count` − 1 if
        none; 0 where `count` is 0)."""
        base, n = mi.UInt32(0), dr.maximum(count, 1)
        live = count > 0
        for _ in range(self.steps):
            half = n >> 1
            base = dr.select(below(dr.gather(kind, values, start + base + half, live)) & (half > 0), base + half, base)
            n = n - half
        last = dr.select(below(dr.gather(kind, values, start + base, live)), base + 1, base)
        return dr.minimum(last, dr.maximum(count, 1) - 1)


def _summed(keys: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct `keys`, sorted, and the sum of `weight` of each."""
    order = np.argsort(keys, kind="stable")
    keys = keys[order]
    first = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]]) if len(keys) else np.zeros(0, np.int64)
    return keys[first], np.add.reduceat(weight[order], first) if len(keys) else weight


def _spread(keys: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's weight (keys: (…, cy, cx) in base `CELLS`) counted too in the cells up to `SPREAD` away
    on the square, summed."""
    cx, cy, rest = keys % CELLS, (keys // CELLS) % CELLS, keys - keys % (CELLS * CELLS)
    moved, weights = [], []
    for a in range(-SPREAD, SPREAD + 1):
        for b in range(-SPREAD, SPREAD + 1):
            inside = (cx + a >= 0) & (cx + a < CELLS) & (cy + b >= 0) & (cy + b < CELLS)
            moved.append((rest + (cy + b) * CELLS + cx + a)[inside])
            weights.append(weight[inside])
    return _summed(np.concatenate(moved), np.concatenate(weights))
