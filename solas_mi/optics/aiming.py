"""Real-ray aiming: bundles of rays per field and wavelength, Newton iteration of their entrance
coordinates onto a target (a stop point, a point of the reference sphere), and where the chief ray's
aim starts: the paraxial guess, or a continuation outward from the axis that follows the entrance
pupil of wide lenses as it moves and tilts, or, where no ray reaches the stop centre, the passing ray
nearest it. Lengths in mm, fields in degrees, wavelengths in nm.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from . import tracer
from .lens import Lens
from .newton import TOL as _TOL
from .newton import solve
from .paraxial import paraxial, pupil_distance

dr = tracer.dr
POLAR_STEP_DEG = 2.0  # largest step of the field when continuing a chief-ray aim outward
_MIN_STEP_DEG = 1e-3  # a continuation step that keeps losing its ray is halved down to this


class Bundle:
    """`per_field` rays for each of a batch of fields (degrees, (n, 2)) and wavelengths (nm, (n,))."""

    def __init__(self, lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, per_field: int):
        self.lens = lens
        self.bundle_fields, self.bundle_wavelengths = field_deg, np.broadcast_to(wavelength_nm, (len(field_deg),))
        self.n_fields = len(field_deg)
        self.per_field = per_field
        self.index = dr.arange(tracer.UInt32, self.n_fields * per_field) // per_field
        # per field: field tangents (x, y), or the unit direction (x, y, z) of polar fields
        self._incoming = lens.field_type.incoming(field_deg)
        self._object_points = tracer.object_points(lens, field_deg)
        # what a converged aim can reach: rays launched from a far object carry its coordinates'
        # rounding (≈ 1e-17 of the distance, measured: 4e-8 mm at 1e12 mm) into every crossing
        self.tolerance = 1e3 * _TOL + (0.0 if lens.at_infinity else 1e-17 * abs(lens.object_distance))

    def per_ray(self, values: np.ndarray, rays: tracer.UInt32 | None = None) -> tracer.F:
        """Per-field values spread over the bundle's rays (or the rays `rays`, a UInt32 index)."""
        return tracer.gather(values, self.index if rays is None else rays // self.per_field)

    def launch(self, ex: tracer.F, ey: tracer.F, rays: tracer.UInt32 | None = None) -> tracer.Rays:
        """The bundle's rays (or the rays `rays`) at entrance coordinates (ex, ey), in the lens's field type."""
        incoming = [self.per_ray(self._incoming[:, i], rays) for i in range(self._incoming.shape[1])]
        if self.lens.field_type.sideways:  # directions up to and beyond 90°, object at infinity
            return tracer.launch_direction(self.lens, *incoming, ex, ey)
        pts = self._object_points
        return tracer.launch(
            self.lens,
            *incoming,
            ex,
            ey,
            None if pts is None else (self.per_ray(pts[:, 0], rays), self.per_ray(pts[:, 1], rays)),
        )

    def trace(
        self, ex: tracer.F, ey: tracer.F, heights: list | None = None, rays: tracer.UInt32 | None = None
    ) -> tracer.Traced:
        """The rays (or the rays `rays`) of entrance coordinates (ex, ey) traced; `heights`: see `tracer.trace`."""
        wavelength_um = self.per_ray(np.asarray(self.bundle_wavelengths) / 1000.0, rays)
        return tracer.trace(self.lens, self.launch(ex, ey, rays), wavelength_um, heights=heights)


def aim(
    bundle: Bundle,
    target,
    ex: tracer.F,
    ey: tracer.F,
    goal_x: tracer.F,
    goal_y: tracer.F,
    max_iter: int = 60,
    jacobian=None,
):
    """Newton iteration on entrance coordinates so that target(traced) → (goal_x, goal_y) (`newton`).

    `target(traced, rays=None)` returns (gx, gy, ok) of the rays traced. The Jacobian (j11, j12, j21, j22) =
    ∂(gx, gy)/∂(ex, ey) is `jacobian` where given (e.g. from neighbouring solutions), else taken by finite
    differences; it is reused (chord method), and taken again for a ray whose residual stops falling; a
    step that would leave the rays that pass (into total internal reflection, past a surface's edge) is
    halved; a ray's iteration ends when its residual is below the tolerance or has not fallen for a few
    steps, or after `max_iter`. A ray counts as converged when its residual is within the precision the
    launch allows (`Bundle.tolerance`). Returns (ex, ey, traced at the solution, converged mask)."""
    return aim_keeping(bundle, target, ex, ey, goal_x, goal_y, max_iter, jacobian)[:4]


def aim_keeping(
    bundle: Bundle,
    target,
    ex: tracer.F,
    ey: tracer.F,
    goal_x: tracer.F,
    goal_y: tracer.F,
    max_iter: int = 60,
    jacobian=None,
    keep=None,
    unknown: tracer.UInt32 | None = None,
):
    """`aim`, and also `keep(traced, rays=None)` (a tuple of arrays of the rays traced) evaluated with each
    step's trace, so that what the caller needs of the rays at the solution costs no trace of its own;
    `unknown`: the rays whose given `jacobian` is not known, taken by finite differences. Returns (ex, ey,
    traced, converged, kept)."""
    ex, ey, rx, ry, ok, kept = solve(bundle, target, ex, ey, goal_x, goal_y, max_iter, jacobian, keep, unknown)
    converged = ok & (dr.maximum(dr.abs(rx), dr.abs(ry)) < bundle.tolerance)
    return ex, ey, bundle.trace(ex, ey), converged, kept


def stop_target(tr: tracer.Traced, rays=None):
    return tr.stop_x, tr.stop_y, tr.ok


def continued_aim(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Entrance coordinates (n, 2) of the real chief rays found by continuation, and the fraction of each
    field that the continuation reached (1: the whole field; the coordinates are those of that fraction):
    each field grows from 0 (the axis, whose chief ray is e = 0) toward its value in steps of at most
    POLAR_STEP_DEG, each aim starting from the last solution, so the aim follows the entrance pupil as it
    moves and tilts (no paraxial guess). A step that loses the ray is halved, down to _MIN_STEP_DEG,
    so the aim follows a pupil that turns fast near the edge of what the lens images."""
    size = np.maximum(np.hypot(field_deg[:, 0], field_deg[:, 1]), 1e-300)
    done = np.zeros(len(field_deg))  # fraction of each field reached
    step = np.minimum(POLAR_STEP_DEG / size, 1.0)
    e = np.zeros((len(field_deg), 2))
    while True:
        active = (done < 1.0) & (step * size >= _MIN_STEP_DEG)
        if not active.any():
            return e, done
        nxt = np.minimum(done + step, 1.0)[active]
        b = Bundle(lens, field_deg[active] * nxt[:, None], wavelength_nm[active], 1)
        zero = dr.zeros(tracer.F, int(active.sum()))
        ex, ey, _, conv = aim(b, stop_target, tracer.array(e[active, 0]), tracer.array(e[active, 1]), zero, zero)
        ex, ey, conv = tracer.to_numpy(ex, ey, conv)
        idx = np.flatnonzero(active)
        e[idx[conv]] = np.stack([ex, ey], axis=-1)[conv]
        done[idx[conv]] = nxt[conv]
        step[idx[conv]] = np.minimum(2.0 * step[idx[conv]], POLAR_STEP_DEG / size[idx[conv]])
        step[idx[~conv]] *= 0.5


def _paraxial_aim(lens: Lens, field_deg: np.ndarray) -> np.ndarray:
    """Entrance coordinates (n, 2) of the paraxial chief ray (through the entrance-pupil centre)."""
    ep_z = paraxial(lens).entrance_pupil_z_mm
    tan = tracer.field_tangents(field_deg)
    if lens.at_infinity:
        # the ray through the pupil centre, in launch-plane coordinates: project (0, 0, ep_z − z0)
        _, (_, _, e1z), (_, _, e2z) = tracer.beam_basis(tan[:, 0], tan[:, 1], np.sqrt)
        span = ep_z - tracer.launch_plane_z(lens)
        return np.stack([span * e1z, span * e2z], axis=-1)
    pts = tracer.object_points(lens, field_deg)
    return pts * (1.0 - lens.object_distance / pupil_distance(lens, ep_z))


def chief_aim(lens: Lens, b: Bundle) -> tuple[np.ndarray, np.ndarray, tuple | None]:
    """Where to start the chief rays' aim (entrance coordinates, (n, 2)) and the stop point to aim at.
    The stop centre, from the paraxial guess; where that loses the ray (wide fields, also of a lens that
    states a small field), by continuation outward from the axis (`continued_aim`); where no ray reaches
    the stop centre, the passing ray nearest it (`nearest_passing`): light of that field still arrives.
    Also the aim from the paraxial guess (`aim`'s answer) where it reached every field: that aim itself."""
    fields, waves = b.bundle_fields, b.bundle_wavelengths
    goal = np.zeros((b.n_fields, 2))
    if lens.field_type.sideways:
        e0, reached = continued_aim(lens, fields, waves)
        lost = reached < 1.0
    else:
        e0 = _paraxial_aim(lens, fields)
        zero = dr.zeros(tracer.F, b.n_fields)
        paraxial_aim = aim(b, stop_target, tracer.array(e0[:, 0]), tracer.array(e0[:, 1]), zero, zero)
        lost = ~tracer.to_numpy(paraxial_aim[3])[0]
        if not lost.any():
            return e0, goal, paraxial_aim
        e0[lost], reached = continued_aim(lens, fields[lost], waves[lost])
        lost[np.flatnonzero(lost)[reached >= 1.0]] = False
    for f in np.flatnonzero(lost):
        found = nearest_passing(lens, fields[f], waves[f])
        if found is not None:
            e0[f], goal[f] = found
    return e0, goal, None


def nearest_passing(lens: Lens, field_deg: np.ndarray, wavelength_nm: float, samples: int = 129):
    """Of a grid of rays of one field over every entrance point that can meet the lens, the one that passes
    the stop (and every aperture before it) nearest the stop centre: (its entrance coordinates, its stop
    crossing), or None when no ray of the field passes the stop."""
    span = -tracer.launch_plane_z(lens) if lens.at_infinity else 2.0 * max(s.semi_diameter for s in lens.surfaces)
    g = np.linspace(-span, span, samples)
    ex, ey = (a.ravel() for a in np.meshgrid(g, g))
    b = Bundle(lens, np.tile(field_deg, (len(ex), 1)), np.full(len(ex), wavelength_nm), 1)
    tr = b.trace(tracer.array(ex), tracer.array(ey))
    ok, clipped, sx, sy = tracer.to_numpy(tr.ok, tr.clipped_by, tr.stop_x, tr.stop_y)
    passed = ok & ((clipped == 0) | (clipped > lens.stop_index + 1))
    if not passed.any():
        return None
    k = np.flatnonzero(passed)[np.argmin(np.hypot(sx, sy)[passed])]
    return (ex[k], ey[k]), (sx[k], sy[k])


class _FilmBundle:
    """Rays of the reversed lens (`exit_pupil.reversed_lens`) from film points (x, y) mm, one per point,
    for `aim`: their entrance coordinates are points on the last surface's vertex plane."""

    def __init__(self, rev: Lens, x: np.ndarray, y: np.ndarray, wavelength_nm: float):
        self.lens, self.x, self.y = rev, tracer.array(x), tracer.array(y)
        self.wavelength_um = tracer.array(np.full(len(x), wavelength_nm * 1e-3))
        self.tolerance = 1e3 * _TOL

    def trace(
        self, ex: tracer.F, ey: tracer.F, heights: list | None = None, rays: tracer.UInt32 | None = None
    ) -> tracer.Traced:
        zero = 0.0 * ex
        x, y, wavelength = (
            v if rays is None else dr.gather(tracer.F, v, rays) for v in (self.x, self.y, self.wavelength_um)
        )
        return tracer.trace(
            self.lens, tracer.launch(self.lens, zero, zero, ex, ey, (x, y)), wavelength, heights=heights
        )


def film_chief_aim(rev: Lens, x: np.ndarray, y: np.ndarray, wavelength_nm: float) -> tuple[np.ndarray, ...]:
    """The chief rays of film points (x, y) mm, traced backward: for each, the point (ex, ey) on the last
    surface's vertex plane that the ray from the film point aims at so that it crosses the stop centre
    (`rev`: the reversed lens), and whether it was found (the ray passes and meets the centre within
    1e-10 mm). The aim starts at the paraxial exit pupil's centre: the paraxial chief ray. (The pupil is
    found with the reversed lens's object at infinity: it does not depend on the object, and a film in the
    reversed lens's front focal plane, a lens focused at infinity onto its paraxial focus, has no paraxial
    image to find it from.)"""
    ep_z, od = paraxial(replace(rev, object_distance=math.inf)).entrance_pupil_z_mm, rev.object_distance
    shrink = 1.0 - od / (ep_z + od)
    b = _FilmBundle(rev, x, y, wavelength_nm)
    zero = dr.zeros(tracer.F, len(x))
    ex, ey, tr, converged = aim(b, stop_target, tracer.array(x * shrink), tracer.array(y * shrink), zero, zero)
    ex, ey, converged, clipped = tracer.to_numpy(ex, ey, converged, tr.clipped_by)
    return ex, ey, converged & (clipped == 0)
