"""The lens's ghosts of a frame's bright sources, added to its degraded image (`degrade --ghosts`).

The sources are the input pixels whose brightest channel exceeds a threshold (linear input units). Their light is
gathered into cells of field angle (`CELLS_PER_NODE` per spacing of the ghost grid's nodes along the radius): each
cell's ghosts are the ghost grid's (`psf.ghost_grid`, every two-reflection ghost of the lens over the field) at the
cell's energy-weighted field (`GhostGrid.at`, interpolated between the nodes and turned to its azimuth), each
ghost's energy that fraction of the cell's light in the channel's wavelength, laid at its own centroid on the
sensor with its own kernel (resampled onto the frame's pixels by area, as `NodeGhosts.image` does). So a ghost
moves, grows and changes shape with its source's field, and the ghosts added hold Σ source light × ghost energy
fraction, less what falls beyond the frame.

The frame's camera is the convolution's: a rectilinear frame (the grid's field, --fov-deg, --intrinsics) maps a
pixel to its direction by the pinhole camera of `kernels.grid_camera` and an image point (mm) to the sensor's pixel
linearly; a fisheye frame (--fisheye) maps a pixel by its calibration and an image point by the lens's chief ray
at the grid's reference wavelength (its image height over polar angle, inverted) then the calibration, each ghost's
kernel scaled by the mapping's local size at its centroid (an isotropic approximation: a fisheye's radial and
tangential scales differ toward the edge). A grid laid out on the sensor is not taken.

The iris's starburst (`psf.starburst`: the stop's aberration-free diffraction at the working f-number, one kernel at
the grid's reference wavelength on the frame's pixels at its centre) is spread from the degraded image as `render
--ghosts` spreads it from the direct image: each pixel keeps the kernel's centre share and gives the rest to the
wings, which join the flare label.

What is not modelled: the ghost grid is of a source at infinity, so with a depth map the sources' distance does not
change their ghosts' focus (for a source beyond some metres a ghost's defocus changes little, its centroid less);
a source's ghosts are those of the cell's one field, so the ghost of a sun disc is its kernel, not the disc imaged
through the ghost's magnification.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import SolasError
from .frame_fields import FrameFields

if TYPE_CHECKING:
    from ..psf.ghost_grid_file import GhostGrid

DEFAULT_THRESHOLD = 10.0  # ten times the white of a linear frame: a sun, lamps and headlights, not lit surfaces
CELLS_PER_NODE = 4  # field cells per spacing of the ghost grid's radial nodes: the sources' light gathered per cell
HDR_SUFFIXES = (".exr",)
UNCOATED = (
    "lens {name} states no coatings: its ghosts are those of uncoated glass (about 4 % a surface), far stronger than "
    "a coated lens's; `solas-mi lens convert --typical-ar` writes it with the typical AR"
)


def check_threshold(value) -> float:
    """The ghost threshold, a positive finite number; SolasError naming it otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value > 0):
        raise SolasError(
            f"ghost threshold {value!r} must be a positive number (linear input units: pixels brighter are the "
            "ghosts' sources)"
        )
    return float(value)


def check_hdr(image_path: str | Path, force: bool) -> list[str]:
    """SolasError for a frame that is not HDR (EXR) unless `force`; with `force`, its warning."""
    suffix = Path(image_path).suffix.lower()
    if suffix in HDR_SUFFIXES:
        return []
    text = (
        f"{image_path}: ghosts of a {suffix or 'non-EXR'} frame: its bright sources are clipped at white, so a "
        "sun gives far too little flare; give the HDR (OpenEXR) frame"
    )
    if not force:
        raise SolasError(text + ", or --force to ghost it anyway")
    return [text]


def lens_ghosts(lens, psf_grid, progress=None) -> GhostGrid:
    """The ghost grid of `lens` over the PSF grid's field (its largest polar angle) at its wavelengths, cached."""
    from ..psf import ghost_grid

    fields = np.asarray(psf_grid.fields_deg, dtype=np.float64).reshape(-1, 2)
    polar = max(lens.field_type.polar(f)[0] for f in fields)
    return ghost_grid(
        lens, field_deg=math.degrees(polar), wavelengths_nm=list(psf_grid.wavelengths_nm), progress=progress
    )


def source_cells(image: np.ndarray, threshold: float, fields: FrameFields, cell_deg: float) -> list:
    """The sources (pixels whose brightest channel exceeds `threshold`) gathered into cells of `cell_deg` of field:
    each cell's (energy-weighted field (2,), light per channel (C,)), in a fixed order."""
    rows, cols = np.nonzero(image.max(axis=-1) > threshold)
    if not len(rows):
        return []
    field = fields.field_deg(cols.astype(np.float64), rows.astype(np.float64))
    light = image[rows, cols].astype(np.float64)
    weight = light.sum(axis=-1)
    keys = np.floor(field / cell_deg).astype(np.int64)
    cells, index = np.unique(keys, axis=0, return_inverse=True)
    index = index.ravel()
    out = []
    for c in range(len(cells)):
        mine = index == c
        w = weight[mine]
        centre = np.average(field[mine], axis=0, weights=w) if w.sum() > 0 else field[mine].mean(axis=0)
        out.append((centre, light[mine].sum(axis=0)))
    return out


def place(plane: np.ndarray, ghosts, k: int, light: float, fields: FrameFields) -> None:
    """Add the ghosts of grid wavelength `k` (`NodeGhosts`), `light` times their energy, to the frame's `plane`
    (H, W)."""
    from ..psf.ghost_grid_file import kernel_overlap

    height, width = plane.shape
    size = ghosts.kernels.shape[-1]
    for p in np.nonzero(ghosts.energy[k] > 0)[0]:
        (col, row), scale = fields.pixel(ghosts.centroid_mm[k, p])
        pitch = float(ghosts.pitch_um[k, p]) * 1e-3 * scale  # the kernel's pitch in frame pixels
        cols, across = kernel_overlap(col - width // 2, pitch, size, 1.0, width)
        rows, down = kernel_overlap(row - height // 2, pitch, size, 1.0, height)
        if len(cols) and len(rows):
            spread = (across @ (light * float(ghosts.energy[k, p]) * ghosts.kernels[k, p]).T).T
            plane[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1] += down @ spread


def frame_ghosts(
    image: np.ndarray, grid: GhostGrid, fields: FrameFields, channels: list[int], threshold: float
) -> tuple[np.ndarray, dict[str, Any]]:
    """The ghosts of `image`'s sources on its frame (H, W, C) and what was done.

    Parameters
    ----------
    image : numpy.ndarray
        (H, W, C) linear values.
    grid : GhostGrid
        The lens's ghosts (`lens_ghosts`).
    fields : FrameFields
        The frame's camera: pixels to fields, image points to pixels.
    channels : list of int
        Each channel's wavelength index in the grid.
    threshold : float
        Pixels whose brightest channel exceeds it are sources.

    Returns
    -------
    (numpy.ndarray, dict)
        The ghosts' irradiance (H, W, C) in the input's units, and the metadata: sources, cells, the light
        of the sources and of their ghosts (all, and inside the frame) per channel, seconds.
    """
    start = time.perf_counter()
    threshold = check_threshold(threshold)
    spacing = float(np.diff(grid.polar_deg).min()) if len(grid.polar_deg) > 1 else float(grid.polar_deg[-1])
    cells = source_cells(image, threshold, fields, spacing / CELLS_PER_NODE)
    flare = np.zeros((image.shape[-1], *image.shape[:2]))  # a plane per channel: each ghost adds to a contiguous block
    expected = np.zeros(image.shape[-1])
    for centre, light in cells:
        ghosts = grid.at(fields.clamped(centre, float(grid.polar_deg[-1])))
        for c, k in enumerate(channels):
            expected[c] += light[c] * float(ghosts.energy[k].sum())
            if light[c] > 0:
                place(flare[c], ghosts, k, float(light[c]), fields)
    source = np.asarray([light for _, light in cells]).sum(axis=0) if cells else np.zeros(image.shape[-1])
    meta = {
        "threshold": threshold,
        "source_pixels": int((image.max(axis=-1) > threshold).sum()),
        "cells": len(cells),
        "cell_deg": spacing / CELLS_PER_NODE,
        "source_light": source.tolist(),
        "ghost_light": expected.tolist(),
        "ghost_light_in_frame": flare.sum(axis=(1, 2)).tolist(),
        "seconds": time.perf_counter() - start,
    }
    return np.moveaxis(flare, 0, -1), meta


FLARE_ABOUT = (
    "flare.irradiance: the lens's ghosts of the frame's sources (the channels' mean, the image's units), 0 where none "
    "arrive; flare.ratio: that over the degraded direct image's mean ({cap:g} where a pixel has no direct light)"
)


class FrameGhosts:
    """`degrade --ghosts` of one frame: checked and its ghost grid read (or computed) before any work (`plan`), then
    the ghosts added to the degraded image (`add`)."""

    def __init__(self, grid, fields: FrameFields, channels: list[int], threshold: float, about: dict, lens) -> None:
        self.grid, self.fields, self.channels, self.threshold, self.about = grid, fields, channels, threshold, about
        self.lens, self.wavelength_nm = lens, float(fields.wavelength_nm)

    @classmethod
    def plan(cls, image_path, psf_grid, spec, force: bool, lens=None, depth=None) -> FrameGhosts | None:
        """None without `spec.ghosts`; else the frame's ghosts: SolasError for an LDR frame (unless `force`) or a
        grid whose lens cannot be read again (`camera.grid_lens`; `lens` given: that one)."""
        if not spec.ghosts:
            return None
        from ..imageio import image_size
        from .camera import grid_lens
        from .kernels import channel_wavelengths

        warnings = check_hdr(image_path, force)
        first = getattr(psf_grid, "layers", [psf_grid])[0]
        lens = grid_lens(psf_grid) if lens is None else lens
        if lens is None:
            raise SolasError(
                f"ghosts: the PSF grid's lens {psf_grid.meta.get('lens')!r} cannot be read again with the grid's "
                "hash (a lens scaled in memory, or its file changed): give the lens (batch degrade --lens)"
            )
        if not any(s.coating for s in lens.surfaces):
            warnings.append(UNCOATED.format(name=lens.name))
        rows, cols, channels = image_size(image_path)
        fields = FrameFields(lens, first, cols, rows, spec.frame)  # a frame it cannot take refused before the grid
        grid = lens_ghosts(lens, first)
        about = {"lens": lens.name, "lens_hash": lens.hash, "paths": len(grid.paths),
                 "grid_options": grid.meta.get("options"), "warnings": warnings,
                 "depth": "sources taken at infinity: the depth map does not change their ghosts"
                 if depth is not None else None}  # fmt: skip
        return cls(grid, fields, channel_wavelengths(first, channels),
                   spec.ghost_threshold, about, lens)  # fmt: skip

    def starburst(self) -> tuple[np.ndarray, dict] | None:
        """The iris's starburst kernel on the frame's pixels (`psf.starburst.lens_starburst`) at the grid's reference
        wavelength (one kernel for every channel, as `render --ghosts` takes one), the pixel pitch the frame's at
        its centre; computed once per `FrameGhosts` (a batch's frames share it)."""
        if not hasattr(self, "_starburst"):
            from ..psf.starburst import lens_starburst

            per_mm = self.fields.pixel((0.0, 0.0))[1]  # pixels per mm on the axis
            self._starburst = lens_starburst(self.lens, self.wavelength_nm, 1e3 / per_mm)
        return self._starburst

    def add(self, image: np.ndarray, out: np.ndarray, meta: dict) -> dict[str, np.ndarray]:
        """Add the ghosts of `image`'s sources and the iris's starburst of the degraded image `out` to `out` (in
        place), record them in `meta["ghosts"]`; the flare label's layers (the stray light over the direct image
        less what it gave to the starburst's wings, as `render --ghosts` has them)."""
        planes = image[..., None] if image.ndim == 2 else image
        flare, about = frame_ghosts(planes, self.grid, self.fields, self.channels, self.threshold)
        from ..labelkinds import flare_layers
        from ..psf.starburst import spread

        direct = out[..., None] if out.ndim == 2 else out
        kept, starburst = direct.astype(np.float64), None
        if self.starburst() is not None:
            kernel, starburst = self.starburst()
            kept, brought = spread(direct, kernel)
            flare += brought
            given = direct.astype(np.float64).sum(axis=(0, 1)) * starburst["wings"]
            starburst = {**starburst, "light_in_frame": brought.sum(axis=(0, 1)).tolist(),
                         "light_given": given.tolist()}  # fmt: skip
        layers = flare_layers(kept, flare)
        direct[...] = (kept + flare).astype(out.dtype)
        meta["ghosts"] = {**self.about, **about, "starburst": starburst}
        return layers
