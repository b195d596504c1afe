"""PSF grids over the field: one stack of PSFs per wavelength, stored as OpenEXR with the metadata
needed to use them without the lens, and a PNG mosaic for looking at them.

The lens is centred, so each distinct |field| pair is computed once and mirrored (`nodes`).

Field grid convention: `ny`×`nx` nodes in image orientation, row 0 = top = largest y field angle,
column 0 = smallest x field angle. "centers" sampling puts the nodes at the centres of ny×nx equal
cells spanning ±field (the block centres of a tiled image); "edges" spans ±field including the ends.
The SOLAS paper's PSF maps are such grids (8×8 over the doublet's ±2°; see the `solas_mi` docstring).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import SolasError
from ..imageio import read_exr, write_exr
from ..optics.camera import pinhole_focal_mm
from ..optics.lens import Lens
from ..pages import small_pages
from . import base as S
from .methods import method_options
from .nodes import Nodes, compute_nodes
from .sensor import default_sensor_mm, fields_for_points, node_mm
from .spec import FIELD_SAMPLINGS, LAYOUTS, GridSpec
MOSAIC_PX = 2048  # the preview mosaic is block-averaged to fit this (a 32×32 grid of 160 px: 64 px a PSF)


@dataclass
class PSFGrid:
    """PSFs on a field grid: data[wavelength, row, column] is a size×size PSF (float32)."""

    data: np.ndarray  # (n_wavelengths, ny, nx, size, size)
    fields_deg: np.ndarray  # (ny, nx, 2)
    chief_ray_mm: np.ndarray  # (n_wavelengths, ny, nx, 2): image point at each PSF's origin pixel
    wavelengths_nm: tuple[float, ...]
    pitch_um: float
    meta: dict = field(default_factory=dict)

    @property
    def size(self) -> int:
        return self.data.shape[-1]

    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx) of the field grid."""
        return self.data.shape[1], self.data.shape[2]

    def mosaic(self, k: int) -> np.ndarray:
        """Wavelength k's PSFs tiled as one (ny·size, nx·size) image."""
        return tile(self.data[k])

    def write(self, path: str) -> None:
        """Write as OpenEXR: one mosaic channel per wavelength ("psf_531nm"), metadata in the header."""
        meta = dict(self.meta)
        meta.update({
            "pitch_um": self.pitch_um, "size": self.size, "grid": list(self.shape),
            "wavelengths_nm": list(self.wavelengths_nm), "fields_deg": self.fields_deg.tolist(),
            "chief_ray_mm": self.chief_ray_mm.tolist(),
        })
        channels = {f"psf_{w:g}nm": self.mosaic(k) for k, w in enumerate(self.wavelengths_nm)}
        if len(channels) != len(self.wavelengths_nm):
            raise SolasError(f"wavelengths {self.wavelengths_nm} nm are not distinct to 6 digits; channel names would collide")
        # PSF tails are float noise that compression cannot shrink; stored as uncompressed float32, the
        # fastest (measured, 32×32×3 grid of 160 px, 315 MB: 0.17 s; ZIPS 3.8 s for 1 % less, PIZ 3.9 s for
        # 14 % less; half floats 157 MB but 4.9 s, numpy's float16 conversion of the 88 % of the values
        # below half's normal range being slow, and a PSF's sum off by up to 2e-5)
        write_exr(path, channels, meta, compress=False)

    @classmethod
    def read(cls, path: str) -> "PSFGrid":
        """Read a grid written by `write`; SolasError naming the file and the field for damaged metadata."""
        channels, meta = read_exr(path)
        if isinstance(meta, dict) and "layers" in meta:
            raise SolasError(f"{path} is a PSF grid over object distance (`psf.depth.DepthGrid`): read it with "
                             "psf.depth.read_grid, use it with a depth map (degrade --depth)")
        return cls.from_channels(path, channels, meta)

    @classmethod
    def from_channels(cls, path, channels: dict, meta) -> "PSFGrid":
        """The grid of an EXR file's channels and metadata (`read`); `path` names it in errors."""
        if not isinstance(meta, dict) or "grid" not in meta:
            raise SolasError(f"{path} is not a solas-mi PSF grid (no grid metadata)")
        ny, nx, s, wl = check_grid_meta(path, meta)
        stacks = []
        for w in wl:
            m = channels.get(f"psf_{w:g}nm")
            if m is None or m.shape != (ny * s, nx * s):
                raise SolasError(f"PSF grid {path}: channel psf_{w:g}nm is " + ("missing" if m is None else
                                 f"{m.shape[1]}x{m.shape[0]} px") + f"; the metadata need {nx * s}x{ny * s} px")
            stacks.append(m.reshape(ny, s, nx, s).transpose(0, 2, 1, 3))
        rest = {k: v for k, v in meta.items() if k not in ("pitch_um", "wavelengths_nm", "fields_deg", "chief_ray_mm")}
        return cls(np.stack(stacks), _meta_array(path, meta, "fields_deg", (ny, nx, 2)),
                   _meta_array(path, meta, "chief_ray_mm", (len(wl), ny, nx, 2)), wl, float(meta["pitch_um"]), rest)

    def write_png(self, path: str) -> None:
        """The mosaic for viewing (`preview`) as a PNG plot with axes in field degrees (`psf.preview`)."""
        from .preview import plot_grid

        plot_grid(self, self.preview(), path)

    def preview(self) -> np.ndarray:
        """A mosaic for viewing, at most MOSAIC_PX wide and high: each PSF block-averaged down to fit
        and scaled to its peak; three wavelengths → R, G, B (longest red)."""
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
    if not (_whole(size) and 2 <= size <= S.MAX_SIZE):
        raise bad("size", f"an integer from 2 to {S.MAX_SIZE} (pixels)")
    wl = meta.get("wavelengths_nm")
    if not (isinstance(wl, list) and wl and all(_real(w) and w > 0 for w in wl) and len(set(wl)) == len(wl)):
        raise bad("wavelengths_nm", "a list of distinct positive numbers (nm)")
    for key in ("pitch_um", *(k for k in ("pinhole_focal_mm", "reference_wavelength_nm") if k in meta)):
        if not (_real(meta.get(key)) and meta[key] > 0):
            raise bad(key, "a positive number")
    if meta.get("normalization", "sum") not in S.NORMALIZATIONS:
        raise bad("normalization", f"one of {', '.join(S.NORMALIZATIONS)}")
    if meta.get("layout", "field") not in LAYOUTS:
        raise bad("layout", f"one of {', '.join(LAYOUTS)}")
    ny, nx = grid
    if meta.get("layout") == "sensor":
        _meta_array(path, meta, "sensor_mm", (2,), positive=True)
        _meta_array(path, meta, "node_mm", (ny, nx, 2))
        if "reference_wavelength_nm" not in meta:
            raise bad("reference_wavelength_nm", "a positive number")
    elif "field_range_deg" in meta:
        if (_meta_array(path, meta, "field_range_deg", (2,)) < 0).any():
            raise bad("field_range_deg", "two non-negative half ranges (deg)")
    for key in ("transmission", "energy_in_window"):
        if key in meta:
            _meta_array(path, meta, key, (len(wl), ny, nx))
    return ny, nx, size, tuple(float(w) for w in wl)


def _whole(v) -> bool:
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
        raise _bad_field(path, meta, key, f"{'x'.join(map(str, shape))} finite{' positive' if positive else ''} "
                                          "numbers (the shape the fields grid, size and wavelengths_nm give)")
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


def field_nodes(n: int, half_range: float, sampling: str) -> np.ndarray:
    """n field angles (degrees) spanning ±half_range, increasing."""
    if sampling == "centers":
        return -half_range + (np.arange(n) + 0.5) * (2.0 * half_range / n)
    if sampling == "edges":
        return np.linspace(-half_range, half_range, n) if n > 1 else np.zeros(1)
    raise SolasError(f"field sampling {sampling!r} must be one of {', '.join(FIELD_SAMPLINGS)}")


def psf_grid(lens: Lens, spec: GridSpec | None = None, progress=None, **options) -> PSFGrid:
    """PSFs on a field grid as `spec` says (a `GridSpec`; or its fields as keywords, e.g.
    `psf_grid(lens, grid=(24, 32), wavelengths_nm=[656, 531, 486])`, which also override a given
    spec's). `progress(done, total)` is called after each batch of PSFs, counting the grid's PSFs
    (nodes × wavelengths, mirrored ones included).

    layout "field": nodes spanning ±field_range_deg (x, y) (default: the lens's field in both);
    layout "sensor" (`psf.sensor`): nodes at the cell centres of a sensor_mm = (width, height) mm sensor
    (default: the square in the lens's image circle), each with the field whose chief ray lands there;
    meta["node_mm"] holds the nodes' image points. meta["energy_in_window"] holds each PSF's fraction of
    its transmitted light inside the window and meta["warnings"] what looked doubtful; `auto_window`
    doubles the size until every window holds `base.WINDOW_ENERGY_LIMIT`."""
    S.check_lens(lens)
    if spec is not None and not isinstance(spec, GridSpec):
        raise SolasError(f"spec {spec!r} must be a GridSpec (or give its options as keywords)")
    spec = GridSpec(**options) if spec is None else replace(spec, **options)
    if spec.distances_m is not None:
        raise SolasError(f"distances {list(spec.distances_m)} m make a grid over object distance: use "
                         "psf.depth.depth_grid (psf_grid is for the lens file's object distance)")
    wl = S.check_wavelengths(lens, spec.wavelengths_nm if spec.wavelengths_nm is not None else lens.wavelengths_nm)
    fields, placement = grid_fields(lens, spec)
    size = spec.size
    while True:  # auto_window: the whole grid again at twice the size until every window holds enough
        start = time.perf_counter()
        with small_pages():
            nodes = compute_nodes(lens, spec, wl, fields.reshape(-1, 2), size, progress)
        if not (spec.auto_window and nodes.energy.min() < S.WINDOW_ENERGY_LIMIT and 2 * size <= S.MAX_SIZE):
            break
        size *= 2
    meta = grid_meta(lens, spec, wl, fields, nodes, size, placement)
    meta["seconds"] = time.perf_counter() - start
    ny, nx = spec.grid
    return PSFGrid(nodes.data, fields, nodes.chief.reshape(len(wl), ny, nx, 2), wl, spec.pitch_um, meta)


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
    placement = {"layout": "field", "field_sampling": spec.field_sampling, "field_range_deg": [hx, hy],
                 "grid_orientation": "grid row 0 = largest y field, column 0 = smallest x field"}
    if hx > 0:  # the ideal image an input spanning ±hx horizontally stands for (`optics.camera`)
        placement.update(pinhole_focal_mm=pinhole_focal_mm(lens, hx), reference_wavelength_nm=lens.primary_wavelength)
    return np.stack(np.meshgrid(fx, fy), axis=-1), placement


def grid_meta(lens: Lens, spec: GridSpec, wl: tuple[float, ...], fields: np.ndarray, nodes: Nodes, size: int,
              placement: dict) -> dict:
    """The grid's metadata: the lens, method and sampling (`base.describe`), the spec, the nodes'
    placement, transmission, window energy and warnings."""
    ny, nx = spec.grid
    n = ny * nx
    lit = nodes.transmission > 0
    meta = S.describe(lens, spec.method, spec.normalization, method_options(spec.method, spec.sampling_options()), size)
    meta.update(placement)
    dark = [] if lit.all() else [f"{int((~lit).sum())} of {lit.size} PSFs receive no light (every ray blocked): "
                                 "they are zero"]
    meta.update({
        "grid_spec": spec.canonical(),
        "transmission": nodes.transmission.reshape(len(wl), ny, nx).tolist(),
        "energy_in_window": nodes.energy.reshape(len(wl), ny, nx).tolist(),
        "vignetted_by_surfaces": list(nodes.vignetting),
        "warnings": [*nodes.doubts, *S.window_warnings(nodes.energy[lit], np.broadcast_to(
            fields.reshape(-1, 2), (len(wl), n, 2))[lit], size, spec.pitch_um), *dark],
    })
    return meta
