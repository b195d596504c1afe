"""Chief rays of the lens as built, aimed in two dimensions with the NumPy tracer (`local_trace`): for
each field (x, y degrees, the direction of the incoming collimated rays in the lens's field type,
`fields`), the ray of that
direction that crosses the stop surface at its centre (in the stop's own frame, so a decentred or tilted
stop is aimed at where it is), found by Newton's method on its start point with a finite-difference
Jacobian (2×2 per field, all fields at once). No symmetry is assumed: x and y are aimed together. Objects
at infinity only (a finite object is refused by name). Not found (`Chief.found` false): the shipped
fisheye's fields beyond about 55° (measured: 54° found, 60° not), where the stop crossing of a start point
far from the aim is no smooth function of it and Newton's method wanders (rays that miss a surface are
not told apart yet); the Dr.Jit tracer's aim (`aiming`) finds them. Lengths in mm, wavelengths in nm.
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
CONTINUATION = 8  # steps from the axis out to a field


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
    from the axis out to the field in `CONTINUATION` steps (each aim starting from the last), so that a
    wide field's pupil, far from the paraxial one (a fisheye's), is followed rather than guessed."""
    if not lens.at_infinity:
        raise SolasError(
            f"lens {lens.name}: chief rays of the lens as built are aimed for an object at infinity "
            f"only; its object lies {lens.object_distance:g} mm away"
        )
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(-1, 2)
    placed = frames(lens.surfaces, lens.image_placement)
    reach = max(s.semi_diameter for s in lens.surfaces)
    z0 = min(0.0, min(float(o[2]) for o, _ in placed[:-1])) - (2.0 * reach + 10.0)
    stop = placed[lens.stop_index][0]
    start = None
    for k in range(1, CONTINUATION + 1):
        d = _directions(lens, field_deg * (k / CONTINUATION))
        if start is None:  # on the plane z = z0, on the line through the stop's vertex
            start = stop[None, :2] - d[:, :2] * ((stop[2] - z0) / d[:, 2])[:, None]
        start = _aim(lens, start, d, z0, wavelength_nm)
    points = np.concatenate([start, np.full((len(start), 1), z0)], axis=1)
    out = local_trace.trace(lens, local_trace.bundle(points, d), wavelength_nm)
    found = out.ok & (np.hypot(out.stop_x, out.stop_y) < TOL_MM)
    return Chief(points, d, np.stack([out.image_x, out.image_y], axis=1), found)


def _directions(lens: Lens, field_deg: np.ndarray) -> np.ndarray:
    """(n, 3) unit directions of the collimated rays of `field_deg` in the lens's field type."""
    incoming = lens.field_type.incoming(field_deg)
    d = incoming if incoming.shape[1] == 3 else np.concatenate([incoming, np.ones((len(incoming), 1))], axis=1)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _aim(lens: Lens, start: np.ndarray, d: np.ndarray, z0: float, wavelength_nm: float) -> np.ndarray:
    """Start points (n, 2) on the plane z = z0 whose rays along `d` cross the stop at its centre: Newton's
    method from `start`."""
    for _ in range(STEPS):
        miss = _stop_crossing(lens, start, d, z0, wavelength_nm)
        if np.all(np.hypot(*miss.T) < TOL_MM):
            break
        jac = np.stack(
            [(_stop_crossing(lens, start + STEP_MM * e, d, z0, wavelength_nm) - miss) / STEP_MM for e in np.eye(2)],
            axis=2,
        )  # (n, 2 crossings, 2 start coordinates)
        step = np.linalg.solve(jac, miss[:, :, None])[:, :, 0]
        start = start - np.where(np.isfinite(step), step, 0.0)
    return start


def _stop_crossing(lens: Lens, start: np.ndarray, d: np.ndarray, z0: float, wavelength_nm: float) -> np.ndarray:
    """(n, 2): where rays from (start, z0) along `d` cross the stop surface, in its frame (NaN: not traced)."""
    points = np.concatenate([start, np.full((len(start), 1), z0)], axis=1)
    out = local_trace.trace(lens, local_trace.bundle(points, d), wavelength_nm)
    return np.stack([out.stop_x, out.stop_y], axis=1)


__all__ = ["Chief", "chief_rays"]
