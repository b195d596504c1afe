"""The lens as built, traced in NumPy Float64: every surface in its own frame (`placement.frames`: the
coordinate breaks of its surfaces chained), met through its geometry object (`Surface.geometry`, any
kind of `shapes.KINDS`: toroids, cylinders and biconics too), clipped at its clear aperture (and the
stop's iris), refracted by the vector form of Snell's law or bent by an ideal thin lens (`ideal.deflect`),
the optical path accumulated. Rays and results are in the global frame of surface 1 before any break;
the image plane is the last frame's z = 0 plane after the last thickness, moved by the lens's
`image_placement` (a decentred or tilted sensor). A reference for the lens as
built (small bundles: NumPy traces 2–6e6 rays/s); the Dr.Jit tracer in local frames (`tracer_local`) traces the
same lens for the PSFs, while `tracer.trace`, the ghosts, the mesh scene and the lens camera take rotationally
symmetric lenses on one axis only and refuse the others by name (`lens_checks.refuse_as_built`).

For each surface: the ray into its frame (p′ = Rᵀ(p − o), d′ = Rᵀ d), on to its vertex plane, then to the
surface (`Shape.intersect`), the normal there (`Shape.normal`), refraction, and back to the global frame.
Lengths in mm, wavelengths in nm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import ideal
from .lens import Lens
from .paraxial import ideal_conjugates
from .placement import frames
from .surface import RIM_SLACK


@dataclass
class Bundle:
    """Ray points (x, y, z), unit directions (dx, dy, dz) and optical path (mm), NumPy arrays in the global
    frame; `ok`: the rays still travelling (every surface met inside its aperture, no total internal reflection);
    `image_x`, `image_y`: where they meet the image plane, in its own frame, and `stop_x`, `stop_y` where they
    cross the stop surface, in its frame (after `trace`)."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    dz: np.ndarray
    opl: np.ndarray
    ok: np.ndarray
    image_x: np.ndarray | None = None
    image_y: np.ndarray | None = None
    stop_x: np.ndarray | None = None
    stop_y: np.ndarray | None = None


def bundle(points, directions) -> Bundle:
    """A `Bundle` of rays from `points` (…, 3) along `directions` (…, 3; normalised here), path 0."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    p, d = np.broadcast_arrays(p, d)
    (x, y, z), (dx, dy, dz) = p.T.copy(), d.T.copy()
    return Bundle(x, y, z, dx, dy, dz, np.zeros(len(p)), np.ones(len(p), dtype=bool))


def trace(lens: Lens, rays: Bundle, wavelength_nm: float, apertures: bool = True, last: int | None = None) -> Bundle:
    """`rays` (object space, before surface 1) through every surface of `lens` as built, to its image plane;
    without `apertures`, a ray beyond a surface's rim or iris travels on (`ok`: every surface met, no total
    internal reflection), as the chief-ray aim wants its rays; with `last` (0-based), through surfaces 1 to
    `last` only, the rays returned there (no image points)."""
    placed = frames(lens.surfaces, lens.image_placement)
    conjugates = ideal_conjugates(lens) if any(s.ideal for s in lens.surfaces) else {}
    n_before = float(lens.object_glass.index(wavelength_nm))
    p = np.stack([rays.x, rays.y, rays.z], axis=1)
    d = np.stack([rays.dx, rays.dy, rays.dz], axis=1)
    opl, ok = rays.opl * 1.0, rays.ok.copy()
    stop = (None, None)
    for k, (s, (origin, axes)) in enumerate(zip(lens.surfaces, placed)):
        n_after = float(s.glass.index(wavelength_nm))
        lp, ld = (p - origin) @ axes, d @ axes  # into the surface's frame
        with np.errstate(divide="ignore", invalid="ignore"):
            t0 = -lp[:, 2] / ld[:, 2]
        ok &= ld[:, 2] > 0
        x, y = lp[:, 0] + t0 * ld[:, 0], lp[:, 1] + t0 * ld[:, 1]
        t, on = s.geometry.intersect(x, y, *ld.T)
        ok &= on
        x, y, lz = x + t * ld[:, 0], y + t * ld[:, 1], t * ld[:, 2]
        opl = opl + n_before * (t0 + t)
        ok &= (x * x + y * y <= (s.semi_diameter * (1.0 + RIM_SLACK)) ** 2) | (not apertures)
        stop = (x, y) if s.stop else stop
        if s.blades and apertures:
            ok &= s.iris_margin(x, y, np.hypot, np.arctan2, np.cos, np.floor) >= -RIM_SLACK * s.semi_diameter
        if s.focal_length is not None:  # an ideal thin lens
            w = conjugates[k]
            ld, delta = ideal.deflect(x, y, tuple(ld.T), n_before, n_after, 1.0 / s.focal_length, w, np.sqrt)
            ld, opl = np.stack(ld, axis=1), opl + delta
        elif n_after != n_before:
            ld, k2 = _refract(s.geometry.normal(x, y), ld, n_before / n_after)
            ok &= k2 >= 0
        p, d = origin + np.stack([x, y, lz], axis=1) @ axes.T, ld @ axes.T  # back to the global frame
        if k == last:
            return Bundle(*p.T, *d.T, opl, ok, None, None, *stop)
        n_before = n_after
    origin, axes = placed[-1]
    lp, ld = (p - origin) @ axes, d @ axes
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -lp[:, 2] / ld[:, 2]
    image = lp + t[:, None] * ld
    p = origin + image @ axes.T
    (x, y, z), (dx, dy, dz) = p.T, d.T
    return Bundle(x, y, z, dx, dy, dz, opl + n_before * t, ok & np.isfinite(t), image[:, 0], image[:, 1], *stop)


def _refract(normal, d: np.ndarray, mu: float) -> tuple[np.ndarray, np.ndarray]:
    """Directions (N, 3) after refraction with index ratio `mu` = n_before/n_after at unit `normal`s (+z at the
    vertex), and k² (negative: total internal reflection), as the Dr.Jit tracer."""
    n = np.stack(normal, axis=1)
    cosi = np.sum(d * n, axis=1)
    k2 = 1.0 - mu * mu * (1.0 - cosi * cosi)
    g = np.sqrt(np.maximum(k2, 0.0)) - mu * cosi
    return mu * d + g[:, None] * n, k2


__all__ = ["Bundle", "bundle", "trace"]
