"""PSF grids over field and object distance: one field grid (`grid.PSFGrid`) per object distance,
the lens focused as its file says (or as `optics.focus.focused` set it) at every node.

A node at distance d is the lens with its object d in front of surface 1 and the SAME image plane
(`replace(lens, object_distance=d)`: the last surface's thickness is kept), so each node's PSFs are
those of an object at d seen by the focused camera: sharp at the focus distance, defocused elsewhere.
Nodes are sorted far to near; defocus is linear in 1/distance, so a depth map is interpolated
between nodes in 1/distance (`inverse`), and `spec.inverse_spaced` spaces them evenly there.

Every node's grid is placed on the image by one camera: the pinhole focal length of the farthest
node (`pinhole_focal_mm`); each node keeps its own chief rays, so the image shift between distances
(the entrance pupil is not the pinhole) is carried as part of each node's chief-ray offset.

File: one OpenEXR with each node's mosaics as channels "d{i}.psf_{w}nm" and the metadata of each
node's grid in meta["layers"], the distances in meta["distances_m"] ("inf" for infinity).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..errors import SolasError
from ..imageio import read_exr, write_exr
from .grid import psf_grid
from .grid_file import PSFGrid, check_grid_meta
from .spec import GridSpec


@dataclass
class DepthGrid:
    """PSF field grids at object distances `distances_m` (far to near; math.inf: infinity)."""

    layers: list[PSFGrid]
    distances_m: tuple[float, ...]
    meta: dict

    @property
    def inverse(self) -> np.ndarray:
        """1/distance (1/m) of the nodes, increasing (far to near)."""
        return np.array([0.0 if math.isinf(d) else 1.0 / d for d in self.distances_m])

    @property
    def wavelengths_nm(self) -> tuple[float, ...]:
        return self.layers[0].wavelengths_nm

    @property
    def nbytes(self) -> int:
        return sum(g.data.nbytes for g in self.layers)

    def subset(self, indices: list[int]) -> DepthGrid:
        """The grid of the nodes `indices` only (far to near), sharing their PSFs."""
        if (
            not indices
            or sorted(set(indices)) != list(indices)
            or not 0 <= indices[0] <= indices[-1] < len(self.layers)
        ):
            raise SolasError(f"node indices {indices!r} must be increasing indices of the {len(self.layers)} nodes")
        return DepthGrid([self.layers[i] for i in indices], tuple(self.distances_m[i] for i in indices), self.meta)

    def write_png(self, path: str) -> None:
        """The nearest node's mosaic for viewing (`PSFGrid.write_png`): the most defocused one when the
        lens is focused far."""
        self.layers[-1].write_png(path)

    def write(self, path: str) -> None:
        channels, layers = {}, []
        for i, g in enumerate(self.layers):
            channels.update({f"d{i}.psf_{w:g}nm": g.mosaic(k) for k, w in enumerate(g.wavelengths_nm)})
            layers.append(
                {
                    **g.meta,
                    "pitch_um": g.pitch_um,
                    "size": g.size,
                    "grid": list(g.shape),
                    "wavelengths_nm": list(g.wavelengths_nm),
                    "fields_deg": g.fields_deg.tolist(),
                    "chief_ray_mm": g.chief_ray_mm.tolist(),
                }
            )
        meta = {**self.meta, "distances_m": _json_distances(self.distances_m), "layers": layers}
        write_exr(path, channels, meta, compress=False)

    @classmethod
    def read(cls, path: str, channels: dict | None = None, meta: dict | None = None) -> DepthGrid:
        """Read a grid written by `write` (or one already read: its channels and metadata)."""
        if channels is None:
            channels, meta = read_exr(path)
        layers_meta, distances = meta.get("layers"), meta.get("distances_m")
        if not (
            isinstance(layers_meta, list)
            and isinstance(distances, list)
            and layers_meta
            and len(layers_meta) == len(distances)
        ):
            raise SolasError(
                f"PSF grid {path}: metadata fields layers and distances_m must be lists of one "
                "entry per object distance"
            )
        layers = []
        for i, m in enumerate(layers_meta):
            check_grid_meta(path, m)
            prefix = f"d{i}."
            layers.append(
                PSFGrid.from_channels(
                    path, {k[len(prefix) :]: v for k, v in channels.items() if k.startswith(prefix)}, m
                )
            )
        rest = {k: v for k, v in meta.items() if k not in ("layers", "distances_m")}
        return cls(layers, _distances(path, distances), rest)


def _json_distances(distances) -> list:
    return [d if math.isfinite(d) else "inf" for d in distances]


def _distances(path, values: list) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        out = ()
    if not out or any(math.isnan(d) or d <= 0 for d in out) or list(out) != sorted(set(out), reverse=True):
        raise SolasError(
            f"PSF grid {path}: metadata field distances_m = {values!r} must be distinct positive "
            "distances (m), far to near"
        )
    return out


def depth_grid(
    lens, spec: GridSpec, progress=None, camera_focal_mm: float | None = None, viewpoint_mm: float | None = None
) -> DepthGrid:
    """The field grid of `spec` at each of its object distances (`spec.distances_m`, m), the lens's
    image plane kept. `progress(done, total)` counts PSFs over all distances. `camera_focal_mm`: the
    pinhole focal length that places every node on the image (default: the farthest node's); e.g.
    that of the lens focused at infinity, when the frames' sensor pitch was set for it and the lens
    has been refocused since (its change of magnification then comes in as chief-ray offsets).
    `viewpoint_mm`: where the frame's pinhole sat, mm behind surface 1's vertex along the axis (None:
    at the lens's entrance pupil, where a real camera's projection centre is); elsewhere, a node's
    field is the direction of its object point as seen from there (`from_viewpoint`): the parallax
    between the two viewpoints, which grows as objects come nearer, is then carried by the nodes."""
    if spec.distances_m is None:
        raise SolasError("a grid over object distance needs distances (GridSpec.distances_m / --distances-m)")
    start = time.perf_counter()
    one = replace(spec, distances_m=None)
    layers: list[PSFGrid] = []
    n = len(spec.distances_m)
    for i, d in enumerate(spec.distances_m):
        step = None if progress is None else (lambda done, total, i=i: progress(i * total + done, n * total))
        layers.append(psf_grid(at_distance(lens, d), one, progress=step))
    focal = layers[0].meta.get("pinhole_focal_mm") if camera_focal_mm is None else float(camera_focal_mm)
    for g in layers:  # one camera for every node
        if focal is not None and focal != g.meta["pinhole_focal_mm"]:
            g.meta["pinhole_focal_mm_own"] = g.meta["pinhole_focal_mm"]
            g.meta["pinhole_focal_mm"] = focal
    if viewpoint_mm is not None:
        for d, g in zip(spec.distances_m, layers):
            from_viewpoint(lens, g, d, float(viewpoint_mm))
    warnings = [f"at {d:g} m: {w}" for d, g in zip(spec.distances_m, layers) for w in g.meta["warnings"]]
    meta = {
        "lens": lens.name,
        "lens_hash": lens.hash,
        "grid_spec": spec.canonical(),
        "warnings": warnings,
        "focus": "the lens's image plane as its file says at every distance",
        "seconds": time.perf_counter() - start,
    }
    return DepthGrid(layers, spec.distances_m, meta)


def from_viewpoint(lens, grid: PSFGrid, distance_m: float, viewpoint_mm: float) -> None:
    """The fields of `grid` (objects `distance_m` in front of surface 1, fields seen from the entrance
    pupil) turned into the directions seen from `viewpoint_mm` behind surface 1:
    tan θ' = tan θ · (d + z_ep) / (d + viewpoint); and the light each frame pixel sends through the lens
    scaled by ((d + viewpoint)/(d + z_ep))² (meta["flux_scale"], applied by `convolution.kernels.psf_scale`)."""
    if math.isinf(distance_m):
        return
    from ..optics.paraxial import paraxial

    d = 1e3 * distance_m
    factor = (d + paraxial(lens).entrance_pupil_z_mm) / (d + viewpoint_mm)
    grid.fields_deg = np.degrees(np.arctan(np.tan(np.radians(grid.fields_deg)) * factor))
    grid.meta.update(
        viewpoint_mm=viewpoint_mm,
        flux_scale=factor**-2,
        fields="directions seen from the viewpoint, viewpoint_mm behind surface 1 (fields_deg); the "
        "PSFs are those of the same object points; flux_scale: the light the lens collects from what "
        "one frame pixel sees, against an object at infinity: the pixel's patch grows as (d + "
        "viewpoint)², the pupil's solid angle falls as 1/(d + entrance pupil)²",
    )


def at_distance(lens, distance_m: float):
    """`lens` with its object `distance_m` (m) in front of surface 1, its image plane unchanged."""
    if math.isinf(distance_m):
        return replace(lens, object_distance=math.inf)
    from ..optics.paraxial import paraxial

    efl = paraxial(lens).efl_mm
    if not 1e3 * distance_m > efl:
        raise SolasError(f"object distance {distance_m:g} m is not beyond the lens's focal length {efl:.4g} mm")
    return replace(lens, object_distance=1e3 * distance_m)


def make_grid(lens, spec: GridSpec, progress=None) -> PSFGrid | DepthGrid:
    """The grid `spec` describes: over field (`psf_grid`), or over field and distance (`depth_grid`)."""
    return psf_grid(lens, spec, progress=progress) if spec.distances_m is None else depth_grid(lens, spec, progress)


def read_grid(path: str) -> PSFGrid | DepthGrid:
    """A grid file of either kind."""
    channels, meta = read_exr(path)
    if isinstance(meta, dict) and "layers" in meta:
        return DepthGrid.read(path, channels, meta)
    return PSFGrid.from_channels(path, channels, meta)
