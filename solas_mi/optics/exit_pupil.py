"""Where rays from a point on the image plane can leave the lens: a bound on the exit pupil per
image-plane radius, found by tracing the lens backwards (the image plane as a finite object of the
reversed lens) with the Float64 tracer.

The bound is a rectangle on the plane of the last surface's vertex, in the frame of the film point:
u along its radial direction, v across it, or the ellipse inscribed in it where that holds every
passing ray (a round stop seen straight on). A sensor samples rays uniformly inside it; rays that the
lens blocks are absorbed by the scene's rims and stop, so a bound only has to contain the pupil.
Lengths are in mm.

The idea, bounds on the exit pupil per radial bin of the film found once by tracing, is pbrt-v4's
RealisticCamera (M. Pharr, W. Jakob, G. Humphreys, "Physically Based Rendering: From Theory to
Implementation", 4th ed., MIT Press, 2023); here they are found by bisecting to the pupil's rim
through the reversed lens in Float64, rather than by testing rays over the rear element's square.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from .lens import Lens
from .lens_checks import refuse_as_built
from .overlap import check_image_distance
from .surface import Surface

FINE = 512  # points per side of the search for a pupil the coarse grid missed
MARCH = 48  # samples along each direction from the pupil's centroid to three times the aperture's reach
CHECK = 256  # points per side of the grid over the aperture's reach that checks the bounds at CHECK_RADII film radii
CHECK_RADII = 9


def reversed_lens(lens: Lens) -> Lens:
    """The lens seen from the image side: surfaces in reverse order, mirrored in z, the image plane
    as a finite object. Vertex z of the reversed lens = last vertex z − original vertex z. SolasError for a
    lens as built (not reversed here: `lens_checks.refuse_as_built`)."""
    refuse_as_built(lens, "reversing a lens (for its exit-pupil bounds)")
    s = lens.surfaces
    before = [lens.object_glass] + [x.glass for x in s[:-1]]
    materials = ["AIR"] + [x.material for x in s[:-1]]
    rev = []
    for i in range(len(s) - 1, -1, -1):
        thickness = s[i - 1].thickness if i > 0 else 1.0  # beyond the original first surface: unused
        rev.append(
            Surface(
                s[i].label,
                -s[i].radius,
                thickness,
                s[i].diameter,
                materials[i],
                before[i],
                s[i].stop,
                s[i].conic,
                tuple(-a for a in s[i].aspheric),
                tuple(-a for a in s[i].qbfs),
                s[i].norm_radius,
                s[i].focal_length,
                s[i].coating,
                s[i].blades,
                s[i].blade_rotation,
                blade_curvature=s[i].blade_curvature,
            )
        )
    return replace(
        lens,
        name=lens.name + " (reversed)",
        surfaces=tuple(rev),
        object_distance=s[-1].thickness,
        object_glass=s[-1].glass,
    )


@dataclass(frozen=True)
class PupilBounds:
    """Per film radius (mm), the rectangle [u0, u1]×[v0, v1] (mm, film-point frame) on the plane
    z = plane_z that holds every ray leaving the lens, and whether its inscribed ellipse does too."""

    radius_mm: np.ndarray  # (n,) increasing from 0
    bounds_mm: np.ndarray  # (n, 4): u0, u1, v0, v1
    elliptical: np.ndarray  # (n,) bool
    plane_z: float

    def at(self, r: np.ndarray) -> np.ndarray:
        """Conservative bounds (…, 5) at film radii r, from the two enclosing table rows (radius_mm[i]
        ≤ r < radius_mm[i + 1]; a radius on a row takes that row and the next): the union of their
        rectangles, and 0; or, where both rows are elliptical, the box of an ellipse holding both
        rows' ellipses, and 1. Ellipses (c_k, semi-axes a_k) lie inside the ellipse of centre c, the
        rows' mean, and semi-axes (1 + m)·max a_k, m the largest |(c_k − c)/max a_k|: a point
        c_k + a_k w (|w| ≤ 1) is c + (c_k − c) + a_k w, of norm ≤ m + 1 in units of max a_k."""
        i = np.clip(np.searchsorted(self.radius_mm, r, side="right") - 1, 0, len(self.radius_mm) - 2)
        a, b = self.bounds_mm[i], self.bounds_mm[i + 1]
        box = np.stack(
            [
                np.minimum(a[..., 0], b[..., 0]),
                np.maximum(a[..., 1], b[..., 1]),
                np.minimum(a[..., 2], b[..., 2]),
                np.maximum(a[..., 3], b[..., 3]),
            ],
            axis=-1,
        )
        centre = [0.5 * (a[..., 0:3:2] + a[..., 1:4:2]), 0.5 * (b[..., 0:3:2] + b[..., 1:4:2])]  # (u, v) each
        semi = np.maximum(0.5 * (a[..., 1:4:2] - a[..., 0:3:2]), 0.5 * (b[..., 1:4:2] - b[..., 0:3:2]))
        c = 0.5 * (centre[0] + centre[1])
        m = np.linalg.norm((centre[0] - c) / np.maximum(semi, 1e-300), axis=-1)
        semi = semi * (1.0 + m)[..., None]
        ellipse = np.stack(
            [c[..., 0] - semi[..., 0], c[..., 0] + semi[..., 0], c[..., 1] - semi[..., 1], c[..., 1] + semi[..., 1]],
            axis=-1,
        )
        both = (self.elliptical[i] & self.elliptical[i + 1])[..., None]
        return np.concatenate([np.where(both, ellipse, box), both.astype(float)], axis=-1)


def passes(rev: Lens, x: np.ndarray, y: np.ndarray, ex: np.ndarray, ey: np.ndarray, wavelength_nm: float) -> np.ndarray:
    """Whether the ray from image point (x, y) toward (ex, ey) on the last vertex plane leaves the lens
    (`rev`: the `reversed_lens`)."""
    from . import tracer

    n = len(ex)
    zero = tracer.F(np.zeros(n))
    rays = tracer.launch(
        rev, zero, zero, tracer.F(ex), tracer.F(ey), (tracer.F(np.broadcast_to(x, n)), tracer.F(np.broadcast_to(y, n)))
    )
    tr = tracer.trace(rev, rays, tracer.F(np.full(n, wavelength_nm * 1e-3)))
    ok, clipped = tracer.to_numpy(tr.ok, tr.clipped_by)
    return ok & (clipped == 0)


def pupil_bounds(
    lens: Lens, max_radius_mm: float, wavelengths_nm=None, radii: int = 64, directions: int = 256, coarse: int = 64
) -> PupilBounds:
    """Exit-pupil bounds for film radii 0…max_radius_mm, over `wavelengths_nm` (default: the lens's).

    Per radius and wavelength, a coarse grid over the last surface's aperture finds the pupil's centroid;
    along `directions` rays from it, a march inward from beyond the aperture finds the outermost passing
    sample (a pupil need not be convex: strong aberration or total internal reflection can cut it into
    a disc and a ring) and bisection the rim beyond it, to 1e-9 mm. The bound is the box of the rim
    points, widened by the most a convex rim can bulge between neighbouring directions."""
    check_image_distance(lens, "the exit pupil's bounds (the lens camera's pupil sampling)")
    rev = reversed_lens(lens)
    reach = exit_reach(lens, max_radius_mm)
    step = 2.0 * reach / coarse
    g = -reach + (np.arange(coarse) + 0.5) * step
    grid = tuple(a.ravel() for a in np.meshgrid(g, g))
    radius = np.linspace(0.0, max_radius_mm, radii) * (1.0 + 1.0 / radii)  # the last row lies past the corner
    phi = 2.0 * np.pi * np.arange(directions) / directions
    seen = np.zeros(radii, dtype=bool)
    rim_u, rim_v = [], []
    for w in lens.wavelengths_nm if wavelengths_nm is None else wavelengths_nm:
        cu, cv, lit = _centroids(rev, radius, grid, reach, w)
        seen |= lit
        u, v = _rim(rev, radius, cu, cv, lit, phi, reach, w)
        rim_u.append(u)
        rim_v.append(v)
    bounds, elliptical = _box(np.array(rim_u), np.array(rim_v), directions)
    bounds[~seen] = 0.0  # nothing reaches these film radii
    escaped, cell, excess = _check(
        rev, radius, bounds, elliptical, reach, lens.wavelengths_nm if wavelengths_nm is None else wavelengths_nm
    )
    ellipse = (elliptical & seen)[:, None]
    if excess > 1.0:  # rays outside an ellipse (a cat's eye's corner between rim points): every ellipse grown
        centre, half = 0.5 * (bounds[:, 0::2] + bounds[:, 1::2]), 0.5 * (bounds[:, 1::2] - bounds[:, 0::2])
        half = np.where(ellipse, half * excess + cell, half)
        bounds = np.stack(
            [
                centre[:, 0] - half[:, 0],
                centre[:, 0] + half[:, 0],
                centre[:, 1] - half[:, 1],
                centre[:, 1] + half[:, 1],
            ],
            axis=-1,
        )
    if escaped.any():  # rays outside a rectangle: every rectangle widened by the most any missed, and a grid cell
        bounds += np.where(ellipse, 0.0, (escaped + cell) * (escaped > 0) * np.array([-1.0, 1.0, -1.0, 1.0]))
    if escaped.max() > 2.0 * cell:  # more than the rim's rounding: a part of the pupil the march stepped over
        warnings.warn(
            f"the exit-pupil bounds of {lens.name} missed a thin part of the pupil (rays up to "
            f"{escaped.max():.3g} mm outside); widened to hold every checked ray",
            stacklevel=2,
        )
    return PupilBounds(radius, bounds, elliptical & seen, float(lens.vertex_z[-1]))


def _check(
    rev: Lens, radius: np.ndarray, bounds: np.ndarray, elliptical: np.ndarray, reach: float, wavelengths_nm
) -> tuple[np.ndarray, float, float]:
    """The most (mm, ≥ 0) by which rays that leave the lens pass outside the bounds (u0, u1, v0, v1 sides),
    over a CHECK² grid on ±reach at CHECK_RADII film radii (a thin ring that the march stepped over;
    zeros where every checked ray lies inside), the grid's cell (mm), and the most by which the
    ellipse of an elliptical row must grow (a factor of its semi-axes, ≥ 1) to hold them."""
    step = 2.0 * reach / CHECK
    g = -reach + (np.arange(CHECK) + 0.5) * step
    gu, gv = (a.ravel() for a in np.meshgrid(g, g))
    out, excess = np.zeros(4), 1.0
    for i in np.unique(np.linspace(0, len(radius) - 1, CHECK_RADII).astype(int)):
        u0, u1, v0, v1 = bounds[i]
        for w in wavelengths_nm:
            ok = passes(rev, np.full(len(gu), radius[i]), 0.0, gu, gv, w)
            u, v = gu[ok], gv[ok]
            if not len(u):
                continue
            miss = np.array([u0 - u.min(), u.max() - u1, v0 - v.min(), v.max() - v1])
            out = np.maximum(out, miss)
            e = ((2.0 * u - u0 - u1) / (u1 - u0)) ** 2 + ((2.0 * v - v0 - v1) / (v1 - v0)) ** 2
            excess = max(excess, float(np.sqrt(e.max())) if elliptical[i] else 1.0)
    return out, step, excess


def exit_reach(lens: Lens, max_radius_mm: float) -> float:
    """Half width (mm) of a square on the last vertex plane that holds every ray leaving the lens toward
    film radii up to max_radius_mm. A ray leaves through a point of the last surface's clear aperture;
    seen from a film point at radius r, thickness T below the vertex plane, a point at height ρ and
    sag z projects onto that plane at r + T/(T − z)·(ρ − r): within ρ of the axis for z = 0 and within
    s·ρ + |1 − s|·r at the rim, s = T/(T − sag) (> 1 for a rim bent toward the film, < 1 for one bent
    away, a ball lens's)."""
    last = lens.surfaces[-1]
    rho, sag = last.semi_diameter, float(last.sag(last.semi_diameter))
    s_rim = last.thickness / max(last.thickness - sag, 1e-9)
    return 1.05 * max(rho, s_rim * rho + abs(1.0 - s_rim) * max_radius_mm)


def _centroids(
    rev: Lens, radius: np.ndarray, grid: tuple[np.ndarray, np.ndarray], reach: float, w: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per film radius, the centroid (u, v) (mm) of the passing points of the coarse `grid`, and
    whether any ray passes (a row the coarse grid misses is searched on a FINE grid)."""
    gx, gy = grid
    radii = len(radius)
    ok = passes(rev, np.repeat(radius, len(gx)), 0.0, np.tile(gx, radii), np.tile(gy, radii), w).reshape(radii, -1)
    count = np.maximum(ok.sum(axis=1), 1)
    cu, cv = (ok * gx).sum(axis=1) / count, (ok * gy).sum(axis=1) / count
    lit = ok.any(axis=1)
    empty = np.flatnonzero(~lit)
    if len(empty):  # a sliver of pupil (heavy vignetting at the field's edge) can fall between coarse points
        fu, fv = (a.ravel() for a in np.meshgrid(*2 * [-reach + (np.arange(FINE) + 0.5) * (2.0 * reach / FINE)]))
        fine = passes(
            rev, np.repeat(radius[empty], len(fu)), 0.0, np.tile(fu, len(empty)), np.tile(fv, len(empty)), w
        ).reshape(len(empty), -1)
        n = np.maximum(fine.sum(axis=1), 1)
        cu[empty], cv[empty] = (fine * fu).sum(axis=1) / n, (fine * fv).sum(axis=1) / n
        lit[empty] = fine.any(axis=1)
    return cu, cv, lit


def _rim(
    rev: Lens,
    radius: np.ndarray,
    cu: np.ndarray,
    cv: np.ndarray,
    lit: np.ndarray,
    phi: np.ndarray,
    reach: float,
    w: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Rim points (u, v) (radii, directions) (mm) of the pupil along directions `phi` from its centroid
    (cu, cv): a march in from beyond the aperture to the outermost passing sample of each direction, so
    a pupil that is not convex (a disc and a ring, a crescent) keeps its outer rim; then bisection to it."""
    radii, directions = len(radius), len(phi)
    r_all = np.repeat(radius, directions)
    cos, sin = np.tile(np.cos(phi), radii), np.tile(np.sin(phi), radii)
    t = np.linspace(0.0, 3.0 * reach, MARCH + 1)
    su = np.repeat(cu, directions)[:, None] + t * cos[:, None]
    sv = np.repeat(cv, directions)[:, None] + t * sin[:, None]
    hit = passes(rev, np.repeat(r_all, MARCH + 1), 0.0, su.ravel(), sv.ravel(), w).reshape(radii, directions, -1)
    last_in = np.where(hit.any(axis=-1), MARCH - np.argmax(hit[..., ::-1], axis=-1), 0)
    inside, outside = t[np.minimum(last_in, MARCH)], t[np.minimum(last_in + 1, MARCH)]
    for _ in range(42):
        mid = 0.5 * (inside + outside).ravel()
        p = passes(rev, r_all, 0.0, np.repeat(cu, directions) + mid * cos, np.repeat(cv, directions) + mid * sin, w)
        p = p.reshape(radii, directions) & lit[:, None]
        inside, outside = np.where(p, mid.reshape(radii, -1), inside), np.where(p, outside, mid.reshape(radii, -1))
    return cu[:, None] + inside * np.cos(phi), cv[:, None] + inside * np.sin(phi)


def _box(rim_u: np.ndarray, rim_v: np.ndarray, directions: int) -> tuple[np.ndarray, np.ndarray]:
    """Bounds (radii, 4) u0, u1, v0, v1 (mm) of the rim points (wavelengths, radii, directions), widened
    by the most a convex rim can bulge between two of them, and whether they are elliptical: the
    box's centred ellipse, grown until it holds every rim point (and widened like the box), has less
    area than the box (then the bounds are that ellipse's box: the rectangle holds the pupil too)."""
    lo_u, hi_u = rim_u.min(axis=(0, 2)), rim_u.max(axis=(0, 2))
    lo_v, hi_v = rim_v.min(axis=(0, 2)), rim_v.max(axis=(0, 2))
    # a convex rim between two rim points Δφ apart bulges at most ρ(1 − cos(Δφ/2)) beyond their chord
    size = np.maximum(hi_u - lo_u, hi_v - lo_v)
    margin = size * (1.0 - np.cos(np.pi / directions)) + 1e-6
    cu, cv = 0.5 * (lo_u + hi_u), 0.5 * (lo_v + hi_v)
    au, av = np.maximum(0.5 * (hi_u - lo_u), 1e-12), np.maximum(0.5 * (hi_v - lo_v), 1e-12)
    e = ((rim_u - cu[:, None]) / au[:, None]) ** 2 + ((rim_v - cv[:, None]) / av[:, None]) ** 2
    grow = np.sqrt(np.maximum(e.max(axis=(0, 2)), 1.0)) * (1.0 + 1e-9)
    eu, ev = grow * au + margin, grow * av + margin
    elliptical = 0.25 * np.pi * eu * ev < (au + margin) * (av + margin)
    half_u, half_v = np.where(elliptical, eu, au + margin), np.where(elliptical, ev, av + margin)
    return np.stack([cu - half_u, cu + half_u, cv - half_v, cv + half_v], axis=-1), elliptical
