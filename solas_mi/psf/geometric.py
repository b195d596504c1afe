"""Geometric PSFs: real rays on a regular grid over the entrance pupil, binned per image pixel."""

from __future__ import annotations

import numpy as np

from ..optics import pupil, tracer
from ..optics.lens import Lens
from ..optics.pupil import ChiefRays
from .base import Computed, centring_warnings, window_centres_um

_BATCH_RAYS = 1 << 20  # rays traced at once


def compute(
    lens: Lens,
    field_deg: np.ndarray,
    wavelength_nm: np.ndarray,
    pitch_um: float,
    size: int,
    *,
    shared_origin: bool = False,
    rays: int,
) -> Computed:
    """Geometric PSFs of field/wavelength pairs from rays×rays entrance grids (the method "geometric" of
    `registry`)."""
    chief = pupil.chief_rays(lens, field_deg, wavelength_nm)
    light = light_offsets_um(lens, field_deg, wavelength_nm, chief)
    center = window_centres_um(chief, light, shared_origin)
    data, _, transmission = geometric(lens, field_deg, wavelength_nm, pitch_um, size, rays, chief, center)
    return Computed(
        data=data,
        chief=chief,
        transmission=transmission,
        vignetted_by=[[] for _ in field_deg],
        warnings=tuple(centring_warnings(chief, light, field_deg)),
        centre_um=center,
    )


def light_offsets_um(
    lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, chief: ChiefRays, rays: int = 64
) -> np.ndarray | None:
    """Where the chief ray of a field is blocked but light passes, the offset (µm) from the chief ray's
    image point to the power centroid of the light that arrives (rays×rays entrance grid), else 0:
    (n, 2), or None when no chief ray is blocked."""
    if not chief.vignetted.any():
        return None
    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (len(field_deg),)).copy()
    out = np.zeros((len(field_deg), 2))
    for i, (x, y, power) in enumerate(entrance_grid_hits(lens, field_deg, wavelength_nm, rays, chief)):
        if chief.vignetted[i] and power.sum() > 0:
            out[i] = (np.dot(power, x) / power.sum(), np.dot(power, y) / power.sum())
    return out


def geometric(
    lens: Lens,
    field_deg: np.ndarray,
    wavelength_nm: np.ndarray,
    pitch_um: float,
    size: int,
    rays: int,
    chief: ChiefRays | None = None,
    center_um: np.ndarray | None = None,
) -> tuple[np.ndarray, ChiefRays, np.ndarray]:
    """Geometric PSFs (n, size, size) in 1/µm²: rays on a rays×rays grid over the entrance pupil,
    binned on the image-plane grid (each bin holds the power that lands in that pixel); also the
    chief rays and the transmitted power (fraction of the on-axis pupil, inside the grid or not).

    `center_um` (n, 2) shifts each grid's origin from the chief ray (default: none)."""
    field_deg = np.atleast_2d(np.asarray(field_deg, dtype=np.float64))
    nf = len(field_deg)
    wavelength_nm = np.broadcast_to(np.asarray(wavelength_nm, dtype=np.float64), (nf,)).copy()
    chief = chief or pupil.chief_rays(lens, field_deg, wavelength_nm)
    data, transmission = bin_hits(
        entrance_grid_hits(lens, field_deg, wavelength_nm, rays, chief), pitch_um, size, center_um
    )
    return data, chief, transmission


def bin_hits(
    hits: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
    pitch_um: float,
    size: int,
    center_um: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """PSFs (n, size, size) in 1/µm² from per-field hits (x, y offsets in µm from the chief ray, power
    of each ray), on the grid whose origin is the chief ray shifted by `center_um` (n, 2); and the
    power of each field's hits."""
    out = np.zeros((len(hits), size, size))
    edges = (np.arange(size + 1) - size // 2 - 0.5) * pitch_um
    shift = np.zeros((len(hits), 2)) if center_um is None else center_um
    for f, (dx, dy, w) in enumerate(hits):
        # rows run down from +y: the row coordinate is −(y offset), binned like the columns
        h, _, _ = np.histogram2d(shift[f, 1] - dy, dx - shift[f, 0], bins=(edges, edges), weights=w)
        out[f] = h / pitch_um**2
    return out, np.array([w.sum() for _, _, w in hits])


def entrance_grid(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, rays: int, chief: ChiefRays):
    """The rays×rays entrance grids over the pupils of the fields, in batches of about a million rays:
    yields (slice of fields, ex, ey, power) with entrance coordinates ex, ey (b, rays, rays) in mm about
    each chief ray and each ray's power (b, rays², fraction of the on-axis entrance-pupil power)."""
    nf = len(field_deg)
    half = entrance_half_width(lens, field_deg, wavelength_nm, chief)
    t = (np.arange(rays) + 0.5) / rays * 2.0 - 1.0
    per_batch = max(1, _BATCH_RAYS // (rays * rays))
    for start in range(0, nf, per_batch):
        sl = slice(start, min(nf, start + per_batch))
        cx, cy, hw = chief.entrance[sl, 0], chief.entrance[sl, 1], half[sl]
        ex = (cx[:, None, None] + hw[:, None, None] * t[None, None, :]).repeat(rays, axis=1)
        ey = (cy[:, None, None] + hw[:, None, None] * t[None, :, None]).repeat(rays, axis=2)
        area = (2.0 * hw / rays) ** 2  # entrance area of one ray
        power = pupil.entrance_power(lens, field_deg[sl], wavelength_nm[sl], ex, ey).reshape(-1, rays * rays)
        yield sl, ex, ey, power * area[:, None]


def entrance_grid_hits(
    lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, rays: int, chief: ChiefRays
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per field: image-plane offsets (µm) from the chief ray of unvignetted rays on a regular
    rays×rays entrance grid covering the pupil, and each ray's power (fraction of the on-axis pupil)."""
    result = []
    for sl, ex, ey, power in entrance_grid(lens, field_deg, wavelength_nm, rays, chief):
        b = pupil.Bundle(lens, field_deg[sl], wavelength_nm[sl], rays * rays)
        tr = b.trace(tracer.array(ex.ravel()), tracer.array(ey.ravel()))
        x, y, _ = tracer.to_plane(tr, lens.image_z)
        keep, x, y = (a.reshape(-1, rays * rays) for a in tracer.to_numpy(tr.ok & (tr.clipped_by == 0), x, y))
        for j, f in enumerate(range(sl.start, sl.stop)):
            m = keep[j]
            result.append(((x[j, m] - chief.image_xy[f, 0]) * 1e3, (y[j, m] - chief.image_xy[f, 1]) * 1e3, power[j, m]))
    return result


def entrance_half_width(lens: Lens, field_deg: np.ndarray, wavelength_nm: np.ndarray, chief: ChiefRays) -> np.ndarray:
    """Half-width (mm) of a square about the chief ray's entrance point that holds the whole pupil."""
    ex, ey, _, _ = pupil.stop_rim(pupil.Bundle(lens, field_deg, wavelength_nm, pupil.RIM_RAYS), chief)
    ex, ey = ex - chief.entrance[:, 0:1], ey - chief.entrance[:, 1:2]
    return np.maximum(np.abs(ex).max(axis=1), np.abs(ey).max(axis=1)) * 1.02
