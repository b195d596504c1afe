"""`PSFGrid`, the PSFs of a grid over the field (one stack per wavelength), and its file: OpenEXR, one
mosaic channel per wavelength, with the metadata needed to use it without the lens (`check_grid_meta`
checks every field a user reads); a PNG mosaic for looking at it. `grid.psf_grid` computes one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TypeGuard

import numpy as np

from ..errors import SolasError
from ..imageio import read_exr, write_exr
from . import base
from .spec import LAYOUTS

MOSAIC_PX = 2048  # the preview mosaic is block-averaged to fit this (a 32×32 grid of 160 px: 64 px a PSF)


@dataclass
class PSFGrid:
    """PSFs on a field grid, one stack per wavelength, as `psf_grid` computes them.

    The nodes are in image orientation: row 0 the largest y field, column 0 the smallest x (the field
    grid convention: `grid`).

    Parameters
    ----------
    data : numpy.ndarray
        (wavelengths, rows, columns, size, size) float32: data[k, i, j] is a PSF (`psf.base`'s convention).
    fields_deg : numpy.ndarray
        (rows, columns, 2): each node's field, (x, y) degrees.
    chief_ray_mm : numpy.ndarray
        (wavelengths, rows, columns, 2): the image point (mm) at each PSF's centre pixel.
    wavelengths_nm : tuple of float
        The wavelengths (nm).
    pitch_um : float
        The PSFs' pixel pitch on the image plane (µm).
    meta : dict, optional
        The lens, the grid's options ("grid_spec"), transmission, each window's share of its light
        ("energy_in_window"), warnings.
    """

    data: np.ndarray
    fields_deg: np.ndarray
    chief_ray_mm: np.ndarray
    wavelengths_nm: tuple[float, ...]
    pitch_um: float
    meta: dict = field(default_factory=dict)

    @property
    def size(self) -> int:
        """Pixels per side of each PSF."""
        return self.data.shape[-1]

    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx) of the field grid."""
        return self.data.shape[1], self.data.shape[2]

    def mosaic(self, k: int) -> np.ndarray:
        """One wavelength's PSFs tiled as one image.

        Parameters
        ----------
        k : int
            The wavelength's index in `wavelengths_nm`.

        Returns
        -------
        numpy.ndarray
            (rows·size, columns·size).
        """
        return tile(self.data[k])

    def write(self, path: str) -> None:
        """Write the grid as OpenEXR, whole or not at all: one mosaic channel per wavelength ("psf_531nm"),
        the metadata in the header.

        Parameters
        ----------
        path : str
            The file.

        Raises
        ------
        SolasError
            For wavelengths that are not distinct to 6 digits (their channel names would collide).
        """
        meta = dict(self.meta)
        meta.update(
            {
                "pitch_um": self.pitch_um,
                "size": self.size,
                "grid": list(self.shape),
                "wavelengths_nm": list(self.wavelengths_nm),
                "fields_deg": self.fields_deg.tolist(),
                "chief_ray_mm": self.chief_ray_mm.tolist(),
            }
        )
        channels = {f"psf_{w:g}nm": self.mosaic(k) for k, w in enumerate(self.wavelengths_nm)}
        if len(channels) != len(self.wavelengths_nm):
            raise SolasError(
                f"wavelengths {self.wavelengths_nm} nm are not distinct to 6 digits; channel names would collide"
            )
        # PSF tails are float noise that compression cannot shrink; stored as uncompressed float32, the
        # fastest (measured, 32×32×3 grid of 160 px, 315 MB: 0.17 s; ZIPS 3.8 s for 1 % less, PIZ 3.9 s for
        # 14 % less; half floats 157 MB but 4.9 s, numpy's float16 conversion of the 88 % of the values
        # below half's normal range being slow, and a PSF's sum off by up to 2e-5)
        write_exr(path, channels, meta, compress=False)

    @classmethod
    def read(cls, path: str) -> PSFGrid:
        """Read a grid that `write` wrote (``solas-mi psf-grid``'s output).

        Parameters
        ----------
        path : str
            The EXR file.

        Returns
        -------
        PSFGrid
            The grid.

        Raises
        ------
        SolasError
            For a file that is not a PSF grid, a grid over object distance (`psf.depth.read_grid` reads
            those), or damaged metadata (naming the file and the field).

        Examples
        --------
        >>> from solas_mi import Lens
        >>> from solas_mi.psf import PSFGrid, psf_grid
        >>> psf_grid(Lens.load("solas-doublet"), grid=(2, 2), size=32).write("grid.exr")
        >>> PSFGrid.read("grid.exr").shape
        (2, 2)
        """
        channels, meta = read_exr(path)
        if isinstance(meta, dict) and "layers" in meta:
            raise SolasError(
                f"{path} is a PSF grid over object distance (`psf.depth.DepthGrid`): read it with "
                "psf.depth.read_grid, use it with a depth map (degrade --depth)"
            )
        return cls.from_channels(path, channels, meta)

    @classmethod
    def from_channels(cls, path, channels: dict, meta) -> PSFGrid:
        """The grid of an EXR file's channels and metadata (`read`).

        Parameters
        ----------
        path : str
            The file, named in errors.
        channels : dict
            Channel name → 2-D array.
        meta : dict
            The file's solas-mi metadata.

        Returns
        -------
        PSFGrid
            The grid.

        Raises
        ------
        SolasError
            For metadata of no grid, or a channel missing or of the wrong size.
        """
        if not isinstance(meta, dict) or "grid" not in meta:
            raise SolasError(f"{path} is not a solas-mi PSF grid (no grid metadata)")
        ny, nx, s, wl = check_grid_meta(path, meta)
        stacks = []
        for w in wl:
            m = channels.get(f"psf_{w:g}nm")
            if m is None or m.shape != (ny * s, nx * s):
                raise SolasError(
                    f"PSF grid {path}: channel psf_{w:g}nm is "
                    + ("missing" if m is None else f"{m.shape[1]}x{m.shape[0]} px")
                    + f"; the metadata need {nx * s}x{ny * s} px"
                )
            stacks.append(m.reshape(ny, s, nx, s).transpose(0, 2, 1, 3))
        rest = {k: v for k, v in meta.items() if k not in ("pitch_um", "wavelengths_nm", "fields_deg", "chief_ray_mm")}
        return cls(
            np.stack(stacks),
            _meta_array(path, meta, "fields_deg", (ny, nx, 2)),
            _meta_array(path, meta, "chief_ray_mm", (len(wl), ny, nx, 2)),
            wl,
            float(meta["pitch_um"]),
            rest,
        )

    def write_png(self, path: str) -> None:
        """Write the mosaic for viewing (`preview`) as a PNG plot, axes in field degrees (`psf.preview`).

        Parameters
        ----------
        path : str
            The file.
        """
        from .preview import plot_grid

        plot_grid(self, self.preview(), path)

    def preview(self) -> np.ndarray:
        """A mosaic for viewing, at most `MOSAIC_PX` wide and high.

        Returns
        -------
        numpy.ndarray
            Each PSF block-averaged down to fit and scaled to its peak; three wavelengths as R, G, B
            (longest red), else their mean.
        """
        ny, nx = self.shape
        step = max(1, -(-max(ny, nx) * self.size // MOSAIC_PX))
        s = self.size // step
        data = self.data[..., : s * step, : s * step].reshape(*self.data.shape[:3], s, step, s, step).mean(axis=(4, 6))
        peak = np.maximum(data.max(axis=(-2, -1), keepdims=True), np.float32(1e-30))
        mosaics = [tile(stack) for stack in data / peak]
        if len(mosaics) == 3:
            order = np.argsort(self.wavelengths_nm)[::-1]
            image = np.stack([mosaics[i] for i in order], axis=-1)
        else:
            image = np.mean(mosaics, axis=0)
        return image


def check_grid_meta(path, meta: dict) -> tuple[int, int, int, tuple[float, ...]]:
    """Every metadata field a grid's users read, checked: (rows, columns, size, wavelengths)."""

    def bad(key: str, want: str):
        return _bad_field(path, meta, key, want)

    grid, size = meta.get("grid"), meta.get("size")
    if not (isinstance(grid, list) and len(grid) == 2 and all(_whole(v) and v >= 1 for v in grid)):
        raise bad("grid", "[rows, columns], positive integers")
    if not (_whole(size) and 2 <= size <= base.MAX_SIZE):
        raise bad("size", f"an integer from 2 to {base.MAX_SIZE} (pixels)")
    wl = meta.get("wavelengths_nm")
    if not (isinstance(wl, list) and wl and all(_real(w) and w > 0 for w in wl) and len(set(wl)) == len(wl)):
        raise bad("wavelengths_nm", "a list of distinct positive numbers (nm)")
    for key in ("pitch_um", *(k for k in ("pinhole_focal_mm", "reference_wavelength_nm") if k in meta)):
        if not (_real(meta.get(key)) and meta[key] > 0):
            raise bad(key, "a positive number")
    if meta.get("normalization", "sum") not in base.NORMALIZATIONS:
        raise bad("normalization", f"one of {', '.join(base.NORMALIZATIONS)}")
    if meta.get("layout", "field") not in LAYOUTS:
        raise bad("layout", f"one of {', '.join(LAYOUTS)}")
    ny, nx = grid
    if meta.get("layout") == "sensor":
        _meta_array(path, meta, "sensor_mm", (2,), positive=True)
        _meta_array(path, meta, "node_mm", (ny, nx, 2))
        if "reference_wavelength_nm" not in meta:
            raise bad("reference_wavelength_nm", "a positive number")
    elif "field_range_deg" in meta and (_meta_array(path, meta, "field_range_deg", (2,)) < 0).any():
        raise bad("field_range_deg", "two non-negative half ranges (deg)")
    for key in ("transmission", "energy_in_window"):
        if key in meta:
            _meta_array(path, meta, key, (len(wl), ny, nx))
    return ny, nx, size, tuple(float(w) for w in wl)


def _whole(v) -> TypeGuard[int]:
    return isinstance(v, int) and not isinstance(v, bool)


def _real(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _meta_array(path, meta: dict, key: str, shape: tuple[int, ...], positive: bool = False) -> np.ndarray:
    """meta[key] as a float64 array of `shape`, finite (and positive); SolasError naming file and field."""
    try:
        a = np.asarray(meta[key], dtype=np.float64)
        ok = a.shape == shape and bool(np.isfinite(a).all()) and (not positive or bool((a > 0).all()))
    except (KeyError, TypeError, ValueError):
        ok = False
    if not ok:
        raise _bad_field(
            path,
            meta,
            key,
            f"{'x'.join(map(str, shape))} finite{' positive' if positive else ''} "
            "numbers (the shape the fields grid, size and wavelengths_nm give)",
        )
    return a


def _bad_field(path, meta: dict, key: str, want: str) -> SolasError:
    """The error for a damaged metadata field: the file, the field, the start of its value, what is due."""
    value = str(meta[key]) if key in meta else "(missing)"
    shown = value if len(value) <= 60 else value[:57] + "..."
    return SolasError(f"PSF grid {path}: metadata field {key} = {shown} must be {want}")


def tile(stack: np.ndarray) -> np.ndarray:
    """(ny, nx, s, s) PSFs tiled as one (ny·s, nx·s) image."""
    ny, nx, s, _ = stack.shape
    return stack.transpose(0, 2, 1, 3).reshape(ny * s, nx * s)
