"""Sequential ray tracer in Dr.Jit Float64 (LLVM): exact spheres, planes, conics (closed form) and
even aspheres (Newton's method from the conic root, exact normal), Snell's law per wavelength,
clipping at every clear aperture and the stop, total internal reflection flagged, optical path length
accumulated; ideal thin lenses bend rays and add the path that images their pencil perfectly (`ideal`).

Rays are vectorised Dr.Jit arrays; nothing here loops over rays in Python. `launch` and `trace` work on
the array type of the rays they are given: `drjit.llvm.Float64` (the default `F`, for the analyses),
the AD or CUDA Float64 of a Mitsuba variant (a sensor tracing inside a render), or Python floats (one
ray, Mitsuba's scalar variants). Lengths in mm, wavelengths in µm inside this module (nm at every
public interface above it).

Reference: G. H. Spencer and M. V. R. K. Murty, "General Ray-Tracing Procedure", J. Opt. Soc. Am.
52(6), 672–678, 1962 (transfer to the vertex plane, then the surface; vector refraction). The sphere
root is taken in its cancellation-free form t = C / (B + √(B² − cC)), and the path in Float64:
Float32 leaves ~20 nm of OPD noise (DESIGN.md).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ..llvm import import_drjit
from . import ideal
from .coated import coating_transmittance
from .fields import ANGLE
from .lens import Lens
from .lens_checks import refuse_as_built
from .paraxial import ideal_conjugates, paraxial, pupil_distance
from .sag import ASPHERE_ITERATIONS, ASPHERE_TOL_MM, sag, sag_slope
from .surface import RIM_SLACK as _RIM_SLACK

dr = import_drjit()
from drjit.llvm import Bool, Float64, UInt32  # noqa: E402

F = Float64


@dataclass
class Rays:
    """Ray positions, unit directions and optical path (mm) as Dr.Jit Float64 arrays."""

    x: F
    y: F
    z: F
    dx: F
    dy: F
    dz: F
    opl: F


@dataclass
class Traced:
    """Result of tracing through every surface."""

    rays: Rays  # at the last surface, directions in image space
    ok: Bool  # geometric success: every surface hit, no total internal reflection
    tir: Bool  # total internal reflection at some surface
    clipped_by: UInt32  # 1-based index of the first aperture (clear or stop) that blocks the ray; 0 = none
    stop_x: F  # where the ray crosses the stop surface (mm)
    stop_y: F
    n_image: F  # refractive index of image space
    transmittance: F | float = 1.0  # of every refraction, unpolarised, its coating's where it has one (fresnel=True)


def opaque(value: float, ftype=F) -> F:
    """A scalar as an opaque value of `ftype`, so kernels are reused across lenses and wavelengths."""
    return dr.opaque(ftype, float(value))


def _kernel_input(value, like):
    """A Python number as an opaque value of Dr.Jit array `like`'s type (a literal: new kernels per lens)."""
    return opaque(value, type(like)) if isinstance(value, (int, float)) and dr.is_array_v(like) else value


def _types(value) -> tuple[type, type, type]:
    """The Float64, UInt32 and Bool types of the array family of `value` (Python float, bool, int for
    a Python float)."""
    ftype = dr.float64_array_t(type(value))
    return ftype, dr.uint32_array_t(ftype), dr.mask_t(ftype)


def refractive_index(glass, wavelength_um: F) -> F:
    """n(λ) as a Dr.Jit array (λ in µm), the glass's numbers opaque (a melt or another glass reuses the kernels)."""
    return glass.index_formula(wavelength_um, dr.sqrt, dr.select, partial(opaque, ftype=_types(wavelength_um)[0]))


def launch_plane_z(lens: Lens) -> float:
    """z (mm) of the point where collimated rays start: in front of every surface's sag (also of a surface
    whose vertex a negative thickness puts before surface 1's)."""
    reach = max(s.semi_diameter for s in lens.surfaces)
    return min(0.0, float(lens.vertex_z.min())) - (2.0 * reach + 10.0)


def beam_basis(tan_x, tan_y, sqrt):
    """Direction d of collimated rays with field tangents (tan_x, tan_y) and the basis (e1, e2) of the
    plane across the beam: e1 ⟂ y, e2 = d × e1. Any array type (NumPy, Dr.Jit) given its `sqrt`."""
    inv = 1.0 / sqrt(tan_x * tan_x + tan_y * tan_y + 1.0)
    dx, dy, dz = tan_x * inv, tan_y * inv, inv
    inv1 = 1.0 / sqrt(dz * dz + dx * dx)
    e1x, e1z = dz * inv1, -dx * inv1
    return (dx, dy, dz), (e1x, 0.0 * e1x, e1z), (dy * e1z, dz * e1x - dx * e1z, -dy * e1x)


def launch(lens: Lens, tan_x: F, tan_y: F, ex: F, ey: F, object_point: tuple[F, F] | None = None) -> Rays:
    """Rays for field tangents (tan_x, tan_y) and entrance coordinates (ex, ey), mm.

    Object at infinity: the ray starts on the plane through (0, 0, launch_plane_z) perpendicular to
    the field direction, at (ex, ey) in that plane's basis (e1 ⟂ y, e2 = d × e1); OPL starts at 0 there.
    Finite object: the ray leaves `object_point` (x, y at z = −distance) aiming at (ex, ey, 0) (a virtual
    object, distance < 0: the ray along that line, converging toward the point behind surface 1); a far
    or virtual one starts where it crosses the plane z = launch_plane_z, with the geometric path from the object
    point less the radius of the sphere about that point through (0, 0, launch_plane_z) as its OPL
    (`trace` scales it by the object-space index): a constant per object point, so OPDs keep their
    meaning while no path of the object's distance enters the sums.
    """
    ftype = _types(ex)[0]
    if object_point is None:
        (dx, dy, dz), (e1x, _, e1z), (e2x, e2y, e2z) = beam_basis(tan_x, tan_y, dr.sqrt)
        z0 = opaque(launch_plane_z(lens), ftype)
        x = ex * e1x + ey * e2x
        y = ey * e2y
        z = z0 + ex * e1z + ey * e2z
        return Rays(x, y, z, dx, dy, dz, dr.zeros(ftype, dr.width(x)))
    ox, oy = object_point
    zs = launch_plane_z(lens)
    if -zs >= lens.object_distance > 0:  # a near object (a film, in a reversed lens): start at the point itself
        oz = opaque(-lens.object_distance, ftype)
        vx, vy, vz = ex - ox, ey - oy, -oz + 0.0 * ex
        inv = dr.rsqrt(vx * vx + vy * vy + vz * vz)
        return Rays(ox + 0.0 * ex, oy + 0.0 * ex, oz + 0.0 * ex, vx * inv, vy * inv, vz * inv,
                    dr.zeros(ftype, dr.width(ex)))
    # A far object: start on the plane z = zs, with the path from the object point measured from the
    # sphere about it through (0, 0, zs): s − R = (s² − R²)/(s + R), free of the cancellation that two
    # paths of up to 1e12 mm would leave (0.1 µm of noise, a fifth of a wave). A virtual object (d < 0,
    # behind surface 1): the same line through the object point and (ex, ey, 0), travelling toward the
    # point, whose converging wave reaches the sphere of radius s before that of radius R: the path R − s.
    d, z0 = opaque(lens.object_distance, ftype), opaque(zs, ftype)
    sx, sy = (ex - ox) / d, (ey - oy) / d  # slopes toward (ex, ey, 0)
    x, y = dr.fma(z0, sx, ex), dr.fma(z0, sy, ey)
    h = z0 + d
    s_len = dr.sqrt((x - ox) * (x - ox) + (y - oy) * (y - oy) + h * h)
    r_len = dr.sqrt(ox * ox + oy * oy + h * h)
    inv = dr.rsqrt(sx * sx + sy * sy + 1.0)
    opl = (x * (x - 2.0 * ox) + y * (y - 2.0 * oy)) / (s_len + r_len) * (-1.0 if lens.virtual_object else 1.0)
    return Rays(x, y, z0 + 0.0 * ex, sx * inv, sy * inv, inv, opl)


def _sphere_from_launch(c, x, y, wz, dx, dy, dz):
    """Distance t (mm) along the ray from (x, y, wz), relative to a sphere's vertex, to the sphere
    c|p|² − 2 p_z = 0 near its vertex, for rays of any direction (fields at or beyond 90° meet surface
    1 travelling sideways or backwards, dz ≤ 0, so they cannot be moved to the vertex plane first).
    Returns (wz, t, hit)."""
    b = dz - c * (x * dx + y * dy + wz * dz)
    cc = c * (x * x + y * y + wz * wz) - 2.0 * wz
    disc = b * b - c * cc
    return wz, cc / (b + dr.sqrt(dr.maximum(disc, 0.0))), (disc >= 0) & (b > 0)


def launch_direction(lens: Lens, dx: F, dy: F, dz: F, ex: F, ey: F) -> Rays:
    """Collimated rays of unit direction (dx, dy, dz), any polar angle up to 180° (object at infinity),
    and entrance coordinates (ex, ey), mm: the ray starts on the plane perpendicular to d through
    −L·d (L = −launch_plane_z, outside every surface), at ex·e1 + ey·e2. With θ, φ the polar angles
    of d, e1 = cos φ e_θ − sin φ e_φ and e2 = sin φ e_θ + cos φ e_φ, well defined at every θ (e1 = x,
    e2 = y on axis; the same basis as `beam_basis` on the y axis). OPL starts at 0 there."""
    ftype = _types(ex)[0]
    reach = opaque(-launch_plane_z(lens), ftype)
    s = dr.sqrt(dx * dx + dy * dy)
    cos_t, sin_t = dz, s
    on_axis = s == 0.0
    cos_p = dr.select(on_axis, 1.0, dx / dr.select(on_axis, 1.0, s))
    sin_p = dr.select(on_axis, 0.0, dy / dr.select(on_axis, 1.0, s))
    # e_θ = (cos θ cos φ, cos θ sin φ, −sin θ), e_φ = (−sin φ, cos φ, 0)
    e1x = cos_p * cos_p * cos_t + sin_p * sin_p
    e1y = cos_p * sin_p * (cos_t - 1.0)
    e1z = -cos_p * sin_t
    e2x = e1y
    e2y = sin_p * sin_p * cos_t + cos_p * cos_p
    e2z = -sin_p * sin_t
    x = dr.fma(ex, e1x, ey * e2x) - reach * dx
    y = dr.fma(ex, e1y, ey * e2y) - reach * dy
    z = dr.fma(ex, e1z, ey * e2z) - reach * dz
    return Rays(x, y, z, dx + 0.0 * ex, dy + 0.0 * ex, dz + 0.0 * ex, dr.zeros(ftype, dr.width(x)))


def trace(lens: Lens, rays: Rays, wavelength_um: F, fresnel: bool = False, heights: list | None = None) -> Traced:
    """Trace `rays` (in object space, before surface 1) through every surface of `lens`, in the array
    type of the rays (see the module docstring); with `fresnel`, also the product of the unpolarised
    Fresnel transmittances (1 − (r_s² + r_p²)/2) of every refraction, a coated surface's coating's
    (`coating_transmittance`) where it has one; a `heights` list receives each
    surface's squared ray height x² + y² (mm², for automatic clear apertures)."""
    refuse_as_built(lens, "the Dr.Jit tracer")
    x, y, z, dx, dy, dz, opl = rays.x, rays.y, rays.z, rays.dx, rays.dy, rays.dz, rays.opl
    ftype, utype, btype = _types(x)
    ok = dr.full(btype, True, dr.width(x))
    tir = dr.full(btype, False, dr.width(x))
    clipped = dr.zeros(utype, dr.width(x))
    transmittance = 1.0
    stop_x = stop_y = None
    n_before = refractive_index(lens.object_glass, wavelength_um)
    opl = opl * n_before  # a launch's geometric path in object space
    conjugates = ideal_conjugates(lens) if any(s.ideal for s in lens.surfaces) else {}
    for k, (s, zv) in enumerate(zip(lens.surfaces, lens.vertex_z)):
        sideways = k == 0 and lens.field_type.sideways  # rays from the side or behind
        x, y, lz, t, opl, hit = _to_surface(s, zv, Rays(x, y, z, dx, dy, dz, opl), n_before, sideways, ftype)
        ok &= hit
        x, y, lz = dr.fma(t, dx, x), dr.fma(t, dy, y), dr.fma(t, dz, lz)
        opl = dr.fma(n_before, t, opl)
        r2 = x * x + y * y
        if heights is not None:
            heights.append(r2)
        blocked = r2 > opaque((s.semi_diameter * (1.0 + _RIM_SLACK)) ** 2, ftype)
        if s.blades:  # the iris's polygon, inside the clear circle
            blocked |= s.iris_margin(x, y, lambda a, b: dr.sqrt(a * a + b * b), dr.atan2, dr.cos, dr.floor,
                                     partial(opaque, ftype=ftype)) < opaque(-_RIM_SLACK * s.semi_diameter, ftype)
        clipped = dr.select((clipped == 0) & blocked, utype(k + 1), clipped)
        if s.stop:
            stop_x, stop_y = x, y
        n_after = refractive_index(s.glass, wavelength_um)
        if s.ideal:
            (dx, dy, dz), delta = ideal.deflect(x, y, (dx, dy, dz), n_before, n_after, opaque(1.0 / s.focal_length, ftype),
                                                None if conjugates[k] is None else opaque(conjugates[k], ftype),
                                                dr.sqrt)
            opl = opl + delta
        elif s.glass != (lens.surfaces[k - 1].glass if k else lens.object_glass):
            coated = (coating_transmittance(s.coating, lens.surfaces[k - 1].glass if k else lens.object_glass, s.glass,
                                            wavelength_um, ftype) if fresnel and s.coating is not None else None)
            (dx, dy, dz), k2, factor = _refract(surface_normal(s, x, y, lz, r2, ftype), (dx, dy, dz), n_before / n_after,
                                                fresnel, coated)
            tir |= k2 < 0
            ok &= k2 >= 0
            if fresnel:
                transmittance = transmittance * factor
        z = lz + opaque(zv, ftype)
        n_before = n_after
    return Traced(Rays(x, y, z, dx, dy, dz, opl), ok, tir, clipped, stop_x, stop_y, n_before, transmittance)


def _to_surface(s, zv: float, rays: Rays, n_before: F, sideways: bool, ftype):
    """Rays (global frame) to surface `s` with its vertex at z = `zv`: (x, y, lz, t, opl, hit), the
    ray's point (x, y, lz relative to the vertex) from which the surface lies t (mm) along it, the optical
    path to that point and whether the surface is met. Rays are first moved to the vertex plane, so
    the sphere equation is solved from nearby, free of the cancellation that a distant start point (a
    finite object far away) would bring into B² − cC; `sideways` rays (polar fields at surface 1) meet a
    curved sphere from where they are."""
    x, y, z, dx, dy, dz, opl = rays.x, rays.y, rays.z, rays.dx, rays.dy, rays.dz, rays.opl
    if sideways and s.curvature != 0.0 and s.is_sphere:
        lz, t, hit = _sphere_from_launch(opaque(s.curvature, ftype), x, y, z - opaque(zv, ftype), dx, dy, dz)
        return x, y, lz, t, opl, hit
    t0 = (opaque(zv, ftype) - z) / dz
    hit = dz > 0
    x, y = dr.fma(t0, dx, x), dr.fma(t0, dy, y)
    lz = dr.zeros(ftype, dr.width(x))
    opl = dr.fma(n_before, t0, opl)
    if s.curvature == 0.0 and s.is_sphere:
        return x, y, lz, dr.zeros(ftype, dr.width(x)), opl, hit
    c = opaque(s.curvature, ftype)
    b = dz - c * (x * dx + y * dy)
    cc = c * (x * x + y * y)
    # conic: A t² − 2B t + C = 0 with A = c (1 + k dz²) (= c for a sphere)
    disc = b * b - (c if s.conic == 0.0 else c * (1.0 + s.conic * dz * dz)) * cc
    on = (disc >= 0) & (b > 0)
    # cancellation-free root nearest the vertex: t = C / (B + sqrt(B² − AC))
    t = cc / (b + dr.sqrt(dr.maximum(disc, 0.0)))
    if any(s.aspheric) or any(s.qbfs):
        t, on = _asphere_hit(s, x, y, dx, dy, dz, dr.select(on, t, 0.0))
    return x, y, lz, t, opl, hit & on


def _refract(normal, d, mu, fresnel: bool, coated=None):
    """Directions after refraction at a surface of unit `normal` (+z at its vertex) of unit directions `d` with
    index ratio `mu` = n_before / n_after: (new directions, k2 (negative: total internal reflection), the
    unpolarised transmittance when `fresnel`, else None): the bare interface's Fresnel transmittance, or
    `coated(cos θ)` where the surface has a coating."""
    dx, dy, dz = d
    nx, ny, nz = normal
    cosi = dx * nx + dy * ny + dz * nz
    k2 = 1.0 - mu * mu * (1.0 - cosi * cosi)
    cost = dr.sqrt(dr.maximum(k2, 0.0))
    factor = None
    if fresnel and coated is not None:
        factor = coated(cosi)
    elif fresnel:
        rs = (mu * cosi - cost) / (mu * cosi + cost)
        rp = (cosi - mu * cost) / (cosi + mu * cost)
        factor = 1.0 - 0.5 * (rs * rs + rp * rp)
    g = cost - mu * cosi
    return (dr.fma(mu, dx, g * nx), dr.fma(mu, dy, g * ny), dr.fma(mu, dz, g * nz)), k2, factor


def surface_normal(s, x, y, lz, r2, ftype):
    """The unit normal of surface `s` (+z at its vertex) at its point (x, y, lz) in its vertex frame, r2 = x² + y²."""
    if s.curvature == 0.0 and s.is_sphere:
        return dr.zeros(ftype, 1), dr.zeros(ftype, 1), dr.ones(ftype, 1)
    if s.is_sphere:
        c = opaque(s.curvature, ftype)
        return -c * x, -c * y, 1.0 - c * lz
    # an exact even asphere: (−2x s', −2y s', 1) / |…|
    slope = 2.0 * sag_slope(r2, **s.shape_in(partial(opaque, ftype=ftype)), sqrt=dr.sqrt, maximum=dr.maximum)
    nz = dr.rsqrt(dr.fma(slope * slope, r2, 1.0))
    return -slope * x * nz, -slope * y * nz, nz


def _asphere_hit(s, x, y, dx, dy, dz, t):
    """Ray parameter t where the ray (x, y, 0) + t (dx, dy, dz), in the vertex frame of surface `s`,
    meets its even asphere: Newton's method on f(t) = z(t) − sag(r²(t)) from the conic root `t`.
    Also whether it converged (|f| < ASPHERE_TOL_MM inside the conic's domain)."""
    shape = s.shape_in(partial(opaque, ftype=_types(x)[0]))
    for _ in range(ASPHERE_ITERATIONS):
        px, py = dr.fma(t, dx, x), dr.fma(t, dy, y)
        r2 = px * px + py * py
        f = t * dz - sag(r2, **shape, sqrt=dr.sqrt, maximum=dr.maximum)
        df = dz - 2.0 * sag_slope(r2, **shape, sqrt=dr.sqrt, maximum=dr.maximum) * (px * dx + py * dy)
        t = t - f / df
    px, py = dr.fma(t, dx, x), dr.fma(t, dy, y)
    r2 = px * px + py * py
    residual = t * dz - sag(r2, **shape, sqrt=dr.sqrt, maximum=dr.maximum)
    inside = opaque((1.0 + s.conic) * s.curvature ** 2, type(r2)) * r2 <= 1.0  # (also within the Qbfs factor's)
    return t, inside & (dr.abs(residual) < ASPHERE_TOL_MM) & dr.isfinite(t)


def to_plane(traced: Traced, z_plane: float | F) -> tuple[F, F, F]:
    """Image-space rays continued to the plane z = `z_plane`: (x, y, optical path to it)."""
    r = traced.rays
    t = (_kernel_input(z_plane, r.z) - r.z) / r.dz
    return dr.fma(t, r.dx, r.x), dr.fma(t, r.dy, r.y), dr.fma(traced.n_image, t, r.opl)


def to_sphere(traced: Traced, cx: F, cy: F, cz: F, radius: F) -> tuple[F, F, F, Bool]:
    """Image-space rays continued (forward or back) to the sphere of `radius` about (cx, cy, cz),
    on the side away from the centre: (x, y, z, optical path to it) and whether it was hit."""
    r = traced.rays
    wx, wy, wz = r.x - cx, r.y - cy, r.z - _kernel_input(cz, r.z)
    b = wx * r.dx + wy * r.dy + wz * r.dz
    c = wx * wx + wy * wy + wz * wz - radius * radius
    disc = b * b - c
    hit = disc >= 0
    far = -b + dr.sqrt(dr.maximum(disc, 0.0))  # root beyond the centre; the near one is c / far
    t = c / far
    x, y, z = dr.fma(t, r.dx, r.x), dr.fma(t, r.dy, r.y), dr.fma(t, r.dz, r.z)
    return x, y, z, dr.fma(traced.n_image, t, r.opl), hit


def field_tangents(field_deg: np.ndarray) -> np.ndarray:
    """(…, 2) field angles in degrees → tangents."""
    return ANGLE.incoming(field_deg)


def object_points(lens: Lens, field_deg: np.ndarray) -> np.ndarray | None:
    """Object points (x, y) in mm for field angles, finite objects only (None at infinity).

    A field angle names the chief ray's direction toward the entrance pupil at the primary wavelength.
    """
    if lens.at_infinity:
        return None
    return -field_tangents(field_deg) * pupil_distance(lens, paraxial(lens).entrance_pupil_z_mm)


def array(values: np.ndarray, ftype=F):
    """A NumPy array as a Dr.Jit array of `ftype` (Float64, a Float32 type or UInt32), in memory aligned for Dr.Jit's
    vector loads. (Dr.Jit maps a NumPy array in place and compiles the kernels that read it for the
    alignment of its address: kernels over NumPy's own memory were compiled afresh whenever an allocation
    happened to land differently, measured at 20-40 compilations of 10-100 ms in each 8x8 PSF grid.)"""
    values = np.asarray(values)
    dtype = np.uint32 if ftype is UInt32 else np.float64 if ftype is F else np.float32
    if not (values.dtype == dtype and values.flags.c_contiguous and values.ctypes.data % _ALIGN == 0):
        values = aligned(values.shape, dtype, values)
    return ftype(values.ravel())


def aligned(shape, dtype, values=None) -> np.ndarray:
    """A new NumPy array of `shape` and `dtype` whose memory Dr.Jit maps as aligned (`array`), holding
    `values` where given (else uninitialised)."""
    size = int(np.prod(shape))
    raw = np.empty(size + _ALIGN // np.dtype(dtype).itemsize, dtype=dtype)
    start = (-raw.ctypes.data % _ALIGN) // raw.itemsize
    out = raw[start:start + size].reshape(shape)
    if values is not None:
        out[...] = values
    return out


_ALIGN = 64  # bytes: the alignment Dr.Jit's LLVM backend checks (drjit-core's jitc_var_mem_map)


def gather(values: np.ndarray, index: UInt32) -> F:
    """Per-ray Dr.Jit values from per-group NumPy values."""
    return dr.gather(F, array(values), index)


def to_numpy(*values) -> tuple[np.ndarray, ...]:
    """Dr.Jit arrays as NumPy arrays, evaluated together: converting them one by one would run
    the whole trace kernel once per array."""
    dr.eval(*values)
    return tuple(np.asarray(v) for v in values)


__all__ = ["Rays", "Traced", "launch", "launch_direction", "trace", "to_plane", "to_sphere", "field_tangents", "object_points",
           "aligned", "array", "gather", "to_numpy", "refractive_index", "launch_plane_z", "opaque"]
