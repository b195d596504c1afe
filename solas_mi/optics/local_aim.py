"""Chief rays of the lens as built, aimed in two dimensions with the NumPy tracer (`local_trace`): for each field
(x, y degrees, the direction of the incoming collimated rays in the lens's field type, `fields`), the ray of
that direction that crosses the stop surface at its centre (in the stop's own frame, so a decentred or tilted
stop is aimed at where it is), found by Newton's method on its start point with a finite-difference Jacobian
(2×2 per field, all fields at once), each step halved until its ray passes every surface up to the stop
(apertures aside) and crosses the stop nearer its centre, from the axis out to the field in steps halved where
an aim does not converge; the aimed rays are then traced through the whole lens. No symmetry is assumed: x and y
are aimed together. Objects at infinity only (a finite object is refused by name). Found on the shipped fisheye
out to 80°, as the Dr.Jit tracer's aim (`aiming`). Lengths in mm, wavelengths in nm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from . import local_trace
from .lens import Lens
from .placement import frames

STEPS = 30  # Newton steps at most
TOL_MM = 1e-12  # the stop crossing's distance from the stop centre at which a field's aim has converged
STEP_MM = 1e-6  # the finite-difference step of the Jacobian
HALVINGS = 20  # halvings of a Newton step at most
CONTINUATION = 8  # steps from the axis out to a field, each halved where its aim does not converge
MIN_FRACTION = 2.0**-12  # the smallest step (of the field) before a field is given up
MAX_TRIES = 200  # continuation steps, taken and halved, at most


@dataclass
class Chief:
    """Chief rays of a batch of fields: their start points (n, 3) and unit directions (n, 3) in the global
    frame, where they meet the image plane in its own frame (n, 2), and whether each was found (aimed to
    `TOL_MM`, not clipped)."""

    start: np.ndarray
    direction: np.ndarray
    image_xy: np.ndarray
    found: np.ndarray


def chief_rays(lens: Lens, field_deg, wavelength_nm: float) -> Chief:
    """The chief ray of each of `field_deg` ((n, 2) degrees) at `wavelength_nm`, aimed at the stop's centre:
    from the axis out to the field in `CONTINUATION` steps (each aim starting from the last, a step halved
    where its aim does not converge), so that a wide field's pupil, far from the paraxial one and moving fast
    (a fisheye's), is followed rather than guessed."""
    if not lens.at_infinity:
        raise SolasError(
            f"lens {lens.name}: chief rays of the lens as built are aimed for an object at infinity "
            f"only; its object lies {lens.object_distance:g} mm away"
        )
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(-1, 2)
    placed = frames(lens.surfaces, lens.image_placement)
    reach = max(s.semi_diameter for s in lens.surfaces)
    z0 = min(0.0, min(float(o[2]) for o, _ in placed[:-1])) - (2.0 * reach + 10.0)
    start = np.repeat(placed[lens.stop_index][0][None, :2], len(field_deg), axis=0)  # on axis: to the stop's vertex
    done, step = np.zeros(len(field_deg)), np.full(len(field_deg), 1.0 / CONTINUATION)
    for _ in range(MAX_TRIES):
        going = (done < 1.0) & (step >= MIN_FRACTION)
        if not going.any():
            break
        trial = np.where(going, np.minimum(done + step, 1.0), done)
        aimed, converged = _aim(lens, start, _directions(lens, field_deg * trial[:, None]), z0, wavelength_nm)
        taken = going & converged  # a step whose aim does not converge is halved (the pupil moved too far)
        done, start = np.where(taken, trial, done), np.where(taken[:, None], aimed, start)
        step = np.where(going & ~converged, 0.5 * step, step)
    d = _directions(lens, field_deg * done[:, None])
    points = np.concatenate([start, np.full((len(start), 1), z0)], axis=1)
    out = local_trace.trace(lens, local_trace.bundle(points, d), wavelength_nm)
    found = out.ok & (np.hypot(out.stop_x, out.stop_y) < TOL_MM) & (done == 1.0)
    return Chief(points, d, np.stack([out.image_x, out.image_y], axis=1), found)


def _directions(lens: Lens, field_deg: np.ndarray) -> np.ndarray:
    """(n, 3) unit directions of the collimated rays of `field_deg` in the lens's field type."""
    incoming = lens.field_type.incoming(field_deg)
    d = incoming if incoming.shape[1] == 3 else np.concatenate([incoming, np.ones((len(incoming), 1))], axis=1)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _aim(lens: Lens, start: np.ndarray, d: np.ndarray, z0: float, wavelength_nm: float):
    """Start points (n, 2), and whether each converged, on the plane z = z0 whose rays along `d` cross the stop at its centre: Newton's
    method from `start`, each step halved (down to `HALVINGS` times) until its ray passes the lens and crosses
    the stop nearer its centre. A full step can leap from a smooth branch of the crossing onto a ray that
    misses a surface, whose crossing is no function of the start point (the fisheye at 45°: Newton's method
    then circled without converging)."""
    miss = _stop_crossing(lens, start, d, z0, wavelength_nm)
    for _ in range(STEPS):
        distance = np.hypot(*miss.T)
        if np.all(distance < TOL_MM):
            break
        jac = np.stack(
            [(_stop_crossing(lens, start + STEP_MM * e, d, z0, wavelength_nm) - miss) / STEP_MM for e in np.eye(2)],
            axis=2,
        )  # (n, 2 crossings, 2 start coordinates)
        step = np.linalg.solve(jac, miss[:, :, None])[:, :, 0]
        step = np.where(np.isfinite(step) & (distance >= TOL_MM)[:, None], step, 0.0)
        start, miss = _damped(lens, start, step, miss, d, z0, wavelength_nm)
    return start, np.hypot(*miss.T) < TOL_MM


def _damped(lens: Lens, start, step, miss, d, z0: float, wavelength_nm: float) -> tuple[np.ndarray, np.ndarray]:
    """Each field's start point moved by its `step`, halved until the moved ray passes and crosses the stop
    nearer its centre than `miss` (any passing ray, where the present one does not pass); a field whose every
    halving fails stays where it is. The new start points and their crossings."""
    distance = np.where(np.isfinite(miss).all(axis=1), np.hypot(*miss.T), np.inf)
    todo = np.any(step != 0.0, axis=1)
    for _ in range(HALVINGS + 1):
        trial = _stop_crossing(lens, start - step, d, z0, wavelength_nm)
        better = todo & np.isfinite(trial).all(axis=1) & (np.hypot(*trial.T) < distance)
        start, miss = np.where(better[:, None], start - step, start), np.where(better[:, None], trial, miss)
        todo &= ~better
        if not todo.any():
            break
        step = step * 0.5
    return start, miss


def _stop_crossing(lens: Lens, start: np.ndarray, d: np.ndarray, z0: float, wavelength_nm: float) -> np.ndarray:
    """(n, 2): where rays from (start, z0) along `d` cross the stop surface, in its frame (NaN: a ray that misses
    a surface up to the stop or is totally reflected there; apertures are not applied; the surfaces after the stop
    are not traced: `chief_rays` checks the aimed rays through them)."""
    points = np.concatenate([start, np.full((len(start), 1), z0)], axis=1)
    out = local_trace.trace(lens, local_trace.bundle(points, d), wavelength_nm, apertures=False, last=lens.stop_index)
    return np.where(out.ok[:, None], np.stack([out.stop_x, out.stop_y], axis=1), np.nan)


__all__ = ["Chief", "chief_rays"]
