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
directions and every ray's wavelength stratified too (Latin hypercube), the wavelength drawn from the
camera response as the camera draws it (`sample_quantile`, weight 1/p(λ)). Each ray carries the light per
area of the plane × the cell's area (`ghost_sources.light`) × the path's reflectances and transmittances
× 1/p(λ), in the camera's units (× its `norm`, over the pixel's area): an unbiased estimate of the image
irradiance the camera's samples estimate. It lands on the film plane and is put into a Mitsuba
`ImageBlock` with the film's reconstruction filter, its weights normalised (each ray's light is kept), its
colour the film's (one wavelength in lane 0, `spectrum_to_srgb`).

How many rays (`counts`): a pilot pass of `PILOT`² rays per (source, path) measures each path's light on
the film E, the share f of its rays that land, and the area A (px) its light covers (4π √det of the
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
from .ghost_sources import CONE, light, sources

PILOT = 32  # pilot rays per side, per (source, path)
DENSITY = 4.0  # landings per pixel and sample in the brightest ghost
BUDGET = 16.0  # rays at most per pixel and sample, over every source and path
MEASURED = 32  # pilot landings a path needs for its area (and brightness) to count
CHUNK = 1 << 19  # rays traced at once
METHOD = (
    "light-traced: rays from each source (area emitters, delta lights, an environment map's sun) along every "
    "two-reflection path of the lens to the film"
)


def stray_light(scene, sensor, spp: int, seed: int = 0):
    """The stray light of `sensor`'s (a `lens_camera`) ghosts in `scene` at `spp` (module docstring): (the
    image, crop rows × columns × 3 (the film's RGB), float64; what the metadata says of it)."""
    start = time.perf_counter()
    to_world = np.array(sensor.world_transform().matrix, dtype=np.float64).reshape(4, 4)
    found, skipped = sources(scene, to_world)
    paths = ghost_paths.paths(sensor.lens)
    rng = np.random.default_rng([seed, 0x5EED])
    film = sensor.film()
    size = tuple(int(v) for v in film.crop_size())
    block = mi.ImageBlock(mi.ScalarVector2u(size), mi.ScalarPoint2i(0, 0), 5, film.rfilter(), normalize=True)
    context = (scene, sensor, to_world, size, block)
    pilots = [_trace(context, s, paths, np.full(len(paths), PILOT * PILOT), rng, splat=False) for s in found]
    counts = _counts(pilots, spp * size[0] * size[1], spp)
    for source, n in zip(found, counts):
        _trace(context, source, paths, n, rng, splat=True)
    image = np.array(block.tensor(), dtype=np.float64)[..., :3]
    meta = {
        "method": METHOD,
        "sources": [s.name for s in found],
        "not_traced": skipped + ["light scattered by the scene's surfaces, a sky without a sun"],
        "rays": int(sum(int(n.sum()) for n in counts)),
        "seconds": time.perf_counter() - start,
    }
    return np.nan_to_num(image, nan=0.0, posinf=0.0, neginf=0.0), meta


def _counts(pilots, pixel_samples: int, spp: int) -> list[np.ndarray]:
    """The main pass's rays per (source, path) from the pilots' (light, landed share, area) (module
    docstring)."""
    if not pilots:
        return []
    light, share, area, landed = (np.array([p[i] for p in pilots]) for i in range(4))
    bright = float(np.where(landed >= MEASURED, light / area, 0.0).max())
    wanted = np.where(light > 0, DENSITY * spp * light / max(bright, 1e-300) / np.maximum(share, 1e-3), 0.0)
    wanted = np.maximum(wanted, PILOT * PILOT)
    wanted *= min(1.0, BUDGET * pixel_samples / wanted.sum())
    return list(np.maximum(np.ceil(wanted), 1).astype(np.int64))


def _reach(lens, source, scene, sensor, to_world) -> float:
    """Half the side of the entrance square: surface 1's clear aperture, widened by its rim's sag along
    the source's steepest direction (a delta light's: the one at the vertex)."""
    front = lens.surfaces[0]
    if source.kind == CONE:
        steepest = math.acos(min(1.0, float(source.axis[2]))) + source.radius
    else:
        wav = _lanes(mi.Float(550.0))
        d, _ = light(scene, source, to_world, sensor.world_unit_mm, (np.zeros(1), np.zeros(1)), np.zeros((2, 1)), wav)
        steepest = math.acos(float(np.clip(d[2, 0], -1.0, 1.0))) + 0.05
    rim = abs(float(front.sag(front.semi_diameter)))
    return 1.02 * front.semi_diameter + rim * min(math.tan(min(steepest, 1.5)), 4.0)


def _lanes(lam):
    """A Mitsuba Spectrum of wavelengths `lam` in every lane (a mono variant's: none)."""
    return mi.Spectrum(lam) if mi.is_spectral else mi.Color0f()


def _lane0(value: np.ndarray):
    """A Mitsuba Spectrum whose colour (`spectrum_to_srgb`, the mean of the lanes') is lane 0's `value`'s."""
    if not mi.is_spectral:
        return mi.Spectrum(mi.Float(value))
    return mi.Spectrum(mi.Float(4.0 * value), 0.0, 0.0, 0.0)


def _samples(counts: np.ndarray, reach: float, rng):
    """Per (path k, counts[k] rays, rounded up to a square): path index, entrance points stratified on
    the square ±`reach`, and three more stratified uniforms (direction, wavelength), each its own
    permutation of strata; the area of each ray's cell (mm²)."""
    sides = np.ceil(np.sqrt(counts)).astype(np.int64)
    index = np.repeat(np.arange(len(counts)), sides * sides)
    parts = []
    for m in sides:
        cells = np.arange(m * m)
        parts.append(np.stack([((cells % m) + rng.random(m * m)) / m, ((cells // m) + rng.random(m * m)) / m]))
    ex, ey = (np.concatenate(parts, axis=1) * 2.0 - 1.0) * reach
    u = np.concatenate(
        [np.stack([(rng.permutation(m * m) + rng.random(m * m)) / (m * m) for _ in range(3)]) for m in sides], axis=1
    )
    return index, ex, ey, u, (2.0 * reach) ** 2 / (sides * sides)[index]


def _trace(context, source, paths, counts: np.ndarray, rng, splat: bool):
    """`counts[k]` rays of `source` along each of `paths`, traced to the film: splatted into the block
    (`splat`), else the pilot's (light on the film, landed share, area in px) per path."""
    scene, sensor, to_world, size, block = context
    lens = sensor.lens
    index, ex, ey, u, cell = _samples(counts, _reach(lens, source, scene, sensor, to_world), rng)
    sums = np.zeros((len(paths), 7))  # per path: rays, landed rays, Σw, Σw·c, Σw·r, Σw·c², Σw·r² (…and c·r below)
    cross = np.zeros(len(paths))
    for lo in range(0, index.size, CHUNK):
        part = slice(lo, lo + CHUNK)
        lam, inverse_pdf = sensor.wavelengths.sample_quantile(mi.Float(u[2, part]))
        wav = _lanes(lam)
        d, carried = light(scene, source, to_world, sensor.world_unit_mm, (ex[part], ey[part]), u[:2, part], wav)
        col, row, value = _land(sensor, (ex[part], ey[part]), d, np.array(lam, dtype=np.float64), index[part])
        value *= carried * cell[part] * np.array(inverse_pdf, dtype=np.float64)
        landed = (col >= 0) & (col < size[0]) & (row >= 0) & (row < size[1]) & (value > 0)
        if splat:
            spectrum = _lane0(np.where(landed, value, 0.0))
            block.put(mi.Point2f(mi.Float(col), mi.Float(row)), wav, spectrum, 0.0, 0.0, mi.Bool(landed))
            continue
        k, w, c, r = index[part][landed], value[landed], col[landed], row[landed]
        sums[:, 0] += np.bincount(index[part], minlength=len(paths))
        for j, v in enumerate((np.ones_like(w), w, w * c, w * r, w * c * c, w * r * r), start=1):
            sums[:, j] += np.bincount(k, weights=v, minlength=len(paths))
        cross += np.bincount(k, weights=w * c * r, minlength=len(paths))
    if splat:
        return None
    return _pilot_figures(sums, cross)


def _pilot_figures(sums: np.ndarray, cross: np.ndarray):
    """(light on the film, landed share, area in px, landed rays) per path from the pilot's sums."""
    w = np.maximum(sums[:, 2], 1e-300)
    mc, mr = sums[:, 3] / w, sums[:, 4] / w
    vc, vr, vcr = sums[:, 5] / w - mc * mc, sums[:, 6] / w - mr * mr, cross / w - mc * mr
    area = 4.0 * math.pi * np.sqrt(np.maximum(vc * vr - vcr * vcr, 0.0))
    return sums[:, 2], sums[:, 1] / np.maximum(sums[:, 0], 1.0), np.maximum(area, 1.0), sums[:, 1]


def _land(sensor, points, d, lam_nm: np.ndarray, index: np.ndarray):
    """Rays through entrance `points` of the vertex plane along lens-frame `d`, traced along their
    paths (`index` into `ghost_paths.paths`) to the film plane: (column, row of the crop window, the
    path's reflectances and transmittances × the camera's `norm` over the pixel's area (mm²))."""
    lens = sensor.lens
    paths = ghost_paths.paths(lens)
    z0 = tracer.launch_plane_z(lens)
    dz = np.where(d[2] > 0, d[2], 1.0)
    t = -z0 / dz
    rays = tracer.Rays(
        *(tracer.F(v) for v in (points[0] - t * d[0], points[1] - t * d[1], np.full(dz.size, z0), d[0], d[1], dz)),
        tracer.F(np.zeros(dz.size)),
    )
    first = tracer.UInt32(np.array([p[0] for p in paths], dtype=np.uint32)[index])
    second = tracer.UInt32(np.array([p[1] for p in paths], dtype=np.uint32)[index])
    leaving, ok, power = ghost_trace.trace_paths(lens, rays, tracer.F(lam_nm * 1e-3), first, second)
    x, y, z, dx, dy, dzo, ok, power = tracer.to_numpy(
        *(getattr(leaving, a) for a in ("x", "y", "z", "dx", "dy", "dz")), ok, power
    )
    ok = ok & (dzo > 0) & (d[2] > 0)
    s = (lens.image_z - z) / np.where(ok, dzo, 1.0)
    fx, fy = x + s * dx, y + s * dy
    pitch = sensor.pitch_mm
    col = fx / pitch + 0.5 * sensor.film_size[0] - sensor.crop_offset[0]
    row = 0.5 * sensor.film_size[1] - fy / pitch - sensor.crop_offset[1]
    value = np.where(ok, power, 0.0) * sensor.norm / (pitch * pitch)
    return np.where(ok, col, -1.0), np.where(ok, row, -1.0), np.nan_to_num(value)
