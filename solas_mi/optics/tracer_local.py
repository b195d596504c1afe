"""The Dr.Jit tracer for every lens, the lens as built too (`lens_checks.as_built`: decentred or tilted
surfaces, a placed sensor, toroids, cylinders, biconics). A lens on one axis of rotationally symmetric
surfaces goes to `tracer.trace` unchanged (bit for bit); a lens as built is traced as `local_trace` traces
it in NumPy, in Dr.Jit Float64: each surface in its own frame (`placement.frames`), the rays carried from
one frame to the next by the relative move p′ = Mp + v, d′ = Md (M = R_nextᵀ R, v = R_nextᵀ(o − o_next)),
met by `tracer`'s own closed forms and Newton's method for the rotationally symmetric kinds and by Newton's
method on the shape's sag and gradient (`Shape.sag_and_gradient`, `base.NEWTON_STEPS` steps from the
vertex plane, as `Shape.intersect`) for the others, clipped, refracted (with coatings and Fresnel
transmittance) or bent by an ideal lens as `tracer.trace` does.

The result is a `tracer.Traced` whose rays lie in the image plane's frame moved along its own z axis to
z = `Lens.image_z`: `tracer.to_plane(traced, lens.image_z)` gives points on the (possibly decentred or tilted)
sensor in its own x and y, as for a lens on one axis (where that frame is the global one). `stop_x`, `stop_y`
are in the stop's frame; `heights` each surface's x² + y² in its frame. Lengths in mm, wavelengths in µm.
"""

from __future__ import annotations

import numpy as np

from ..llvm import import_drjit
from . import ideal, local_trace, tracer
from .coated import coating_transmittance
from .lens import Lens
from .lens_checks import as_built
from .paraxial import ideal_conjugates
from .placement import frames
from .sag import ASPHERE_TOL_MM
from .shapes.base import NEWTON_STEPS
from .surface import RIM_SLACK
from .tracer import Rays, Traced, opaque, refractive_index

dr = import_drjit()


def trace(lens: Lens, rays: Rays, wavelength_um, fresnel: bool = False, heights: list | None = None) -> Traced:
    """`rays` (object space, before surface 1) through every surface of `lens`, any lens: `tracer.trace`'s
    arguments and result (the module docstring for the frames of a lens as built)."""
    if not as_built(lens):
        return tracer.trace(lens, rays, wavelength_um, fresnel, heights)
    ftype, utype, btype = tracer._types(rays.x)
    width = dr.width(rays.x)
    path = _Path(dr.full(btype, True, width), dr.full(btype, False, width), dr.zeros(utype, width))
    placed = frames(lens.surfaces, lens.image_placement)
    n_before = refractive_index(lens.object_glass, wavelength_um)
    rays = Rays(rays.x, rays.y, rays.z, rays.dx, rays.dy, rays.dz, rays.opl * n_before)
    conjugates = ideal_conjugates(lens) if any(s.ideal for s in lens.surfaces) else {}
    frame = (np.zeros(3), np.eye(3))
    for k, s in enumerate(lens.surfaces):
        rays, frame = _moved(rays, frame, placed[k], ftype), placed[k]
        n_after = refractive_index(s.glass, wavelength_um)
        before = lens.surfaces[k - 1].glass if k else lens.object_glass
        coated = (
            coating_transmittance(s.coating, before, s.glass, wavelength_um, ftype)
            if fresnel and s.coating is not None and s.glass != before
            else None
        )
        ideal_w = None if not s.ideal or conjugates[k] is None else opaque(conjugates[k], ftype)
        rays = _surface(s, k, rays, (n_before, n_after), path, (fresnel, coated, ideal_w, heights), lens, ftype)
        n_before = n_after
    origin, axes = placed[-1]
    image = (origin - axes[:, 2] * lens.image_z, axes)  # the image frame moved to put its plane at z = image_z
    out = _moved(rays, frame, image, ftype)
    return Traced(out, path.ok, path.tir, path.clipped, path.stop_x, path.stop_y, n_before, path.transmittance)


class _Path:
    """What `trace` gathers along the way: `tracer.Traced`'s ok, tir, clipped_by, stop and transmittance."""

    def __init__(self, ok, tir, clipped):
        self.ok, self.tir, self.clipped = ok, tir, clipped
        self.stop_x = self.stop_y = None
        self.transmittance = 1.0


def _moved(rays: Rays, frame, to, ftype) -> Rays:
    """`rays` in `frame` (origin, axes) expressed in frame `to`: p′ = Mp + v, d′ = Md (nothing multiplied where M = 1)."""
    m = to[1].T @ frame[1]
    v = to[1].T @ (frame[0] - to[0])
    p, d = (rays.x, rays.y, rays.z), (rays.dx, rays.dy, rays.dz)
    if not np.array_equal(m, np.eye(3)):
        p, d = (_rotated(m, a, ftype) for a in (p, d))
    p = tuple(a + opaque(b, ftype) if b != 0.0 else a for a, b in zip(p, v))
    return Rays(*p, *d, rays.opl)


def _rotated(m: np.ndarray, a, ftype):
    """The vector `a` (three arrays) times the 3×3 NumPy matrix `m`."""
    return tuple(sum(opaque(m[i, j], ftype) * a[j] for j in range(3)) for i in range(3))


def _surface(s, k: int, rays: Rays, indices, path: _Path, options, lens: Lens, ftype) -> Rays:
    """`rays` in the frame of surface `s` (index `k`) met, clipped and refracted there (`trace`'s loop body);
    `indices` (n before, n after), `options` (fresnel, coated, the ideal lens's conjugate, heights)."""
    fresnel, coated, ideal_w, heights = options
    n_before, n_after = indices
    dx, dy, dz = rays.dx, rays.dy, rays.dz
    if s.form is None:
        sideways = k == 0 and lens.field_type.sideways
        x, y, lz, t, opl, hit = tracer._to_surface(s, 0.0, rays, n_before, sideways, ftype)
    else:
        x, y, lz, t, opl, hit = _to_shape(s.form, rays, n_before, ftype)
    path.ok &= hit
    x, y, lz = dr.fma(t, dx, x), dr.fma(t, dy, y), dr.fma(t, dz, lz)
    opl = dr.fma(n_before, t, opl)
    r2 = x * x + y * y
    if heights is not None:
        heights.append(r2)
    blocked = r2 > opaque((s.semi_diameter * (1.0 + RIM_SLACK)) ** 2, ftype)
    if s.blades:
        hypot = lambda a, b: dr.sqrt(a * a + b * b)  # noqa: E731
        blocked |= s.iris_margin(x, y, hypot, dr.atan2, dr.cos, dr.floor) < -RIM_SLACK * s.semi_diameter
    path.clipped = dr.select((path.clipped == 0) & blocked, type(path.clipped)(k + 1), path.clipped)
    if s.stop:
        path.stop_x, path.stop_y = x, y
    if s.ideal:
        inverse_f = opaque(1.0 / s.focal_length, ftype)
        (dx, dy, dz), delta = ideal.deflect(x, y, (dx, dy, dz), n_before, n_after, inverse_f, ideal_w, dr.sqrt)
        opl = opl + delta
    elif s.glass != (lens.surfaces[k - 1].glass if k else lens.object_glass):
        normal = tracer.surface_normal(s, x, y, lz, r2, ftype) if s.form is None else _normal(s.form, x, y)
        (dx, dy, dz), k2, factor = tracer._refract(normal, (dx, dy, dz), n_before / n_after, fresnel, coated)
        path.tir |= k2 < 0
        path.ok &= k2 >= 0
        if fresnel:
            path.transmittance = path.transmittance * factor
    return Rays(x, y, lz, dx, dy, dz, opl)


def _to_shape(form, rays: Rays, n_before, ftype):
    """Rays (in the frame of a surface of shape `form`) to its vertex plane, then Newton's method on
    f(t) = t dz − sag(x + t dx, y + t dy) from t = 0 (`Shape.intersect`'s): `tracer._to_surface`'s result."""
    x, y, z, dx, dy, dz = rays.x, rays.y, rays.z, rays.dx, rays.dy, rays.dz
    t0 = -z / dz
    x, y = dr.fma(t0, dx, x), dr.fma(t0, dy, y)
    opl = dr.fma(n_before, t0, rays.opl)
    t = dr.zeros(ftype, dr.width(x))
    for _ in range(NEWTON_STEPS):
        f, gx, gy = form.sag_and_gradient(dr.fma(t, dx, x), dr.fma(t, dy, y), dr.sqrt)
        t = t - (t * dz - f) / (dz - gx * dx - gy * dy)
    residual = t * dz - form.sag_and_gradient(dr.fma(t, dx, x), dr.fma(t, dy, y), dr.sqrt)[0]
    on = dr.isfinite(t) & (dr.abs(residual) < ASPHERE_TOL_MM)
    return x, y, dr.zeros(ftype, dr.width(x)), t, opl, (dz > 0) & on


def _normal(form, x, y):
    """The unit normal (−∂z/∂x, −∂z/∂y, 1)/|…| of shape `form` at (x, y) (`Shape.normal`'s)."""
    _, gx, gy = form.sag_and_gradient(x, y, dr.sqrt)
    nz = dr.rsqrt(1.0 + gx * gx + gy * gy)
    return -gx * nz, -gy * nz, nz


def trace_bundle(lens: Lens, rays: local_trace.Bundle, wavelength_nm: float) -> local_trace.Bundle:
    """`local_trace.trace(lens, rays, wavelength_nm)` (apertures on) computed by `trace` in Dr.Jit: the rays to the
    image plane, in the global frame and in the image plane's own x and y, the stop crossings in the stop's frame."""
    start = tracer.Rays(*(tracer.array(a) for a in (rays.x, rays.y, rays.z, rays.dx, rays.dy, rays.dz, rays.opl)))
    traced = trace(lens, start, opaque(wavelength_nm * 1e-3))
    x, y, opl = tracer.to_plane(traced, lens.image_z)
    passed = traced.ok & (traced.clipped_by == 0) & dr.isfinite(x) & dr.isfinite(y)
    d = traced.rays
    x, y, opl, passed, dx, dy, dz, stop_x, stop_y = tracer.to_numpy(
        x, y, opl, passed, d.dx, d.dy, d.dz, traced.stop_x, traced.stop_y
    )
    origin, axes = frames(lens.surfaces, lens.image_placement)[-1]
    with np.errstate(invalid="ignore"):  # a lost ray's NaNs
        p = origin + np.stack([x, y, np.zeros_like(x)], axis=1) @ axes.T
        d = np.stack([dx, dy, dz], axis=1) @ axes.T
    return local_trace.Bundle(*p.T, *d.T, opl, passed & rays.ok, x, y, stop_x, stop_y)


__all__ = ["trace", "trace_bundle"]
