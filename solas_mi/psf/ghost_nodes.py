"""Ghost grids: every two-reflection ghost of a lens (`stray_light`) on nodes along the field's radius, each
ghost kept as its energy, centroid and a small kernel about it, per wavelength (`ghost_grid_file.GhostGrid`,
whose docstring says why and how a field between nodes is served). Cached on disk by the lens's hash and the
options (`caches.FileCache`, folder ghost-grids in solas-mi's cache folder): a second call with the same lens
and options reads the grid back.

A node's ghosts are those of `stray_light.ghosts` at its field and one wavelength (the same launch grid, so the
same rays): energy relative to that wavelength's direct image, centroid, and the rays binned about the
centroid, smoothed over their spacing and, for a focused ghost, blurred by its Airy pattern as the stray-light
PSF does (`stray_psf`), on a kernel whose pitch holds the whole ghost.
"""

from __future__ import annotations

import numpy as np

from ..caches import FileCache
from ..errors import SolasError
from ..optics import ghost_paths
from ..optics.lens import Lens
from .geometric import bin_hits
from .ghost_grid_file import (
    DEFAULT_IRIS_AZIMUTHS,
    DEFAULT_KERNEL,
    DEFAULT_RADII,
    KERNEL_RANGE,
    MAX_AZIMUTHS,
    MAX_RADII,
    GhostGrid,
)
from .stray_light import MAX_FIELD_DEG, check_rays, ghost_row, launch, on_image
from .stray_psf import AIRY_REACH, airy_blur, ray_spacing_um, smooth

KERNEL_SHARE = 0.999  # a kernel's reach: the radius about the centroid that holds this share of the ghost's rays
CACHE = FileCache("ghost-grids", "ghost grid", ".exr")


def _count(name: str, value, low: int, high: int, what: str) -> int:
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or not low <= value <= high:
        raise SolasError(f"{name} {value!r} must be an integer from {low} to {high} ({what})")
    return int(value)


def _odd_kernel(kernel) -> int:
    if isinstance(kernel, (int, np.integer)) and not isinstance(kernel, bool) and kernel % 2 == 0:
        raise SolasError(f"kernel {kernel!r} must be odd (pixels per side, symmetric about the ghost's centroid)")
    return _count("kernel", kernel, *KERNEL_RANGE, "pixels per side of each ghost's kernel, odd")


def grid_options(lens: Lens, radii, field_deg, wavelengths_nm, rays, kernel, azimuths) -> dict:
    """The options as one checked, canonical dict (the cache's key with the lens's hash); SolasError naming a
    bad one and what is allowed."""
    blades = lens.surfaces[lens.stop_index].blades if lens.stop_index is not None else 0
    if field_deg is None:
        field_deg = lens.field_deg
    if isinstance(field_deg, bool) or not isinstance(field_deg, (int, float)) or not 0 < field_deg < MAX_FIELD_DEG:
        raise SolasError(
            f"field_deg {field_deg!r} must be a polar angle above 0 and below {MAX_FIELD_DEG:g} deg (the grid's "
            "largest field; default the lens's field_deg)"
        )
    check_rays(rays)
    wavelengths = [lens.check_wavelength(w) for w in (wavelengths_nm or lens.wavelengths_nm)]
    if len({f"{w:g}" for w in wavelengths}) != len(wavelengths):
        raise SolasError(f"wavelengths_nm {wavelengths} must be distinct to 6 digits (one channel each)")
    if blades:
        azimuths = _count("azimuths", DEFAULT_IRIS_AZIMUTHS if azimuths is None else azimuths, 1, MAX_AZIMUTHS,
                          f"nodes per {360 / blades:g} deg sector of the {blades}-blade iris")  # fmt: skip
    elif azimuths not in (None, 1):
        raise SolasError(
            f"azimuths {azimuths!r}: the lens's stop is round, so every azimuth's ghosts are the meridian's turned; "
            "azimuths are for an iris (blades); give 1 or none"
        )
    return {
        "radii": _count("radii", radii, 2, MAX_RADII, "nodes along the field's radius"),
        "field_deg": float(field_deg),
        "wavelengths_nm": wavelengths,
        "rays": rays,
        "kernel": _odd_kernel(kernel),
        "azimuths": azimuths or 1,
        "sector_deg": 360.0 / blades if blades else 360.0,
    }


def ghost_grid(
    lens: Lens,
    radii: int = DEFAULT_RADII,
    field_deg: float | None = None,
    wavelengths_nm=None,
    rays: int = ghost_paths.DEFAULT_RAYS,
    kernel: int = DEFAULT_KERNEL,
    azimuths: int | None = None,
    cache: bool = True,
    progress=None,
) -> GhostGrid:
    """Every ghost of the lens on `radii` nodes from the axis to `field_deg`, per wavelength (module docstring).

    Parameters
    ----------
    lens : Lens
        The lens (centred; its coatings weigh the ghosts).
    radii : int, default 9
        Nodes along the field's radius, polar angles 0 … `field_deg` evenly.
    field_deg : float, optional
        The largest polar angle (degrees); default the lens's field_deg.
    wavelengths_nm : sequence of float, optional
        The wavelengths (nm), each a channel of its own; default the lens's.
    rays : int, default 128
        Rays per side of each node's launch grid (`stray_light.ghosts`).
    kernel : int, default 63
        Pixels per side of each ghost's kernel (odd).
    azimuths : int, optional
        For an iris: nodes per blade sector (default 4); a round stop takes 1 (the ghosts turn with the field).
    cache : bool, default True
        Read the grid back from solas-mi's cache folder where it is there, and keep it there.
    progress : callable, optional
        Called as ``progress(done, total)`` after each node.

    Returns
    -------
    GhostGrid
        The grid; ``.at(field)`` gives the ghosts of any field within it.

    Raises
    ------
    SolasError
        For a bad option (named), a lens with fewer than two reflecting surfaces, or a node without direct light.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> from solas_mi.psf import ghost_grid
    >>> grid = ghost_grid(Lens.load("solas-doublet"), radii=3, rays=32, kernel=15, cache=False)
    >>> grid.energy.shape  # wavelengths, azimuths, radii, paths
    (3, 1, 3, 3)
    """
    options = grid_options(lens, radii, field_deg, wavelengths_nm, rays, kernel, azimuths)
    if not ghost_paths.paths(lens):
        raise SolasError(f"lens {lens.name} has fewer than two reflecting surfaces: it has no ghost")
    if not cache:
        return compute(lens, options, progress)
    key = {"lens_hash": lens.hash, "ghost_grid": options}
    grid, _ = CACHE.get_file(key, lambda: compute(lens, options, progress), GhostGrid.write, GhostGrid.read)
    return grid


def compute(lens: Lens, options: dict, progress=None) -> GhostGrid:
    """The grid of checked `options` (`grid_options`), node by node."""
    polar = np.linspace(0.0, options["field_deg"], options["radii"])
    azimuth = 90.0 + np.arange(options["azimuths"]) * options["sector_deg"] / options["azimuths"]
    wl, k, paths = options["wavelengths_nm"], options["kernel"], ghost_paths.paths(lens)
    shape = (len(wl), len(azimuth), len(polar), len(paths))
    energy, pitch, centroid = np.zeros(shape), np.ones(shape), np.zeros((*shape, 2))
    kernels, direct = np.zeros((*shape, k, k), dtype=np.float32), np.zeros((*shape[:3], 2))
    fields = np.zeros((len(azimuth), len(polar), 2))
    for a, phi in enumerate(np.radians(azimuth)):
        for r, theta in enumerate(np.radians(polar)):
            fx, fy = lens.field_type.field_of(theta, np.cos(phi), np.sin(phi))
            fields[a, r] = float(fx), float(fy)
            start = launch(lens, tuple(fields[a, r]), options["rays"])
            for w, wavelength in enumerate(wl):
                traced = ghost_paths.trace_all(lens, start, wavelength)
                x, y, power, _, _ = on_image(lens, traced[None])
                if power.sum() <= 0:
                    raise SolasError(f"no direct light reaches the image at field ({fx:g}, {fy:g}) deg: a smaller "
                                     "field_deg")  # fmt: skip
                direct[w, a, r] = np.average(x, weights=power), np.average(y, weights=power)
                for p, path in enumerate(paths):
                    hit = on_image(lens, traced[path])
                    ghost = ghost_row(path, hit, float(power.sum()), wavelength)
                    if ghost.energy > 0:
                        energy[w, a, r, p], centroid[w, a, r, p] = ghost.energy, ghost.centroid_mm
                        pitch[w, a, r, p], kernels[w, a, r, p] = ghost_kernel(hit, ghost, k)
            if progress is not None:
                progress(a * len(polar) + r + 1, len(azimuth) * len(polar))
    meta = {
        "lens": lens.name,
        "lens_hash": lens.hash,
        "options": options,
        "field_type": lens.field_type.name,
        "fields_deg": fields.tolist(),
        "unit": "energy: fraction of the direct image's at each wavelength; kernels: fractions of the ghost's",
    }
    return GhostGrid(polar, azimuth, options["sector_deg"], tuple(wl), [(j + 1, i + 1) for j, i in paths], energy,
                     centroid, pitch, kernels, direct, meta)  # fmt: skip


def ghost_kernel(hit, ghost, k: int) -> tuple[float, np.ndarray]:
    """A ghost's pitch (µm) and k × k kernel about its centroid summing to 1: its rays binned, smoothed over their
    spacing and, where focused, blurred by its Airy pattern, the pitch such that it holds the rays
    within `KERNEL_SHARE` of its power."""
    x, y, w = hit[0], hit[1], hit[2]
    cx, cy = ghost.centroid_mm
    spacing = ray_spacing_um(x, y, w)
    airy_um = ghost.airy_mm * 1e3 if ghost.focused else 0.0
    distance = np.hypot(x - cx, y - cy)
    order = np.argsort(distance)
    held = np.cumsum(w[order])  # the radius that holds KERNEL_SHARE of its light (a few stray rays do not set it)
    reach = 1e3 * float(distance[order][min(np.searchsorted(held, KERNEL_SHARE * held[-1]), len(held) - 1)])
    reach += 3.0 * spacing + AIRY_REACH * airy_um
    pitch = max(reach, 1e-3) / (k // 2 - 0.5)
    binned, _ = bin_hits([((x - cx) * 1e3, (y - cy) * 1e3, w)], pitch, k)
    image = smooth(binned[0] * pitch**2, spacing / pitch)
    if ghost.focused:
        image = airy_blur(image, airy_um / pitch)
    return pitch, image / image.sum()
