"""PSF grids over the field: one stack of PSFs per wavelength, stored as OpenEXR with the metadata
needed to use them without the lens, and a PNG mosaic for looking at them.

The lens is centred (every surface is rotationally symmetric about the axis), so the PSF of field
(−x, y) is the mirror image of that of (x, y), and that of (y, x) its transpose: each distinct
|field| pair is computed once (on an odd grid, symmetric about the chief ray) and mirrored.

Field grid convention: `ny`×`nx` nodes in image orientation, row 0 = top = largest y field angle,
column 0 = smallest x field angle. "centers" sampling puts the nodes at the centres of ny×nx equal
cells spanning ±field (the block centres of a tiled image); "edges" spans ±field including the ends.
The SOLAS paper's PSF maps are such grids (8×8 over the doublet's ±2°; see the `solas_mi` docstring).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import SolasError
from ..imageio import read_exr, write_exr, write_png
from ..optics.camera import pinhole_focal_mm
from ..optics.fields import ANGLE
from ..optics.lens import Lens
from ..options import parse_wxh
from . import base as S
from .methods import DEFAULT_METHOD, METHODS, check_method, compute
from .sensor import check_sensor_mm, default_sensor_mm, fields_for_points, node_mm

FIELD_SAMPLINGS = ("centers", "edges")
LAYOUTS = ("field", "sensor")  # nodes on field angles (tangents), or on sensor positions (`psf.sensor`)
MOSAIC_PX = 2048  # the preview mosaic is block-averaged to fit this (a 32×32 grid of 160 px: 64 px a PSF)
_FIELDS_PER_BATCH = 64


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
        """Read a grid written by `write`."""
        channels, meta = read_exr(path)
        if "grid" not in meta:
            raise SolasError(f"{path} is not a solas-mi PSF grid (no grid metadata)")
        ny, nx = meta["grid"]
        s = meta["size"]
        wl = [float(w) for w in meta["wavelengths_nm"]]
        stacks = []
        for w in wl:
            m = channels[f"psf_{w:g}nm"]
            stacks.append(m.reshape(ny, s, nx, s).transpose(0, 2, 1, 3))
        rest = {k: v for k, v in meta.items() if k not in ("pitch_um", "wavelengths_nm", "fields_deg", "chief_ray_mm")}
        return cls(np.stack(stacks), np.array(meta["fields_deg"]), np.array(meta["chief_ray_mm"]), tuple(wl),
                   float(meta["pitch_um"]), rest)

    def write_png(self, path: str) -> None:
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
        write_png(path, image)


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


def symmetry_classes(fields: np.ndarray, decimals: int = 12):
    """Fields (n, 2) reduced by the mirror and diagonal symmetries of a centred lens.

    Returns the canonical fields (m, 2) with x ≥ y ≥ 0, and for each input field the index of its
    canonical field, whether x and y are swapped, and the signs (n, 2) that map canonical to input."""
    ax = np.abs(fields)
    swap = ax[:, 1] > ax[:, 0]
    key = np.round(np.where(swap[:, None], ax[:, ::-1], ax), decimals)
    canon, which = np.unique(key, axis=0, return_inverse=True)
    sign = np.where(fields < 0, -1.0, 1.0)
    return canon, which.ravel(), swap, sign


def psf_grid(lens: Lens, grid: tuple[int, int] | str = (8, 8), wavelengths_nm=None,
             field_range_deg: tuple[float, float] | float | None = None, pitch_um: float = S.DEFAULT_PITCH_UM,
             size: int = S.DEFAULT_SIZE,
             method: str = DEFAULT_METHOD, normalization: str = "sum", pupil_samples: int = S.DEFAULT_PUPIL_SAMPLES,
             rays: int = S.DEFAULT_GEOMETRIC_RAYS, field_sampling: str = "centers", progress=None,
             auto_window: bool = False, layout: str = "field", sensor_mm: tuple[float, float] | None = None) -> PSFGrid:
    """PSFs on a field grid ("columns x rows" text or a (rows, columns) tuple) spanning
    ±field_range_deg (x, y) (default: the lens's field in both). meta["energy_in_window"] holds each
    PSF's fraction of its transmitted light inside the window and meta["warnings"] what looked
    doubtful; `auto_window` doubles `size` until every window holds `base.WINDOW_ENERGY_LIMIT`.

    layout "sensor" (`psf.sensor`) puts the nodes at the cell centres of a sensor_mm = (width, height)
    mm sensor instead (default: the square in the lens's image circle), each with the field whose chief
    ray lands there; meta["node_mm"] holds the nodes' image points and field_range_deg is unused."""
    ny, nx = parse_wxh(grid, "grid")
    S.check_grid(pitch_um, size)
    sampling = check_method(method, pupil_samples, rays)
    S.check_normalization(normalization)
    wl = tuple(float(w) for w in (wavelengths_nm if wavelengths_nm is not None else lens.wavelengths_nm))
    if not wl:
        raise SolasError("at least one wavelength is needed")
    for w in wl:
        lens.check_wavelength(w)
    if layout == "sensor":
        sensor_mm = default_sensor_mm(lens) if sensor_mm is None else check_sensor_mm(sensor_mm)
        nodes = node_mm(sensor_mm, ny, nx)
        fields = fields_for_points(lens, nodes, lens.primary_wavelength)
        hx = hy = 0.0
    elif layout == "field":
        if field_range_deg is None:
            field_range_deg = lens.field_deg
        hx, hy = ANGLE.check((field_range_deg, field_range_deg) if np.isscalar(field_range_deg) else field_range_deg)
        if hx < 0 or hy < 0:
            raise SolasError(f"field range ({hx:g}, {hy:g}) deg must be non-negative (half ranges)")
        fx = field_nodes(nx, hx, field_sampling)
        fy = field_nodes(ny, hy, field_sampling)[::-1]  # row 0 = top = largest y
        fields = np.stack(np.meshgrid(fx, fy), axis=-1)  # (ny, nx, 2)
    else:
        raise SolasError(f"grid layout {layout!r} must be one of {', '.join(LAYOUTS)}")
    flat = fields.reshape(-1, 2)
    n = len(flat)
    canon, which, swap, sign = symmetry_classes(flat)
    odd = 2 * (size // 2) + 1  # symmetric about the origin pixel, so mirrors stay on the grid
    # stored as the EXR's mosaics (wavelength, row, y, column, x), the layout `read` gives too, so that
    # writing needs no copy; `data` (wavelength, row, column, y, x) is a view of it
    data = np.zeros((len(wl), ny, size, nx, size), dtype=np.float32).transpose(0, 1, 3, 2, 4)
    chief = np.zeros((len(wl), n, 2))
    transmission = np.zeros((len(wl), n))
    energy = np.zeros((len(wl), n))
    vignetting: set[int] = set()
    doubts: list[str] = []
    start = time.perf_counter()
    for k, w in enumerate(wl):
        for a in range(0, len(canon), _FIELDS_PER_BATCH):
            b = min(len(canon), a + _FIELDS_PER_BATCH)
            psfs, cr, tr, vig, warned, centre_um = compute(lens, canon[a:b], np.full(b - a, w), pitch_um, odd, method,
                                                           pupil_samples, rays)
            vignetting.update(s for v in vig for s in v)
            doubts.extend(d for d in warned if d not in doubts)
            for c in range(a, b):
                for i in np.flatnonzero(which == c):
                    p = psfs[c - a]
                    xy = cr.image_xy[c - a] + (0.0 if centre_um is None else centre_um[c - a] * 1e-3)
                    if swap[i]:
                        p, xy = p[::-1, ::-1].T, xy[::-1]
                    if sign[i, 0] < 0:
                        p = p[:, ::-1]
                    if sign[i, 1] < 0:
                        p = p[::-1, :]
                    data[k, i // nx, i % nx] = S.normalize(p[:size, :size], normalization)
                    chief[k, i] = xy * sign[i]
                    transmission[k, i] = tr[c - a]
                    energy[k, i] = S.window_energy(p[:size, :size], pitch_um, tr[c - a])
            if progress is not None:
                progress(k * len(canon) + b, len(wl) * len(canon))
    lit = transmission > 0
    meta = S.describe(lens, method, normalization, {METHODS[method].sampling: sampling}, size)
    meta.update({"layout": layout, "reference_wavelength_nm": lens.primary_wavelength, "sensor_mm": list(sensor_mm),
                 "node_mm": nodes.tolist()}
                if layout == "sensor" else {"layout": layout, "field_sampling": field_sampling, "field_range_deg": [hx, hy]})
    meta.update({
        "grid_orientation": "grid row 0 = largest y field, column 0 = smallest x field",
        "transmission": transmission.reshape(len(wl), ny, nx).tolist(),
        "energy_in_window": energy.reshape(len(wl), ny, nx).tolist(),
        "vignetted_by_surfaces": sorted(vignetting),
        "warnings": [*doubts, *S.window_warnings(energy[lit], np.broadcast_to(flat, (len(wl), n, 2))[lit], size,
                                                  pitch_um)] + ([f"{int((~lit).sum())} of {lit.size} PSFs receive no "
                                                                 "light (every ray blocked): they are zero"]
                                                                if not lit.all() else []),
        "seconds": time.perf_counter() - start,
    })
    if layout == "sensor":
        meta["grid_orientation"] = "grid row 0 = top (largest y) of the sensor, column 0 = left"
    if hx > 0:  # the ideal image an input spanning ±hx horizontally stands for (`optics.camera`)
        meta.update(pinhole_focal_mm=pinhole_focal_mm(lens, hx), reference_wavelength_nm=lens.primary_wavelength)
    if auto_window and energy.min() < S.WINDOW_ENERGY_LIMIT and 2 * size <= S.MAX_SIZE:
        return psf_grid(lens, (ny, nx), wl, field_range_deg if layout == "sensor" else (hx, hy), pitch_um, 2 * size,
                        method, normalization, pupil_samples, rays, field_sampling, progress, auto_window=True,
                        layout=layout, sensor_mm=sensor_mm)
    return PSFGrid(data, fields, chief.reshape(len(wl), ny, nx, 2), wl,
                   float(pitch_um), meta)
