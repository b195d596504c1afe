"""Geometric PSFs of the lens as built (decentred or tilted surfaces, toroids, a tilted sensor), traced with
the NumPy tracer (`optics.local_trace`) about chief rays aimed in two dimensions (`optics.local_aim`).

For each field (x, y degrees; an object at infinity) the collimated rays start on a regular rays×rays grid
across the beam, in the plane through (0, 0, z0) perpendicular to their direction and the basis of the Dr.Jit
tracer's launch (`tracer.beam_basis`: e1 ⟂ y, e2 = d × e1), centred on the chief ray; each carries the power
of its cell (`pupil.power_densities`: the on-axis entrance pupil carries 1) and lands where the lens as built
puts it on the image plane, in the image plane's own frame (a tilted sensor's), binned about the chief ray's
image point (`geometric.bin_hits`). No symmetry is assumed: every field of a grid is traced, none mirrored.
The grid's half-width is found by a coarse pass over the beam that surface 1's aperture lets through, unless
given. Lengths in mm (offsets and pitches in µm), wavelengths in nm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from ..optics import local_aim, local_trace
from ..optics.lens import Lens
from ..optics.placement import frames
from ..optics.pupil import power_densities
from .geometric import bin_hits

COARSE_RAYS = 48  # rays per side of the pass that finds the beam's half-width
MARGIN = 1.02  # the half-width's margin over the outermost passing ray of that pass (as `geometric`'s)


@dataclass
class Hits:
    """Where one field's rays land on the image plane (x, y mm in its frame), each ray's power (fraction of the
    on-axis entrance pupil's), and the chief ray's image point (mm)."""

    x: np.ndarray
    y: np.ndarray
    power: np.ndarray
    chief_xy: np.ndarray


def basis(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unit vectors (e1, e2) across the beam of unit direction `d` (3,): e1 ⟂ y, e2 = d × e1 (the Dr.Jit
    tracer's `beam_basis`)."""
    inv1 = 1.0 / np.sqrt(d[2] * d[2] + d[0] * d[0])
    e1x, e1z = d[2] * inv1, -d[0] * inv1
    return np.array([e1x, 0.0, e1z]), np.array([d[1] * e1z, d[2] * e1x - d[0] * e1z, -d[1] * e1x])


def field_hits(
    lens: Lens, field_deg, wavelength_nm: float, rays: int, half_mm: float | None = None
) -> tuple[Hits, float]:
    """The `Hits` of a rays×rays grid across the beam of field `field_deg` (x, y degrees) at `wavelength_nm`,
    and the grid's half-width (mm; found by `beam_half_width` unless `half_mm` is given)."""
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(2)
    chief = local_aim.chief_rays(lens, field_deg.reshape(1, 2), wavelength_nm)
    if not chief.found[0]:
        raise SolasError(
            f"lens {lens.name}: no chief ray of the lens as built found at field ({field_deg[0]:g}, {field_deg[1]:g}) "
            f"deg, {wavelength_nm:g} nm (none passes the stop's centre, or its aim does not converge)"
        )
    d = chief.direction[0]
    e1, e2 = basis(d)
    plane = np.array([0.0, 0.0, chief.start[0, 2]])
    centre = np.array([(chief.start[0] - plane) @ e1, (chief.start[0] - plane) @ e2])
    half = beam_half_width(lens, d, plane, (e1, e2), centre, wavelength_nm) if half_mm is None else half_mm
    _, _, out = _trace_grid(lens, d, plane, (e1, e2), centre, half, rays, wavelength_nm)
    area = (2.0 * half / rays) ** 2
    power = np.full(rays * rays, float(power_densities(lens, np.array([wavelength_nm]))[0]) * area)
    ok = out.ok
    return Hits(out.image_x[ok], out.image_y[ok], power[ok], chief.image_xy[0]), half


def beam_half_width(lens: Lens, d, plane, axes, centre, wavelength_nm: float) -> float:
    """Half-width (mm) of a square across the beam, about `centre`, that holds every ray the lens passes: a
    coarse grid over what surface 1's aperture can let through (its semi-diameter and sag's reach about its
    vertex), widened by one of its cells and `MARGIN`."""
    first = frames(lens.surfaces, lens.image_placement)[0][0]
    s = lens.surfaces[0]
    rim = (
        np.array([s.semi_diameter, 0.0, -s.semi_diameter, 0.0]),
        np.array([0.0, s.semi_diameter, 0.0, -s.semi_diameter]),
    )
    reach = np.hypot(s.semi_diameter, np.abs(s.geometry.sag(*rim)).max())  # x and y: a toroid's sags differ
    vertex = np.array([(first - plane) @ axes[0], (first - plane) @ axes[1]])
    outer = float(np.abs(vertex - centre).max() + reach) * MARGIN
    ex, ey, out = _trace_grid(lens, d, plane, axes, centre, outer, COARSE_RAYS, wavelength_nm)
    if not out.ok.any():
        return outer
    spread = max(np.abs(ex[out.ok] - centre[0]).max(), np.abs(ey[out.ok] - centre[1]).max())
    return min(outer, (spread + 2.0 * outer / COARSE_RAYS) * MARGIN)


def _trace_grid(lens: Lens, d, plane, axes, centre, half: float, rays: int, wavelength_nm: float):
    """Entrance coordinates (rays²,) of a rays×rays grid of half-width `half` about `centre` across the beam
    (cell centres, rows up the e2 axis as `geometric.entrance_grid`) and their trace."""
    t = (np.arange(rays) + 0.5) / rays * 2.0 - 1.0
    ex = np.broadcast_to(centre[0] + half * t[None, :], (rays, rays)).ravel()
    ey = np.broadcast_to(centre[1] + half * t[:, None], (rays, rays)).ravel()
    points = plane + ex[:, None] * axes[0] + ey[:, None] * axes[1]
    return ex, ey, local_trace.trace(lens, local_trace.bundle(points, d), wavelength_nm)


def geometric(
    lens: Lens, field_deg, wavelength_nm, pitch_um: float, size: int, rays: int, half_mm=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Geometric PSFs (n, size, size) in 1/µm² of the lens as built at fields `field_deg` (n, 2) and
    `wavelength_nm` (n,, or one), each binned about its chief ray's image point on the image plane (in that
    plane's frame); also those points (n, 2) mm and the transmitted power (n,). Every field is traced
    (a grid over the whole field: no half of it mirrored). `half_mm` (n,): each grid's half-width, else found."""
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(-1, 2)
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),))
    halves = [None] * len(field_deg) if half_mm is None else np.broadcast_to(half_mm, (len(field_deg),))
    found = [field_hits(lens, f, float(w), rays, h)[0] for f, w, h in zip(field_deg, wavelength_nm, halves)]
    offsets = [((h.x - h.chief_xy[0]) * 1e3, (h.y - h.chief_xy[1]) * 1e3, h.power) for h in found]
    data, transmission = bin_hits(offsets, pitch_um, size)
    return data, np.array([h.chief_xy for h in found]), transmission


__all__ = ["Hits", "basis", "beam_half_width", "field_hits", "geometric"]
