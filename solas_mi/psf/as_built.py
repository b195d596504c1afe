"""Geometric PSFs of the lens as built (decentred or tilted surfaces, toroids, a tilted sensor), traced with
the Dr.Jit tracer in each surface's frame (`optics.tracer_local`, every field of a wavelength in one trace) about
chief rays aimed in two dimensions, all fields together (`optics.local_aim`).

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

from dataclasses import dataclass, fields

import numpy as np

from ..errors import SolasError
from ..llvm import import_drjit
from ..optics import local_aim, local_trace, tracer, tracer_local
from ..optics.lens import Lens
from ..optics.placement import frames
from ..optics.pupil import power_densities
from .geometric import bin_hits

dr = import_drjit()

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
    half: float  # the half-width (mm) of the ray grid's square across the beam


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

    def points(self, ex: np.ndarray, ey: np.ndarray) -> np.ndarray:
        """The start points (n, 3) of the rays of entrance coordinates (ex, ey)."""
        return self.plane + ex[:, None] * self.axes[0] + ey[:, None] * self.axes[1]


def trace_beams(lens: Lens, beams: list[Beam], entrance, wavelength_nm: float) -> list[local_trace.Bundle]:
    """The rays of each of `beams` at its entrance coordinates (`entrance`: (ex, ey) per beam) through `lens` as
    built, all in one trace of the Dr.Jit tracer (`optics.tracer_local`): one `local_trace.Bundle` per beam."""
    points = np.concatenate([b.points(ex, ey) for b, (ex, ey) in zip(beams, entrance)])
    directions = np.concatenate([np.broadcast_to(b.direction, (len(ex), 3)) for b, (ex, _) in zip(beams, entrance)])
    out = tracer_local.trace_bundle(lens, local_trace.bundle(points, directions), wavelength_nm)
    ends = np.cumsum([len(ex) for ex, _ in entrance])[:-1]
    parts = [np.split(getattr(out, f.name), ends) for f in fields(out)]
    return [local_trace.Bundle(*columns) for columns in zip(*parts)]


def grid_hits(lens: Lens, found: list[Beam], rays: int, wavelength_nm: float) -> tuple[np.ndarray, ...]:
    """Where the rays of each of beams `found` on its rays×rays grid (`Beam.grid`) land on the image plane, in its
    own frame: (x, y, passed), each (beams, rays²). The rays are made in Dr.Jit from each beam's plane, axes,
    centre, half-width and direction (gathered per ray) and traced in one call of the Dr.Jit tracer in local
    frames; only the image points come back to NumPy."""
    n = rays * rays
    idx = dr.arange(tracer.UInt32, len(found) * n)
    beam, cell = idx // n, idx % n
    per_beam = np.array([[*b.plane, *b.axes[0], *b.axes[1], *b.centre, b.half, *b.direction] for b in found])
    plane, e1, e2, centre, half, d = (
        [tracer.gather(per_beam[:, k], beam) for k in range(start, stop)]
        for start, stop in ((0, 3), (3, 6), (6, 9), (9, 11), (11, 12), (12, 15))
    )
    steps = 2.0 / rays
    ex = dr.fma(half[0], tracer.F(cell % rays) * steps + (0.5 * steps - 1.0), centre[0])
    ey = dr.fma(half[0], tracer.F(cell // rays) * steps + (0.5 * steps - 1.0), centre[1])
    p = [dr.fma(ex, a, dr.fma(ey, b, o)) for o, a, b in zip(plane, e1, e2)]
    traced = tracer_local.trace(
        lens, tracer.Rays(*p, *d, dr.zeros(tracer.F, len(found) * n)), tracer.opaque(wavelength_nm * 1e-3)
    )
    x, y, _ = tracer.to_plane(traced, lens.image_z)
    passed = traced.ok & (traced.clipped_by == 0) & dr.isfinite(x) & dr.isfinite(y)
    return tuple(a.reshape(len(found), n) for a in tracer.to_numpy(x, y, passed))


def beams(lens: Lens, field_deg, wavelength_nm: float, half_mm=None) -> list[Beam]:
    """The `Beam` of each of fields `field_deg` ((n, 2) degrees) at `wavelength_nm`, their chief rays aimed together,
    their half-widths found together by `beam_half_widths` unless `half_mm` ((n,) mm) is given; SolasError naming the
    first field without a chief ray."""
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(-1, 2)
    chief = local_aim.chief_rays(lens, field_deg, wavelength_nm)
    if not chief.found.all():
        fx, fy = field_deg[np.argmin(chief.found)]
        raise SolasError(
            f"lens {lens.name}: no chief ray of the lens as built found at field ({fx:g}, {fy:g}) "
            f"deg, {wavelength_nm:g} nm (none passes the stop's centre, or its aim does not converge)"
        )
    found = []
    for i in range(len(field_deg)):
        one = local_aim.Chief(*(a[i : i + 1] for a in (chief.start, chief.direction, chief.image_xy, chief.found)))
        d = chief.direction[i]
        axes = basis(d)
        plane = np.array([0.0, 0.0, chief.start[i, 2]])
        centre = np.array([(chief.start[i] - plane) @ axes[0], (chief.start[i] - plane) @ axes[1]])
        found.append(Beam(one, d, plane, axes, centre, 0.0))
    halves = beam_half_widths(lens, found, wavelength_nm) if half_mm is None else np.broadcast_to(half_mm, len(found))
    for b, half in zip(found, halves):
        b.half = float(half)
    return found


def pupil_density(lens: Lens, wavelength_nm: float) -> float:
    """The power per mm² across a beam at `wavelength_nm` (`pupil.power_densities`: the on-axis entrance pupil
    carries 1)."""
    return float(power_densities(lens, np.array([wavelength_nm]))[0])


def ray_power(density: float, b: Beam, rays: int) -> float:
    """The power of one ray of a rays×rays grid over beam `b` (fraction of the on-axis entrance pupil's), of
    `pupil_density` `density`."""
    return density * (2.0 * b.half / rays) ** 2


def fields_hits(lens: Lens, field_deg, wavelength_nm: float, rays: int, half_mm=None) -> list[Hits]:
    """The `Hits` of a rays×rays grid across the beam of each of fields `field_deg` ((n, 2) degrees) at
    `wavelength_nm`, all traced together (`beams`, `trace_beams`); `half_mm` as `beams`'."""
    found = beams(lens, field_deg, wavelength_nm, half_mm)
    density = pupil_density(lens, wavelength_nm)
    out = []
    for b, x, y, ok in zip(found, *grid_hits(lens, found, rays, wavelength_nm)):
        out.append(Hits(x[ok], y[ok], np.full(int(ok.sum()), ray_power(density, b, rays)), b.chief.image_xy[0], b.half))
    return out


def field_hits(
    lens: Lens, field_deg, wavelength_nm: float, rays: int, half_mm: float | None = None
) -> tuple[Hits, float]:
    """The `Hits` of one field `field_deg` (x, y degrees) and the grid's half-width (mm) (`fields_hits`)."""
    hits = fields_hits(lens, np.reshape(field_deg, (1, 2)), wavelength_nm, rays, None if half_mm is None else [half_mm])
    return hits[0], hits[0].half


def beam_half_widths(lens: Lens, found: list[Beam], wavelength_nm: float) -> np.ndarray:
    """Half-width (mm) of a square across each of beams `found`, about its chief ray, that holds every ray the lens
    passes: a coarse grid over what surface 1's aperture can let through (its semi-diameter and sag's reach about
    its vertex), widened by one of its cells and `MARGIN`; the coarse grids of every beam traced together."""
    first = frames(lens.surfaces, lens.image_placement)[0][0]
    s = lens.surfaces[0]
    rim = (
        np.array([s.semi_diameter, 0.0, -s.semi_diameter, 0.0]),
        np.array([0.0, s.semi_diameter, 0.0, -s.semi_diameter]),
    )
    reach = np.hypot(s.semi_diameter, np.abs(s.geometry.sag(*rim)).max())  # x and y: a toroid's sags differ
    coarse = []
    for b in found:
        vertex = np.array([(first - b.plane) @ b.axes[0], (first - b.plane) @ b.axes[1]])
        outer = float(np.abs(vertex - b.centre).max() + reach) * MARGIN
        coarse.append(Beam(b.chief, b.direction, b.plane, b.axes, b.centre, outer))
    halves = []
    for c, *_, ok in zip(coarse, *grid_hits(lens, coarse, COARSE_RAYS, wavelength_nm)):
        if not ok.any():
            halves.append(c.half)
            continue
        ex, ey = c.grid(COARSE_RAYS)
        spread = max(np.abs(ex[ok] - c.centre[0]).max(), np.abs(ey[ok] - c.centre[1]).max())
        halves.append(min(c.half, (spread + 2.0 * c.half / COARSE_RAYS) * MARGIN))
    return np.array(halves)


def geometric(
    lens: Lens, field_deg, wavelength_nm, pitch_um: float, size: int, rays: int, half_mm=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Geometric PSFs (n, size, size) in 1/µm² of the lens as built at fields `field_deg` (n, 2) and
    `wavelength_nm` (n,, or one), each binned about its chief ray's image point on the image plane (in that
    plane's frame); also those points (n, 2) mm and the transmitted power (n,). Every field is traced
    (a grid over the whole field: no half of it mirrored). `half_mm` (n,): each grid's half-width, else found."""
    found = hits_by_wavelength(lens, field_deg, wavelength_nm, rays, half_mm)
    offsets = [((h.x - h.chief_xy[0]) * 1e3, (h.y - h.chief_xy[1]) * 1e3, h.power) for h in found]
    data, transmission = bin_hits(offsets, pitch_um, size)
    return data, np.array([h.chief_xy for h in found]), transmission


def hits_by_wavelength(lens: Lens, field_deg, wavelength_nm, rays: int, half_mm=None) -> list[Hits]:
    """`fields_hits` of fields `field_deg` (n, 2) at `wavelength_nm` (n,, or one), the fields of each wavelength
    traced together, in the order given; `half_mm` (n,) as `beams`'."""
    field_deg = np.asarray(field_deg, dtype=np.float64).reshape(-1, 2)
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),))
    found: list = [None] * len(field_deg)
    for w in np.unique(wavelength_nm):
        at = np.flatnonzero(wavelength_nm == w)
        halves = None if half_mm is None else np.broadcast_to(half_mm, (len(field_deg),))[at]
        for i, h in zip(at, fields_hits(lens, field_deg[at], float(w), rays, halves)):
            found[i] = h
    return found


__all__ = [
    "Beam",
    "Hits",
    "basis",
    "beam_half_widths",
    "beams",
    "field_hits",
    "fields_hits",
    "grid_hits",
    "geometric",
    "hits_by_wavelength",
    "pupil_density",
    "ray_power",
    "trace_beams",
]
