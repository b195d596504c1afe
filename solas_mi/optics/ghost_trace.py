"""Ghost paths in the Dr.Jit tracer: each ray follows its own path through the lens, the direct one or a
two-reflection ghost, as `ghost_paths` defines them (cross surfaces 1…j−1, reflect at j, cross back
j−1…i+1, reflect at i, cross i+1…N), for the lens camera (`plugins/lens_camera.py`, option `ghosts`).

A ray's path is given per ray by the two surfaces it reflects at, `first` > `second` (0-based; `DIRECT`,
= the lens's surface count, for the direct path), so one kernel traces a wavefront of mixed paths: the
surfaces are met in three sweeps, forward over 0…N−1, back over N−2…0, forward over 1…N−1, and each ray
takes part in the events of its own path only (`_schedule`). An event meets the surface from either side
(the root of its conic nearest the vertex plane, aspheres by `tracer`'s Newton steps), clips at its clear
aperture and the iris, and reflects or refracts, weighing the ray by the interface's unpolarised
reflectance or transmittance: its coating's (`coated`) where it has one, else Fresnel's (total internal
reflection: R = 1). The direct path so traced is `tracer.trace(fresnel=True)`'s (test_ghost_trace). No
optical path is kept. Lengths in mm, wavelengths in µm (as `tracer`).
"""

from __future__ import annotations

from ..llvm import import_drjit
from . import tracer
from .coated import coating_transmittance
from .lens import Lens
from .surface import RIM_SLACK

dr = import_drjit()


def direct(lens: Lens) -> int:
    """The value of `first` and `second` that names the direct path (no reflection)."""
    return len(lens.surfaces)


def _schedule(n: int):
    """The events of the three sweeps: (surface k, forward, whether ray paths (first, second) meet k, whether
    they reflect there), the last two as functions of the per-ray `first` and `second`."""
    for k in range(n):  # forward, up to the first reflection (the direct path: every surface)
        yield k, True, lambda first, second, k=k: first >= k, lambda first, second, k=k: first == k
    for k in range(n - 2, -1, -1):  # back, from below the first reflection to the second
        yield k, False, lambda first, second, k=k: (first > k) & (second <= k), lambda first, second, k=k: second == k
    for k in range(1, n):  # forward again, after the second reflection
        yield k, True, lambda first, second, k=k: second < k, lambda first, second: False


def trace_paths(lens: Lens, rays: tracer.Rays, wavelength_um, first, second):
    """`rays` (object space, heading for surface 1) each along its path (`first`, `second`: module
    docstring) out of the lens: (the rays after their last surface, whether each arrived, the product of
    its reflectances and transmittances)."""
    ftype, utype, btype = tracer._types(rays.x)
    first, second = utype(first), utype(second)
    state = (rays.x, rays.y, rays.z, rays.dx, rays.dy, rays.dz)
    ok = dr.full(btype, True, dr.width(rays.x))
    weight = dr.ones(ftype, dr.width(rays.x))
    media = [lens.object_glass] + [s.glass for s in lens.surfaces]
    index = [tracer.refractive_index(g, wavelength_um) for g in media]
    for k, forward, meets, reflects in _schedule(len(lens.surfaces)):
        active = meets(first, second) & ok
        reflect = reflects(first, second)
        moved, arrived, power = _event(lens, k, forward, reflect, state, (media, index), wavelength_um, ftype)
        state = tuple(dr.select(active, a, b) for a, b in zip(moved, state))
        ok &= ~active | arrived
        weight = dr.select(active, weight * power, weight)
    x, y, z, dx, dy, dz = state
    return tracer.Rays(x, y, z, dx, dy, dz, dr.zeros(ftype, dr.width(x))), ok, dr.select(ok, weight, 0.0)


def _meet(s, zv: float, state, ftype):
    """Rays (global frame) to surface `s` (vertex at z = `zv`) from either side: the point (x, y, lz, the
    vertex frame) and whether it is met."""
    x, y, z, dx, dy, dz = state
    t0 = (tracer.opaque(zv, ftype) - z) / dz
    x, y = dr.fma(t0, dx, x), dr.fma(t0, dy, y)
    hit = dr.isfinite(t0)
    if s.curvature == 0.0 and s.is_sphere:
        return x, y, dr.zeros(ftype, dr.width(x)), hit
    c = tracer.opaque(s.curvature, ftype)
    b = dz - c * (x * dx + y * dy)
    cc = c * (x * x + y * y)
    disc = b * b - (c if s.conic == 0.0 else c * (1.0 + s.conic * dz * dz)) * cc
    root = dr.sqrt(dr.maximum(disc, 0.0))
    t = cc / dr.select(b >= 0, b + root, b - root)  # the root nearest the vertex plane, either way
    hit &= (disc >= 0) & dr.isfinite(t)
    t = dr.select(hit, t, 0.0)
    if any(s.aspheric) or any(s.qbfs):
        t, on = tracer._asphere_hit(s, x, y, dx, dy, dz, t)
        hit &= on
    return dr.fma(t, dx, x), dr.fma(t, dy, y), t * dz, hit


def _event(lens: Lens, k: int, forward: bool, reflect, state, media, wavelength_um, ftype):
    """Rays `state` at surface k met going `forward` or back, reflected where `reflect`, else crossed: (the
    new state, whether met and inside the apertures (and not totally reflected where crossing), the power
    kept)."""
    s, zv = lens.surfaces[k], float(lens.vertex_z[k])
    x, y, lz, ok = _meet(s, zv, state, ftype)
    dx, dy, dz = state[3:]
    ok &= (dz > 0) if forward else (dz < 0)
    r2 = x * x + y * y
    ok &= r2 <= tracer.opaque((s.semi_diameter * (1.0 + RIM_SLACK)) ** 2, ftype)
    if s.blades:
        ok &= s.iris_margin(x, y, lambda a, b: dr.sqrt(a * a + b * b), dr.atan2, dr.cos, dr.floor) >= (
            -RIM_SLACK * s.semi_diameter
        )
    z = lz + tracer.opaque(zv, ftype)
    glasses, index = media
    if glasses[k] == glasses[k + 1]:  # no interface (a stop in air): nothing bends or reflects
        return (x, y, z, dx, dy, dz), ok, 1.0
    order = (k, k + 1) if forward else (k + 1, k)
    nx, ny, nz = tracer.surface_normal(s, x, y, lz, r2, ftype)
    cosi = dx * nx + dy * ny + dz * nz
    sign = dr.select(cosi < 0, -1.0, 1.0)  # the normal turned along the ray
    nx, ny, nz, cosi = nx * sign, ny * sign, nz * sign, cosi * sign
    mu = index[order[0]] / index[order[1]]
    k2 = 1.0 - mu * mu * (1.0 - cosi * cosi)
    cost = dr.sqrt(dr.maximum(k2, 0.0))
    reflectance = _reflectance(s, glasses[order[0]], glasses[order[1]], wavelength_um, ftype, mu, cosi, cost)
    g = dr.select(reflect, -2.0 * cosi, cost - mu * cosi)
    scale = dr.select(reflect, 1.0, mu)
    moved = (x, y, z, dr.fma(scale, dx, g * nx), dr.fma(scale, dy, g * ny), dr.fma(scale, dz, g * nz))
    power = dr.select(reflect, reflectance[0], reflectance[1])
    return moved, ok & (reflect | (k2 >= 0)), power


def _reflectance(s, before, after, wavelength_um, ftype, mu, cosi, cost):
    """(R, T) of surface `s` for light from medium `before` into `after` at cos θ `cosi` (index ratio `mu`,
    cos θ′ `cost`): its coating's, else Fresnel's equations, (s + p)/2."""
    if s.coating is not None:
        return tuple(
            coating_transmittance(s.coating, before, after, wavelength_um, ftype, reflect)(cosi)
            for reflect in (True, False)
        )
    rs = (mu * cosi - cost) / (mu * cosi + cost)
    rp = (cosi - mu * cost) / (cosi + mu * cost)
    r = 0.5 * (rs * rs + rp * rp)
    return r, 1.0 - r
