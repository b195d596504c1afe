"""PSF grids over the field computed: `psf_grid` gives one stack of PSFs per wavelength, a
`grid_file.PSFGrid` (which writes them as OpenEXR with the metadata needed to use them without the
lens, and a PNG mosaic for looking at them).

A centred lens's distinct |field| pairs are each computed once and mirrored (`nodes`); a lens as built
(decentred, tilted or non-symmetric surfaces, or a placed sensor) has every node traced (`as_built_grid`).

Field grid convention: `ny`×`nx` nodes in image orientation, row 0 = top = largest y field angle,
column 0 = smallest x field angle. "centers" sampling puts the nodes at the centres of ny×nx equal
cells spanning ±field (the block centres of a tiled image); "edges" spans ±field including the ends.
The SOLAS paper's PSF maps are such grids (8×8 over the doublet's ±2°; see the `solas_mi` docstring).
"""
from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import SolasError
from ..optics.camera import pinhole_focal_mm
from ..optics.lens import Lens
from ..optics.lens_checks import as_built
from ..pages import small_pages
from . import base
from .grid_file import PSFGrid  # a grid's PSFs and its file; imported from here too
from .methods import method_options
from .nodes import Nodes, compute_nodes
from .sensor import default_sensor_mm, fields_for_points, node_mm
from .spec import FIELD_SAMPLINGS, GridSpec


def field_nodes(n: int, half_range: float, sampling: str) -> np.ndarray:
    """n field angles (degrees) spanning ±half_range, increasing."""
    if sampling == "centers":
        return -half_range + (np.arange(n) + 0.5) * (2.0 * half_range / n)
    if sampling == "edges":
        return np.linspace(-half_range, half_range, n) if n > 1 else np.zeros(1)
    raise SolasError(f"field sampling {sampling!r} must be one of {', '.join(FIELD_SAMPLINGS)}")


def psf_grid(lens: Lens, spec: GridSpec | None = None, progress=None, **options) -> PSFGrid:
    """PSFs on a grid of fields, one stack per wavelength.

    Layout "field": nodes spanning ±field_range_deg (x, y); layout "sensor" (`psf.sensor`): nodes at
    the cell centres of a sensor, each with the field whose chief ray lands there (``meta["node_mm"]``:
    their image points). A centred lens's mirror-image fields are computed once, a lens as built's each traced.

    Parameters
    ----------
    lens : Lens
        The lens.
    spec : GridSpec, optional
        The grid's options; default: `GridSpec()`.
    progress : callable, optional
        Called as ``progress(done, total)`` after each batch of PSFs, counting the grid's PSFs (nodes ×
        wavelengths, mirrored ones included).
    **options
        Fields of `GridSpec`, e.g. ``grid=(24, 32)``; they change those of `spec`.

    Returns
    -------
    PSFGrid
        The grid; ``meta["energy_in_window"]`` holds each PSF's share of its transmitted light inside its
        window and ``meta["warnings"]`` what looked doubtful.

    Raises
    ------
    SolasError
        For a `spec` that is not a GridSpec, a bad option, object distances (a grid over distance:
        `psf.depth.depth_grid`), or a node whose every ray is blocked.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> from solas_mi.psf import psf_grid
    >>> grid = psf_grid(Lens.load("solas-doublet"), grid=(2, 2), size=32)
    >>> grid.data.shape, grid.fields_deg[0, 0].tolist()
    ((3, 2, 2, 32, 32), [-1.0, 1.0])
    """
    base.check_lens(lens)
    if spec is not None and not isinstance(spec, GridSpec):
        raise SolasError(f"spec {spec!r} must be a GridSpec (or give its options as keywords)")
    spec = GridSpec(**options) if spec is None else replace(spec, **options)
    if spec.distances_m is not None:
        raise SolasError(f"distances {list(spec.distances_m)} m make a grid over object distance: use "
                         "psf.depth.depth_grid (psf_grid is for the lens file's object distance)")
    wl = base.check_wavelengths(lens, spec.wavelengths_nm if spec.wavelengths_nm is not None else lens.wavelengths_nm)
    compute, (fields, placement) = node_computer(lens, spec, wl), grid_fields(lens, spec)  # checked first
    size = spec.size
    while True:  # auto_window: the whole grid again at twice the size until every window holds enough
        start = time.perf_counter()
        with small_pages():
            nodes = compute(lens, spec, wl, fields.reshape(-1, 2), size, progress)
        if not (spec.auto_window and nodes.energy.min() < base.WINDOW_ENERGY_LIMIT and 2 * size <= base.MAX_SIZE):
            break
        size *= 2
    meta = grid_meta(lens, spec, wl, fields, nodes, size, placement)
    meta["seconds"] = time.perf_counter() - start
    ny, nx = spec.grid
    return PSFGrid(nodes.data, fields, nodes.chief.reshape(len(wl), ny, nx, 2), wl, spec.pitch_um, meta)


def node_computer(lens: Lens, spec: GridSpec, wl: tuple[float, ...]):
    """What computes the grid's nodes: `nodes.compute_nodes` (mirrored) for a centred lens, and for a lens as
    built `as_built_grid.compute_nodes` (every node traced), once `as_built_grid.check` takes the spec."""
    if not as_built(lens):
        return compute_nodes
    from . import as_built_grid

    as_built_grid.check(lens, spec, wl)
    return as_built_grid.compute_nodes


def grid_fields(lens: Lens, spec: GridSpec) -> tuple[np.ndarray, dict]:
    """The fields (ny, nx, 2) in degrees of the grid's nodes, and the metadata of their placement."""
    ny, nx = spec.grid
    if spec.layout == "sensor":
        sensor_mm = default_sensor_mm(lens) if spec.sensor_mm is None else spec.sensor_mm
        nodes = node_mm(sensor_mm, ny, nx)
        return fields_for_points(lens, nodes, lens.primary_wavelength), {
            "layout": "sensor", "reference_wavelength_nm": lens.primary_wavelength, "sensor_mm": list(sensor_mm),
            "node_mm": nodes.tolist(),
            "grid_orientation": "grid row 0 = top (largest y) of the sensor, column 0 = left"}
    hx, hy = lens.field_deg, lens.field_deg
    if spec.field_range_deg is not None:
        hx, hy = spec.field_range_deg
    fx = field_nodes(nx, hx, spec.field_sampling)
    fy = field_nodes(ny, hy, spec.field_sampling)[::-1]  # row 0 = top = largest y
    placement: dict[str, Any] = {"layout": "field", "field_sampling": spec.field_sampling, "field_range_deg": [hx, hy],
                 "grid_orientation": "grid row 0 = largest y field, column 0 = smallest x field"}
    if hx > 0:  # the ideal image an input spanning ±hx horizontally stands for (`optics.camera`)
        from .as_built_grid import pinhole_focal_mm as as_built_focal_mm

        focal = (as_built_focal_mm if as_built(lens) else pinhole_focal_mm)(lens, hx)
        placement.update(pinhole_focal_mm=focal, reference_wavelength_nm=lens.primary_wavelength)
    return np.stack(np.meshgrid(fx, fy), axis=-1), placement


def grid_meta(lens: Lens, spec: GridSpec, wl: tuple[float, ...], fields: np.ndarray, nodes: Nodes, size: int,
              placement: dict) -> dict:
    """The grid's metadata: the lens, method and sampling (`base.describe`), the spec, the nodes'
    placement, transmission, window energy and warnings."""
    ny, nx = spec.grid
    n = ny * nx
    lit = nodes.transmission > 0
    meta = base.describe(lens, spec.method, spec.normalization, method_options(spec.method, spec.sampling_options()),
                         size)
    meta.update(placement)
    if as_built(lens):  # every node traced by the paths of the lens as built, none mirrored
        from .as_built_methods import PATHS

        meta["path"] = PATHS[spec.method] + "; every node traced (none mirrored)"
    dark = [] if lit.all() else [f"{int((~lit).sum())} of {lit.size} PSFs receive no light (every ray blocked): "
                                 "they are zero"]
    meta.update({
        "grid_spec": spec.canonical(),
        "transmission": nodes.transmission.reshape(len(wl), ny, nx).tolist(),
        "energy_in_window": nodes.energy.reshape(len(wl), ny, nx).tolist(),
        "vignetted_by_surfaces": list(nodes.vignetting),
        "warnings": [*nodes.doubts, *base.window_warnings(nodes.energy[lit], np.broadcast_to(
            fields.reshape(-1, 2), (len(wl), n, 2))[lit], size, spec.pitch_um), *dark],
    })
    return meta
