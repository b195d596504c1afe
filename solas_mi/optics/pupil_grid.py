"""The rays and cells of the pupil function's (α, β) grid (`pupil.pupil_functions`), in Dr.Jit.

Rays, coarse to fine: each field's grid is first solved on a few nodes per side (aimed from the stop
rim's affine map, Jacobians by finite differences), then on grids of about four times as many nodes per
side, each node's first guess and Newton Jacobian interpolated from the coarser solution by cubic
Lagrange polynomials. Measured on the doublet's 128² grids: 2 traces per ray at the finest level, where
a start from the affine map took 6 to 9 (every node converges to the same tolerance, so the rays agree
with a direct aim to 1e-11 mm).

Cells: power (entrance power density × |∂e/∂(α, β)|, derivatives by central differences across the grid,
one-sided at its edges, as `numpy.gradient` takes them), the fraction of each cell inside the stop's
edge, the optical path difference, the largest phase step between neighbouring cells, and the complex
pupil √power × coverage × e^{iφ} in complex64 — each one kernel over every cell of the batch, with no
NumPy pass over the cells. Lengths in mm.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np

from ..blas import single_threaded_blas
from . import tracer
from .aiming import Bundle, aim_keeping
from .lens import Lens

dr = tracer.dr
LEVEL_STEP = 4  # a coarser level has about a quarter of the nodes per side ...
COARSEST = 17  # ... down to at most this many, aimed from the rim's affine map


def grid_axes(rim, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Per field the α and β grids (n, N) relative to the chief ray that hold the stop rim's image on the
    reference sphere (`pupil._sphere_rim`), one cell and 1 % to spare."""
    _, _, ra, rb, rok = rim
    axes = []
    for rel in (ra, rb):
        lo, hi = np.where(rok, rel, np.inf).min(axis=1), np.where(rok, rel, -np.inf).max(axis=1)
        half = 0.5 * (hi - lo) * (1.0 + 2.0 / samples) * 1.01
        mid = 0.5 * (hi + lo)
        axes.append(mid[:, None] + half[:, None] * np.linspace(-1.0, 1.0, samples))
    return axes[0], axes[1]


def affine_map(rim) -> np.ndarray:
    """Per field the least-squares affine map (n, 3, 2) from (1, α, β) to entrance coordinates of the rim
    rays that passed: the coarsest level's first guess."""
    rex, rey, ra, rb, rok = rim
    w = rok.astype(np.float64)
    design = np.stack([np.ones_like(ra), ra, rb], axis=-1) * w[..., None]  # (n, RIM_RAYS, 3)
    normal = np.einsum("nri,nrj->nij", design, design)
    right = np.einsum("nri,nrc->nic", design, np.stack([rex, rey], axis=-1))
    return np.linalg.solve(normal, right)


def aim_levels(samples: int) -> list[int]:
    """Nodes per side of each level, coarsest first, ending with `samples`."""
    sizes = [samples]
    while sizes[0] > COARSEST:
        sizes.insert(0, (sizes[0] - 1) // LEVEL_STEP + 1)
    return sizes


def lagrange(fine: int, coarse: int, t: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Weights (fine, coarse) of cubic Lagrange interpolation from `coarse` evenly spaced nodes to `fine`
    ones spanning the same interval, or at the positions `t` (in coarse spacings from the first node, a
    little beyond the ends allowed) (each from the four nodes around it, one-sided at the ends), and
    of its derivative per coarse spacing."""
    t = np.arange(fine) * ((coarse - 1) / max(fine - 1, 1)) if t is None else t
    start = np.clip(np.floor(t).astype(int) - 1, 0, coarse - 4)
    nodes = start[:, None] + np.arange(4)  # (fine, 4)
    x = t[:, None] - nodes  # distances to the four nodes
    value, slope = np.zeros((fine, coarse)), np.zeros((fine, coarse))
    rows = np.arange(fine)
    for a in range(4):
        others = [b for b in range(4) if b != a]
        denom = np.prod([a - b for b in others])
        value[rows, nodes[:, a]] = np.prod([x[:, b] for b in others], axis=0) / denom
        slope[rows, nodes[:, a]] = sum(np.prod([x[:, b] for b in others if b != c], axis=0) for c in others) / denom
    return value, slope


def sphere_target(lens: Lens, b: Bundle, chief):
    """The aim target of `b`'s rays: direction cosines (α, β) of their point on each field's reference
    sphere (`pupil.ChiefRays`), seen from the chief ray's image point."""
    cx, cy = b.per_ray(chief.image_xy[:, 0]), b.per_ray(chief.image_xy[:, 1])
    radius = b.per_ray(chief.sphere_radius)
    cz = lens.image_z

    def target(tr: tracer.Traced, rays=None):
        sx, sy, r = (v if rays is None else dr.gather(tracer.F, v, rays) for v in (cx, cy, radius))
        x, y, _z, _opl, hit = tracer.to_sphere(tr, sx, sy, cz, r)
        return (x - sx) / r, (y - sy) / r, tr.ok & hit

    return target


def grid_rays(
    lens: Lens,
    field_deg: np.ndarray,
    wavelength_nm: np.ndarray,
    chief,
    alpha: np.ndarray,
    beta: np.ndarray,
    affine: np.ndarray,
    start: tuple | None = None,
):
    """Every node of the (α, β) grids aimed at its point of the reference sphere, coarse to fine
    (`aim_levels`), or in one level from `start`, the same pupils solved on another grid (the error
    estimate's coarser grid from the PSF's own, `pupil.Pupils.sampled`): the finest level's bundle, its
    rays' entrance coordinates, whether each converged, and what `_kept` keeps of them at the solution
    (Dr.Jit arrays, [field, β, α] order); and that solution as a `start` (NumPy entrance coordinates and
    convergence (n, N, N), and the grids α, β)."""
    nf, samples = alpha.shape
    levels = aim_levels(samples) if start is None else [samples]
    solved = start
    for m in levels:
        a, b = (
            axis if m == samples else axis[:, :1] + (axis[:, -1:] - axis[:, :1]) * np.linspace(0.0, 1.0, m)
            for axis in (alpha, beta)
        )
        guess = [
            np.add(
                affine[:, 0, c, None, None] + affine[:, 1, c, None, None] * a[:, None, :],
                affine[:, 2, c, None, None] * b[:, :, None],
                out=tracer.aligned((nf, m, m), np.float64),
            )
            for c in (0, 1)
        ]  # the rim's affine map
        # from another grid (`grid_axes` scales α and β alike): its nodes' positions in the solved grid's
        # spacings, the same for every field
        at = None if start is None else (a[0] - start[1][0, 0]) * ((start[1].shape[1] - 1) / np.ptp(start[1][0]))
        jacobian, unknown = (None, None) if solved is None else _next_level(*solved, m, guess, at)
        g = Bundle(lens, field_deg, wavelength_nm, m * m)
        ray = dr.arange(tracer.UInt32, nf * m * m)  # the goals: each ray's (α, β) on the sphere, gathered per ray
        goal_a = tracer.gather((a + chief.sphere_point[:, :1]).ravel(), g.index * m + ray % m)
        goal_b = tracer.gather((b + chief.sphere_point[:, 1:]).ravel(), g.index * m + (ray // m) % m)
        keep = _kept(lens, g, chief) if m == samples else None
        ex, ey, _traced, ok, kept = aim_keeping(
            g,
            sphere_target(lens, g, chief),
            tracer.array(guess[0]),
            tracer.array(guess[1]),
            goal_a,
            goal_b,
            jacobian=jacobian,
            keep=keep,
            unknown=unknown,
        )
        solved = [s.reshape(nf, m, m) for s in tracer.to_numpy(ex, ey, ok)], a, b
    return g, ex, ey, ok, kept, solved


def _kept(lens: Lens, g: Bundle, chief):
    """What `cells` needs of the finest level's rays: a function of the traced rays giving their optical
    path difference on the reference sphere, whether they met it, the surface that clipped them and their
    stop crossing."""
    cx, cy = g.per_ray(chief.image_xy[:, 0]), g.per_ray(chief.image_xy[:, 1])
    radius, opl0 = g.per_ray(chief.sphere_radius), g.per_ray(chief.opl)

    def keep(tr: tracer.Traced, rays=None):
        sx, sy, r, o = (v if rays is None else dr.gather(tracer.F, v, rays) for v in (cx, cy, radius, opl0))
        _, _, _, opl, hit = tracer.to_sphere(tr, sx, sy, lens.image_z, r)
        return opl - o, hit, tr.clipped_by, tr.stop_x, tr.stop_y

    return keep


def _next_level(
    solved: list[np.ndarray], a: np.ndarray, b: np.ndarray, m: int, guess: list[np.ndarray], at: np.ndarray | None
):
    """Interpolate a level's solution (`solved`: entrance coordinates and whether each converged, on the
    grids `a`, `b`) by cubic Lagrange polynomials onto the next level, m nodes per side (spanning the same
    interval, or at the positions `at` in spacings of `a` and `b` alike): its first guess
    (written into `guess`, two (n, m, m) arrays) and Newton Jacobian ∂(α, β)/∂(ex, ey) (four Dr.Jit arrays),
    and the nodes whose interpolation reaches a ray that did not converge (a UInt32 index, or None): they
    keep their guess (the rim's affine map), their Jacobian taken by finite differences."""
    (sx, sy, ok), nf, mc = solved, a.shape[0], a.shape[1]
    w, dw = lagrange(m, mc, at)
    both = np.concatenate([w, dw]).T  # (mc, 2m): values and slopes along α
    slopes = []
    w32, dw32 = w.astype(np.float32), dw.astype(np.float32)
    with single_threaded_blas():  # many small products; the slopes in float32, enough for a Newton step
        reach = None if ok.all() else np.abs(w) @ (~ok).astype(np.float64) @ np.abs(w).T > 0  # from a lost ray
        for s, into in zip((sx, sy), guess):
            right = np.matmul(s, both)  # (n, mc, 2m)
            if reach is None:
                np.matmul(w, right[..., :m], out=into)
            else:
                np.copyto(into, np.matmul(w, right[..., :m]), where=~reach)
            right32 = right.astype(np.float32)
            slopes += [
                np.matmul(weights, right32[..., part], out=tracer.aligned((nf, m, m), np.float32))
                for weights, part in ((w32, slice(m, None)), (dw32, slice(None, m)))
            ]  # per coarse step in α, β
    unknown = None if reach is None else tracer.array(np.flatnonzero(reach), tracer.UInt32)
    index = dr.arange(tracer.UInt32, nf * m * m) // (m * m)
    per_a, per_b = (tracer.gather((mc - 1) / (x[:, -1] - x[:, 0]), index) for x in (a, b))
    f32 = dr.float32_array_t(tracer.F)
    ex_a, ex_b, ey_a, ey_b = (
        tracer.F(tracer.array(v, f32)) * per for v, per in zip(slopes, (per_a, per_b, per_a, per_b))
    )
    det = ex_a * ey_b - ex_b * ey_a
    return (ey_b / det, -ex_b / det, -ey_a / det, ex_a / det), unknown


def cells(
    lens: Lens,
    g: Bundle,
    ex: tracer.F,
    ey: tracer.F,
    ok: tracer.Bool,
    kept: tuple,
    alpha: np.ndarray,
    beta: np.ndarray,
    power_density,
) -> dict:
    """What each cell of the grids carries, from the rays of `grid_rays` (`kept`: their `_kept` values):
    NumPy arrays (n, N, N) power (per dα dβ, a fraction of the on-axis entrance-pupil power), coverage,
    opd_mm and the complex pupil (complex64); per field phase_step (rad, the largest between neighbouring
    cells inside the pupil) and vignetted_by (1-based surfaces that block part of the pupil).
    `power_density(ex, ey)` is the entrance power per mm² of the bundle's rays (`pupil.entrance_power`)."""
    nf, n = alpha.shape
    idx = dr.arange(tracer.UInt32, nf * n * n)
    power, coverage, opd, blocked = _weights(lens, g, ex, ey, ok, kept, alpha, beta, power_density, idx)
    phase = g.per_ray(2.0 * math.pi / (g.bundle_wavelengths * 1e-6)) * opd
    inside, step = coverage > 0, dr.zeros(tracer.F, nf * n * n)
    for along, stride in ((idx % n, 1), ((idx // n) % n, n)):
        nxt = dr.minimum(idx + stride, nf * n * n - 1)
        both = (along < n - 1) & inside & (dr.gather(tracer.F, coverage, nxt) > 0)
        step = dr.maximum(step, dr.select(both, dr.abs(dr.gather(tracer.F, phase, nxt) - phase), 0.0))
    amplitude = dr.sqrt(power) * coverage
    sin, cos = dr.sincos(phase)
    f32 = dr.float32_array_t(tracer.F)
    real, imag = f32(amplitude * cos), f32(amplitude * sin)
    steps = dr.block_reduce(dr.ReduceOp.Max, step, n * n)
    surfaces = len(lens.surfaces) + 1  # per field, the surfaces that block rays reaching the stop's opening
    seen = dr.zeros(tracer.UInt32, nf * surfaces)
    dr.scatter(seen, 1, g.index * surfaces + blocked, blocked != 0)
    dr.eval(real, imag, steps, seen)
    shape = (nf, n, n)
    pupil = np.empty(shape, dtype=np.complex64)
    pupil.real, pupil.imag = np.asarray(real).reshape(shape), np.asarray(imag).reshape(shape)
    return {
        "power": np.asarray(power).reshape(shape),
        "coverage": np.asarray(coverage).reshape(shape),
        "opd_mm": np.asarray(opd).reshape(shape),
        "complex_pupil": pupil,
        "phase_step": np.asarray(steps),
        "vignetted_by": [np.flatnonzero(row).tolist() for row in np.asarray(seen).reshape(nf, surfaces)],
    }


def _weights(
    lens: Lens,
    g: Bundle,
    ex: tracer.F,
    ey: tracer.F,
    ok: tracer.Bool,
    kept: tuple,
    alpha: np.ndarray,
    beta: np.ndarray,
    power_density,
    idx: tracer.UInt32,
):
    """Per cell (`cells`): power, coverage, optical path difference (0 outside the pupil) and the surface
    that blocks a ray reaching the stop's opening (0: none); evaluated."""
    n = alpha.shape[1]
    opd, hit, clipped, sx, sy = kept
    ok = ok & hit
    col, row = idx % n, (idx // n) % n

    def gradient(u: tracer.F, along: tracer.UInt32, stride: int) -> tracer.F:
        """∂u per grid step along rows (stride 1) or columns (stride n), as numpy.gradient takes it."""
        ahead, behind = dr.minimum(along + 1, n - 1), dr.select(along > 0, along - 1, 0)
        at = idx - along * stride
        return (dr.gather(tracer.F, u, at + ahead * stride) - dr.gather(tracer.F, u, at + behind * stride)) / tracer.F(
            ahead - behind
        )

    da, db = g.per_ray(alpha[:, 1] - alpha[:, 0]), g.per_ray(beta[:, 1] - beta[:, 0])

    def jacobian(u: tracer.F, w: tracer.F) -> tracer.F:
        """|∂(u, w)/∂(α, β)|."""
        du_da, du_db, dw_da, dw_db = gradient(u, col, 1), gradient(u, row, n), gradient(w, col, 1), gradient(w, row, n)
        return dr.abs(du_da * dw_db - du_db * dw_da) / (da * db)

    power = power_density(ex, ey) * jacobian(ex, ey)
    cell = dr.sqrt(jacobian(sx, sy) * da * db)  # grid cell size at the stop (mm)
    # the stop's rim (an iris: its nearest blade's edge); round, the same operations as r_stop − |s|
    margin = lens.surfaces[lens.stop_index].iris_margin(
        sx, sy, lambda a, b: dr.sqrt(a * a + b * b), dr.atan2, dr.cos, dr.floor, partial(tracer.opaque, ftype=type(sx))
    )
    coverage = dr.clip(0.5 + margin / dr.maximum(cell, 1e-300), 0.0, 1.0)
    other = (clipped != 0) & (clipped != lens.stop_index + 1)
    # a cell beside a lost ray (its stop crossing NaN) has no size at the stop, its coverage NaN: no light
    coverage = dr.select(other | ~ok | ~dr.isfinite(power) | ~dr.isfinite(coverage), 0.0, coverage)
    inside = coverage > 0
    out = dr.select(inside, power, 0.0), coverage, dr.select(inside, opd, 0.0), dr.select(ok & (margin > 0), clipped, 0)
    dr.eval(*out)
    return out
