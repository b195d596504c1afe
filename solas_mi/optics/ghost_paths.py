"""Two-reflection ghost paths, traced sequentially in NumPy Float64: for surfaces 1…N that reflect (a
change of medium), each pair i < j gives the path that crosses 1…j−1, reflects at j, crosses back
j−1…i+1, reflects at i and crosses i+1…N to the image plane: N(N−1)/2 paths. The direct image is the
path without reflections. Every crossing clips at the surface's clear aperture (the stop's iris too)
and weighs the ray by the interface's unpolarised transmittance, each reflection by its reflectance:
the surface's coating (`coating`) or Fresnel's equations for the bare interface, (s + p)/2 per event
(no polarisation is carried from one event to the next, as sequential ghost analyses do).

Surfaces: spheres, planes, conics in closed form, even aspheres and Qbfs by Newton's method from the
conic root (as `tracer`), met from either side: the root nearest the vertex plane. Ideal thin lenses
have no glass to reflect or to cross backwards and are refused. Lengths in mm, wavelengths in nm.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..errors import SolasError
from .coating import stack_power
from .lens import Lens
from .lens_checks import refuse_as_built
from .sag import ASPHERE_ITERATIONS, ASPHERE_TOL_MM, sag, sag_slope
from .surface import RIM_SLACK

DEFAULT_RAYS = 128  # rays × rays over the first surface's clear aperture, per path and wavelength


@dataclass
class Rays:
    """Positions, unit directions, power and whether each ray still travels (NumPy arrays)."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    dz: np.ndarray
    power: np.ndarray
    alive: np.ndarray
    ids: np.ndarray | None = None  # each ray's index in the launch (kept as rays drop out)


def reflecting(lens: Lens) -> list[int]:
    """The surfaces (0-based) that reflect: where the medium changes; SolasError for an ideal thin lens, a
    surface without rotational symmetry or a coordinate break."""
    refuse_as_built(lens, "the ghost tracer")
    ideal = [k + 1 for k, s in enumerate(lens.surfaces) if s.ideal]
    if ideal:
        raise SolasError(
            f"lens {lens.name}: surface {ideal[0]} is an ideal thin lens (focal_length), which has no "
            "glass to reflect from or cross backwards; ghosts need real surfaces"
        )
    media = [lens.object_glass] + [s.glass for s in lens.surfaces]
    return [k for k in range(len(lens.surfaces)) if media[k] != media[k + 1]]


def paths(lens: Lens) -> list[tuple[int, int]]:
    """Every two-reflection path (j, i), reflecting first at j then at i < j (0-based), in the order j, i."""
    surfaces = reflecting(lens)
    return [(j, i) for jj, j in enumerate(surfaces) for i in surfaces[:jj]]


def events(lens: Lens, path: tuple[int, int] | None) -> list[tuple[int, bool]]:
    """The surfaces a path meets in order, each with whether it reflects there (None: the direct path)."""
    n = len(lens.surfaces)
    if path is None:
        return [(k, False) for k in range(n)]
    j, i = path
    return (
        [(k, False) for k in range(j)]
        + [(j, True)]
        + [(k, False) for k in range(j - 1, i, -1)]
        + [(i, True)]
        + [(k, False) for k in range(i + 1, n)]
    )


def _hit(s, zv: float, r: Rays) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rays to surface `s` (vertex at z = zv) from either side: the point (x, y, z − zv) and whether met."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (zv - r.z) / r.dz
    x, y = r.x + t0 * r.dx, r.y + t0 * r.dy
    ok = r.alive & np.isfinite(t0)
    c, k = s.curvature, s.conic
    if c == 0.0 and s.is_sphere:
        return x, y, np.zeros_like(x), ok
    b = r.dz - c * (x * r.dx + y * r.dy)
    cc = c * (x * x + y * y)
    disc = b * b - c * (1.0 + k * r.dz * r.dz) * cc
    ok &= disc >= 0
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(b >= 0, cc / (b + root), cc / (b - root))  # the root nearest the vertex plane, either way
    t = np.where(np.isfinite(t), t, 0.0)
    if not s.is_sphere and (any(s.aspheric) or any(s.qbfs)):
        for _ in range(ASPHERE_ITERATIONS):
            px, py = x + t * r.dx, y + t * r.dy
            r2 = px * px + py * py
            f = t * r.dz - sag(r2, **s.shape)
            df = r.dz - 2.0 * sag_slope(r2, **s.shape) * (px * r.dx + py * r.dy)
            with np.errstate(divide="ignore", invalid="ignore"):
                t = np.where(df != 0, t - f / df, t)
        px, py = x + t * r.dx, y + t * r.dy
        r2 = px * px + py * py
        inside = (1.0 + s.conic) * s.curvature**2 * r2 <= 1.0  # within the conic's domain, as the tracer
        ok &= inside & (np.abs(t * r.dz - sag(r2, **s.shape)) < ASPHERE_TOL_MM) & np.isfinite(t)
    return x + t * r.dx, y + t * r.dy, t * r.dz, ok


def _normal(s, x, y, lz):
    """Unit normals (+z at the vertex) of surface `s` at local points."""
    if s.curvature == 0.0 and s.is_sphere:
        return np.zeros_like(x), np.zeros_like(x), np.ones_like(x)
    slope = 2.0 * sag_slope(x * x + y * y, **s.shape)
    norm = 1.0 / np.sqrt(1.0 + slope * slope * (x * x + y * y))
    return -slope * x * norm, -slope * y * norm, norm


def interface(s, before, after, wavelength_nm: float, cos_in: np.ndarray, reflect: bool) -> np.ndarray:
    """The unpolarised power a ray keeps at surface `s` going from medium `before` into `after` (glasses),
    meeting it at cos θ = `cos_in`: the reflectance where it reflects, else the transmittance; the surface's
    coating where it has one, else Fresnel's equations."""
    n_in, n_out = _index(before, wavelength_nm), _index(after, wavelength_nm)
    if s.coating is not None:
        power = s.coating.power(n_in, n_out, wavelength_nm, cos_in)
    else:
        power = stack_power(n_in, [], [], n_out, wavelength_nm, cos_in)
    return power.reflectance if reflect else power.transmittance


def trace(lens: Lens, path: tuple[int, int] | None, rays: Rays, wavelength_nm: float) -> Rays:
    """`rays` (object space, heading for surface 1) along `path` (None: the direct one) to its last surface,
    their power multiplied by every event's reflectance or transmittance: the rays that arrive only."""
    r, forward = _copy(rays), True  # the way the path runs: forward to its first reflection, back, then on
    for k, reflect in events(lens, path):
        r = step(lens, k, reflect, forward, r, wavelength_nm)
        forward ^= reflect
    return r


def trace_all(lens: Lens, rays: Rays, wavelength_nm: float) -> dict:
    """`trace` of the direct path (key None) and of every path of `paths` (keys (j, i)), sharing what paths
    share: the rays arriving at j on the direct path, and for each j those arriving back at each i."""
    surfaces, n = reflecting(lens), len(lens.surfaces)
    arriving, r = [], _copy(rays)
    for k in range(n):
        arriving.append(r)
        r = step(lens, k, False, True, r, wavelength_nm)
    out = {None: r}
    for j in surfaces:
        back = step(lens, j, True, True, arriving[j], wavelength_nm)  # reflected at j, heading back
        for k in range(j - 1, surfaces[0] - 1, -1):
            if k in surfaces:
                ghost = step(lens, k, True, False, back, wavelength_nm)
                for m in range(k + 1, n):
                    ghost = step(lens, m, False, True, ghost, wavelength_nm)
                out[(j, k)] = ghost
            if k > surfaces[0]:
                back = step(lens, k, False, False, back, wavelength_nm)
    return out


def step(lens: Lens, k: int, reflect: bool, forward: bool, r: Rays, wavelength_nm: float) -> Rays:
    """Rays `r` at surface k (0-based), met going `forward` or back: clipped, then reflected or crossed, their
    power weighed; only those that go on."""
    media = [lens.object_glass] + [s.glass for s in lens.surfaces]
    s, zv = lens.surfaces[k], float(lens.vertex_z[k])
    r = Rays(r.x, r.y, r.z, r.dx, r.dy, r.dz, r.power, r.alive & ((r.dz > 0) == forward), r.ids)
    x, y, lz, ok = _hit(s, zv, r)
    if s.stop and s.blades:
        ok &= s.iris_margin(x, y, np.hypot, np.arctan2, np.cos, np.floor) >= -RIM_SLACK * s.semi_diameter
    ok &= x * x + y * y <= (s.semi_diameter * (1.0 + RIM_SLACK)) ** 2
    r = Rays(x, y, lz + zv, r.dx, r.dy, r.dz, r.power, ok, r.ids)
    r, (x, y, lz) = _alive(r, x, y, lz)
    if media[k] == media[k + 1]:  # no interface: nothing bends or reflects (a stop in air, a dummy)
        return r
    n_in, n_other = (media[k], media[k + 1]) if forward else (media[k + 1], media[k])
    nx, ny, nz = _normal(s, x, y, lz)
    cosi = r.dx * nx + r.dy * ny + r.dz * nz
    sign = np.where(cosi < 0, -1.0, 1.0)  # the normal turned along the ray
    nx, ny, nz, cosi = nx * sign, ny * sign, nz * sign, cosi * sign
    power = r.power * interface(s, n_in, n_other, wavelength_nm, cosi, reflect)
    r = _bend(r, (nx, ny, nz), cosi, n_in, n_other, wavelength_nm, reflect, r.alive)
    r.power = power
    return r


@lru_cache(maxsize=256)
def _index(glass, wavelength_nm: float) -> float:
    """A medium's index, kept: a path asks for each a few times per surface."""
    return float(glass.index(wavelength_nm))


def _copy(rays: Rays) -> Rays:
    return Rays(
        *(np.array(a, dtype=np.float64) for a in (rays.x, rays.y, rays.z, rays.dx, rays.dy, rays.dz, rays.power)),
        rays.alive.copy(),
        np.arange(len(rays.x)),
    )


def _alive(r: Rays, *more: np.ndarray) -> tuple[Rays, tuple[np.ndarray, ...]]:
    """Only the rays still travelling (most of a ghost's are stopped early): `r` and `more` compacted."""
    if r.alive.all():
        return r, more
    keep = np.flatnonzero(r.alive)
    return Rays(*(a[keep] for a in (r.x, r.y, r.z, r.dx, r.dy, r.dz, r.power, r.alive, r.ids))), tuple(
        a[keep] for a in more
    )


def _bend(r: Rays, normal, cosi, n_in, n_out, wavelength_nm: float, reflect: bool, ok) -> Rays:
    """Directions after reflecting, or refracting from `n_in` into `n_out` (glasses); rays totally
    reflected where they should cross are lost (a ray that should reflect off a bare interface beyond the
    critical angle reflects it all: Fresnel's R is 1 there)."""
    nx, ny, nz = normal
    if reflect:
        g = -2.0 * cosi
        return Rays(r.x, r.y, r.z, r.dx + g * nx, r.dy + g * ny, r.dz + g * nz, r.power, ok, r.ids)
    mu = _index(n_in, wavelength_nm) / _index(n_out, wavelength_nm)
    k2 = 1.0 - mu * mu * (1.0 - cosi * cosi)
    g = np.sqrt(np.maximum(k2, 0.0)) - mu * cosi
    return Rays(
        r.x, r.y, r.z, mu * r.dx + g * nx, mu * r.dy + g * ny, mu * r.dz + g * nz, r.power, ok & (k2 >= 0), r.ids
    )
