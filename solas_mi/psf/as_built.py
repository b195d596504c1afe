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


@dataclass
class Beam:
    """One field's collimated beam: its chief ray (`local_aim.Chief` of one field), direction (3,), the point
    (3,) and unit vectors (e1, e2) of the plane across it where entrance coordinates lie, the chief ray's
    entrance coordinates (2,) and the half-width (mm) of the square about them that holds the pupil."""

    chief: local_aim.Chief
    direction: np.ndarray
    plane: np.ndarray
    axes: tuple[np.ndarray, np.ndarray]
    centre: np.ndarray
    half: float

    def grid(self, rays: int) -> tuple[np.ndarray, np.ndarray]:
        """Entrance coordinates (rays²,) of the rays×rays cell centres of the square (rows up the e2 axis, as
        `geometric.entrance_grid`)."""
        t = (np.arange(rays) + 0.5) / rays * 2.0 - 1.0
        ex = np.broadcast_to(self.centre[0] + self.half * t[None, :], (rays, rays)).ravel()
        ey = np.broadcast_to(self.centre[1] + self.half * t[:, None], (rays, rays)).ravel()
        return ex, ey

    def trace(self, lens: Lens, ex: np.ndarray, ey: np.ndarray, wavelength_nm: float) -> local_trace.Bundle:
        """The rays of entrance coordinates (ex, ey) traced through `lens` as built."""
        points = self.plane + ex[:, None] * self.axes[0] + ey[:, None] * self.axes[1]
        return local_trace.trace(lens, local_trace.bundle(points, self.direction), wavelength_nm)


def beam(lens: Lens, field_deg, wavelength_nm: float, half_mm: float | None = None) -> Beam:
    """The `Beam` of field `field_deg` (x, y degrees) at `wavelength_nm`, its half-width found by
    `beam_half_width` unless `half_mm` is given; SolasError where no chief ray is found."""
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(2)
    chief = local_aim.chief_rays(lens, field_deg.reshape(1, 2), wavelength_nm)
    if not chief.found[0]:
        raise SolasError(
            f"lens {lens.name}: no chief ray of the lens as built found at field ({field_deg[0]:g}, {field_deg[1]:g}) "
            f"deg, {wavelength_nm:g} nm (none passes the stop's centre, or its aim does not converge)"
        )
    d = chief.direction[0]
    axes = basis(d)
    plane = np.array([0.0, 0.0, chief.start[0, 2]])
    centre = np.array([(chief.start[0] - plane) @ axes[0], (chief.start[0] - plane) @ axes[1]])
    found = Beam(chief, d, plane, axes, centre, 0.0)
    found.half = beam_half_width(lens, found, wavelength_nm) if half_mm is None else half_mm
    return found


def ray_power(lens: Lens, b: Beam, rays: int, wavelength_nm: float) -> float:
    """The power of one ray of a rays×rays grid over beam `b` (fraction of the on-axis entrance pupil's)."""
    return float(power_densities(lens, np.array([wavelength_nm]))[0]) * (2.0 * b.half / rays) ** 2


def field_hits(
    lens: Lens, field_deg, wavelength_nm: float, rays: int, half_mm: float | None = None
) -> tuple[Hits, float]:
    """The `Hits` of a rays×rays grid across the beam of field `field_deg` (x, y degrees) at `wavelength_nm`,
    and the grid's half-width (mm; found by `beam_half_width` unless `half_mm` is given)."""
    b = beam(lens, field_deg, wavelength_nm, half_mm)
    out = b.trace(lens, *b.grid(rays), wavelength_nm)
    ok = out.ok
    power = np.full(int(ok.sum()), ray_power(lens, b, rays, wavelength_nm))
    return Hits(out.image_x[ok], out.image_y[ok], power, b.chief.image_xy[0]), b.half


def beam_half_width(lens: Lens, b: Beam, wavelength_nm: float) -> float:
    """Half-width (mm) of a square across beam `b`, about its chief ray, that holds every ray the lens passes: a
    coarse grid over what surface 1's aperture can let through (its semi-diameter and sag's reach about its
    vertex), widened by one of its cells and `MARGIN`."""
    first = frames(lens.surfaces, lens.image_placement)[0][0]
    s = lens.surfaces[0]
    rim = (
        np.array([s.semi_diameter, 0.0, -s.semi_diameter, 0.0]),
        np.array([0.0, s.semi_diameter, 0.0, -s.semi_diameter]),
    )
    reach = np.hypot(s.semi_diameter, np.abs(s.geometry.sag(*rim)).max())  # x and y: a toroid's sags differ
    vertex = np.array([(first - b.plane) @ b.axes[0], (first - b.plane) @ b.axes[1]])
    outer = float(np.abs(vertex - b.centre).max() + reach) * MARGIN
    coarse = Beam(b.chief, b.direction, b.plane, b.axes, b.centre, outer)
    ex, ey = coarse.grid(COARSE_RAYS)
    ok = coarse.trace(lens, ex, ey, wavelength_nm).ok
    if not ok.any():
        return outer
    spread = max(np.abs(ex[ok] - b.centre[0]).max(), np.abs(ey[ok] - b.centre[1]).max())
    return min(outer, (spread + 2.0 * outer / COARSE_RAYS) * MARGIN)


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


__all__ = ["Beam", "Hits", "basis", "beam", "beam_half_width", "field_hits", "geometric", "ray_power"]
