"""Newton iteration of a bundle's entrance coordinates onto a target (`aiming.aim`), each step tracing only
the rays still moving: a ray leaves the iteration when its residual is below TOL or has stopped falling,
and only its own state decides when (its Jacobian refreshed on its own, its step halved on its own), so a
ray's solution does not depend on the other rays of its batch. (Measured on the double Gauss lens, whose
vignetted rims hold a few rays that move for tens of steps: 175 traces of every ray of a 128² grid, where
a step now traces the few that move.)

A bundle is any object with `trace(ex, ey, rays=None)` (the rays `rays`, a UInt32 index, or all, traced
from entrance coordinates given for those rays) and `tolerance`; a target is `target(traced, rays=None)`
→ (gx, gy, ok) for the same rays. Lengths in mm.
"""

from __future__ import annotations

import numpy as np

from . import tracer

dr = tracer.dr
HALVINGS = 6  # a Newton step that loses its ray is halved up to this many times
FD_STEP = 1e-5  # mm, finite-difference step in entrance coordinates
TOL = 1e-13  # convergence of aimed quantities (mm at the stop, direction cosines on the sphere)
STALLS = 4  # steps in a row that do not halve a ray's residual: it is at the floor of what the arithmetic resolves


def at(values, rays):
    """Per-ray `values` of the rays `rays` (None: all)."""
    return values if rays is None else dr.gather(type(values), values, rays)


def put(dense, values, rays):
    """`dense` with the rays `rays` set to `values` (all: `values` itself)."""
    if rays is None:
        return values
    dr.scatter(dense, values, rays)
    return dense


def solve(
    bundle,
    target,
    ex: tracer.F,
    ey: tracer.F,
    goal_x: tracer.F,
    goal_y: tracer.F,
    max_iter: int,
    jacobian,
    keep,
    unknown=None,
):
    """The iteration of `aiming.aim_keeping`: (ex, ey, residual x, residual y, passed, kept)."""

    def residual(ax, ay, rays):
        tr = bundle.trace(ax, ay, rays=rays)
        gx, gy, ok = target(tr, rays)
        return gx - at(goal_x, rays), gy - at(goal_y, rays), ok, tr

    rx, ry, ok, _ = residual(ex, ey, None)
    dr.eval(ex, ey, rx, ry, ok)
    j = list(fd_jacobian(residual, ex, ey, rx, ry, None) if jacobian is None else jacobian)
    if jacobian is not None and unknown is not None:  # where the given Jacobian is not known
        j = _refresh(residual, j, ex, ey, rx, ry, unknown)
    best, stalled = dr.full(tracer.F, np.inf, dr.width(rx)), dr.zeros(tracer.UInt32, dr.width(rx))
    rays, kept = None, None
    for _ in range(max_iter):
        step = _step([at(v, rays) for v in j], at(rx, rays), at(ry, rays))
        good = at(ok, rays) & dr.isfinite(step[0]) & dr.isfinite(step[1])
        new = _trial(residual, keep, at(ex, rays), at(ey, rays), step, good, rays)
        ex, ey, rx, ry, ok = (put(d, v, rays) for d, v in zip((ex, ey, rx, ry, ok), new[:5]))
        kept = new[5] if kept is None else tuple(put(d, v, rays) for d, v in zip(kept, new[5]))
        err = dr.select(new[4], dr.maximum(dr.abs(new[2]), dr.abs(new[3])), 0.0)
        slow = dr.select(err > 0.5 * at(best, rays), at(stalled, rays) + 1, 0)
        lowest = dr.minimum(at(best, rays), err)
        dr.eval(slow, lowest)
        best, stalled = put(best, lowest, rays), put(stalled, slow, rays)
        moving = (err >= TOL) & (slow < STALLS)
        dr.eval(ex, ey, rx, ry, ok, best, stalled, *kept)
        if not dr.any(moving):
            break
        rays = _within(rays, dr.compress(moving))
        stale = at(stalled, rays) == 2  # the chord has stopped working: a fresh Jacobian where those rays are now
        if dr.any(stale):
            j = _refresh(residual, j, ex, ey, rx, ry, _within(rays, dr.compress(stale)))
    return ex, ey, rx, ry, ok, kept


def _within(rays, index: tracer.UInt32) -> tracer.UInt32:
    """The rays at positions `index` of the subset `rays` (None: all)."""
    return index if rays is None else dr.gather(tracer.UInt32, rays, index)


def _step(j, rx, ry):
    j11, j12, j21, j22 = j
    det = j11 * j22 - j12 * j21
    return (j22 * rx - j12 * ry) / det, (-j21 * rx + j11 * ry) / det


def _trial(residual, keep, ex, ey, step, good, rays):
    """Step the rays `rays` (positions ex, ey) by −`step` where `good`; a step that leaves the rays that pass
    (total internal reflection, a missed surface) is halved, for those rays alone, up to HALVINGS times.
    Returns their new (ex, ey, rx, ry, ok, kept)."""
    step_x, step_y = step
    nx, ny = dr.select(good, ex - step_x, ex), dr.select(good, ey - step_y, ey)
    rx, ry, ok, tr = residual(nx, ny, rays)
    out = [nx, ny, rx, ry, ok, *(() if keep is None else keep(tr, rays))]
    lost = good & ~ok
    dr.eval(*out, lost)
    if dr.any(lost):
        index = dr.compress(lost)  # positions (in `rays`) of the lost rays, with their steps and starts
        sx, sy, bx, by = (dr.gather(tracer.F, v, index) for v in (step_x, step_y, ex, ey))
        for _ in range(HALVINGS):
            sx, sy = 0.5 * sx, 0.5 * sy
            sub = _within(rays, index)
            lrx, lry, lok, ltr = residual(bx - sx, by - sy, sub)
            for k, v in enumerate((bx - sx, by - sy, lrx, lry, lok, *(() if keep is None else keep(ltr, sub)))):
                dr.scatter(out[k], v, index)
            dr.eval(*out)
            if dr.all(lok):
                break
            still = dr.compress(~lok)
            index, sx, sy, bx, by = (
                dr.gather(tracer.UInt32, index, still),
                *(dr.gather(tracer.F, v, still) for v in (sx, sy, bx, by)),
            )
    return (*out[:5], tuple(out[5:]))


def fd_jacobian(residual, ex, ey, rx, ry, rays):
    """∂(residual)/∂(ex, ey) of the rays `rays` by forward differences (FD_STEP)."""
    px, py, _, _ = residual(ex + FD_STEP, ey, rays)
    qx, qy, _, _ = residual(ex, ey + FD_STEP, rays)
    j = ((px - rx) / FD_STEP, (qx - rx) / FD_STEP, (py - ry) / FD_STEP, (qy - ry) / FD_STEP)
    dr.eval(*j)
    return j


def _refresh(residual, j, ex, ey, rx, ry, rays):
    """The Jacobians `j` (dense) with those of the rays `rays` taken afresh where they are now."""
    fresh = fd_jacobian(residual, at(ex, rays), at(ey, rays), at(rx, rays), at(ry, rays), rays)
    dr.eval(*j)
    return [put(d, v, rays) for d, v in zip(j, fresh)]
