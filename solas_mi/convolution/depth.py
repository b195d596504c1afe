"""Depth-aware convolution: an RGB-D frame degraded with PSFs interpolated in field and in 1/distance
(`psf.depth.DepthGrid`), depth edges handled by layered compositing.

Layers. With the grid's nodes at u_k = 1/d_k (far to near, u increasing) and the pixel's u = 1/depth,
hat weights in u split each pixel's light between its two neighbouring nodes (clamped beyond the
outermost ones): w_k(p), Σ_k w_k = 1. Layer k is the image weighted by w_k, convolved with node k's
field grid by `interp` (PSFs interpolated bilinearly in field): so every pixel's PSF is interpolated
in field and, linearly, in 1/distance, where defocus is linear. A plane at one node's distance gives
exactly that node's single-distance `interp` result.

Occlusion ("layered", the default): the layers are composited far to near. Slab k holds the pixels
with u_k ≤ u < u_{k+1} (the last one everything nearer): each of them is nearer than all the light of
layers 0 … k−1 (which comes from pixels with u < u_k), so before layer k's light is added, the light
gathered so far is multiplied by 1 − C_k, C_k the slab's coverage blurred by node k's PSFs (kernels of
unit sum, the middle wavelength's for every channel; slabs are disjoint, so coverages add): a
defocused near object hides the background behind its blur instead of being added onto it. Light of
a pixel split between layers is not dimmed by its own slab (it is not nearer than itself), so a
plane at any one depth comes out as with the interpolated PSF alone. What layering cannot know is
the background hidden behind a near object: where the background is blurred more than the near
object (a lens focused near), the background's blur is missing its hidden part at the edge (dark by
up to half the background there). "none": the layers are added, no occlusion (each pixel's light
spreads through everything nearer), for comparison.

Depth: metres from the camera along the optical axis (z), +inf for the sky; a pixel nearer than the
nearest node takes its PSFs (and farther than the farthest, the farthest's), counted in the metadata.
Only the tiles of a layer that hold light are convolved (`interp`): a layer's cost is that of the part
of the frame it covers.
"""
from __future__ import annotations

import time

import numpy as np

from ..blas import single_threaded_blas
from ..errors import SolasError
from ..imageio import check_finite
from . import interp
from .kernels import channel_wavelengths, check_boundary, check_kernel, layout

OCCLUSIONS = ("filled", "layered", "none")
SUMMARY = "PSFs interpolated in field and in 1/distance from a depth map, composited far to near"


def check_depth(depth: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The depth map (m) as float64 (H, W): positive, +inf allowed (sky), no NaN, the image's size."""
    d = np.asarray(depth, dtype=np.float64)
    if d.ndim == 3 and d.shape[-1] == 1:
        d = d[..., 0]
    if d.shape != tuple(shape):
        raise SolasError(f"depth map of shape {d.shape} must be the image's {shape[1]}x{shape[0]} pixels, one channel")
    bad = np.isnan(d) | ~(d > 0)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise SolasError(f"depth map: {int(bad.sum())} pixel(s) are not a positive distance in metres (first at row "
                         f"{r}, column {c}: {d[r, c]!r}); allowed: positive values, inf for the sky")
    return d


def layer_weights(inverse: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hat weights (L, H, W) in 1/distance of each node, clamped at the ends, and each pixel's slab
    index (H, W): k where nodes[k] ≤ u < nodes[k+1] (0 below the first node, L−1 from the last on)."""
    eye = np.eye(len(nodes))
    w = np.stack([np.interp(inverse, nodes, e) for e in eye]) if len(nodes) > 1 else np.ones((1, *inverse.shape))
    slab = np.clip(np.searchsorted(nodes, inverse, side="right") - 1, 0, len(nodes) - 1)
    return w, slab


def degrade_depth(image: np.ndarray, depth_m: np.ndarray, grid, boundary: str = "edge", *,
                  occlusion: str = "filled", dtype=np.float32, meta: dict | None = None,
                  progress=None, frame=None) -> np.ndarray:
    """The linear image (H, W) or (H, W, C) with its depth map (H, W, metres) seen through the lens of
    `grid` (a `psf.depth.DepthGrid`): `interp` per layer, composited as `occlusion` says; `frame`: the
    frame's camera (`convolution.methods.degrade`)."""
    from ..psf.depth import DepthGrid

    if not isinstance(grid, DepthGrid):
        raise SolasError(f"grid {type(grid).__name__} must be a PSF grid over object distance (psf.depth.DepthGrid)")
    if occlusion not in OCCLUSIONS:
        raise SolasError(f"occlusion {occlusion!r} must be one of {', '.join(OCCLUSIONS)}")
    check_boundary(boundary)
    image = np.asarray(image)
    if image.ndim not in (2, 3) or image.size == 0 or not np.issubdtype(image.dtype, np.number):
        raise SolasError(f"image of shape {image.shape} must be a non-empty H×W or H×W×C array of numbers")
    planes = check_finite(image[..., None] if image.ndim == 2 else image, "image")
    height, width, nchan = planes.shape
    depth = check_depth(depth_m, (height, width))
    wavelengths = channel_wavelengths(grid.layers[0], nchan)
    lays = [layout(g, width, height, frame) for g in grid.layers]
    radius = max(check_kernel(g, lay) for g, lay in zip(grid.layers, lays))
    nodes = grid.inverse
    weights, slab = layer_weights(np.where(np.isinf(depth), 0.0, 1.0 / depth), nodes)
    start = time.perf_counter()
    with single_threaded_blas():
        cover = coverages(grid, lays, slab, boundary, dtype) if occlusion != "none" else {}
        fills = fill_plans(weights, slab, radius) if occlusion == "filled" else {}
        out = np.empty(planes.shape, dtype=dtype)
        for c, k in enumerate(wavelengths):
            out[..., c] = composite(planes[..., c], weights, fills, cover, grid, lays, k, boundary, dtype)
            if progress is not None:
                progress(c + 1, nchan)
    if meta is not None:
        meta.update(depth_meta(grid, depth, weights, occlusion, boundary, time.perf_counter() - start))
        meta.update({"camera": lays[0].camera.meta(), "kernel_size_px": 2 * radius + 1,
                     "channel_wavelengths_nm": [grid.wavelengths_nm[k] for k in wavelengths]})
        if frame is not None:
            meta["frame_camera"] = frame.meta(width, height)
    return out if image.ndim == 3 else out[..., 0]


def coverages(grid, lays, slab: np.ndarray, boundary: str, dtype) -> dict[int, np.ndarray]:
    """Each non-empty slab's coverage (k ≥ 1) blurred by its node's PSFs of unit sum at the middle
    wavelength (`interp`: the chief-ray offsets move the coverage with the light), clipped to [0, 1].
    (One FFT of the frame with the central node's PSF costs a tenth, but misplaces the coverage by the
    distortion: measured 2.2 % → 4.0 % at the 10 m depth edge of tests/convolution/test_depth.py.)"""
    from dataclasses import replace

    middle = int(np.argsort(grid.wavelengths_nm)[len(grid.wavelengths_nm) // 2])
    out = {}
    for k in range(1, len(grid.layers)):
        mask = slab == k
        if mask.any():
            unit = replace(grid.layers[k], meta={**grid.layers[k].meta, "normalization": "peak"})  # unit-sum kernels
            c = interp.convolve_channel(mask.astype(dtype), unit, lays[k], middle, boundary, dtype)
            out[k] = np.clip(c, 0.0, 1.0)
    return out


def composite(plane: np.ndarray, weights: np.ndarray, fills: dict, cover: dict, grid, lays, wavelength: int,
              boundary: str, dtype) -> np.ndarray:
    """One channel: each layer's light convolved by its node's grid and added far to near, the light
    gathered so far dimmed by each nearer slab's coverage (none in `cover`: no occlusion); a layer in
    `fills` (`fill_plans`) has its light behind nearer objects extrapolated first (`fill_hidden`)."""
    acc = np.zeros(plane.shape, dtype=dtype)
    for k, g in enumerate(grid.layers):
        if k in cover:
            acc *= 1 - cover[k]
        if weights[k].any():
            light = (plane * weights[k]).astype(dtype)
            if k in fills:
                fill_hidden(light, *fills[k])
            acc += interp.convolve_channel(light, g, lays[k], wavelength, boundary, dtype)
    return acc


def box_sum(a: np.ndarray, r: int) -> np.ndarray:
    """Sum of `a` over the (2r+1)² square around each pixel (zero outside), by cumulative sums."""
    for axis in (0, 1):
        c = np.cumsum(np.pad(a, [(r + 1, r) if i == axis else (0, 0) for i in range(2)]), axis=axis)
        n = a.shape[axis]
        a = np.take(c, np.arange(2 * r + 1, n + 2 * r + 1), axis=axis) - np.take(c, np.arange(n), axis=axis)
    return a


def fill_plans(weights: np.ndarray, slab: np.ndarray, radius: int) -> dict:
    """For each layer with light next to pixels where something nearer hides it: the crop (rows,
    columns) holding those pixels and the visible light within reach, its visible mask, and the
    mask twice box-filtered (channel-independent parts of `fill_hidden`)."""
    plans, reach = {}, 2 * radius + 1
    h, w = slab.shape
    for k in range(len(weights) - 1):
        rows, cols = np.flatnonzero(weights[k].any(axis=1)), np.flatnonzero(weights[k].any(axis=0))
        if not len(rows):
            continue
        box = (slice(max(0, rows[0] - 2 * reach), min(h, rows[-1] + 2 * reach + 1)),
               slice(max(0, cols[0] - 2 * reach), min(w, cols[-1] + 2 * reach + 1)))
        visible = slab[box] <= k
        if visible.all():
            continue
        den = box_sum(box_sum(visible.astype(np.float32), radius), radius)
        plans[k] = (box, visible, den, radius)
    return plans


def fill_hidden(light: np.ndarray, box: tuple, visible: np.ndarray, den: np.ndarray, radius: int) -> None:
    """A layer's light (H, W), in place: within `box`, the pixels where it is hidden (not `visible`:
    something nearer sits there) filled, up to about 2·radius pixels in, with the mean of its visible
    light around them (a normalised box filter applied twice): the background a near object's blur
    lets through."""
    part = light[box]
    num = box_sum(box_sum(np.where(visible, part, 0).astype(np.float32), radius), radius)
    filled = np.divide(num, den, out=np.zeros_like(num), where=den > 1e-6 * (2 * radius + 1) ** 4)
    light[box] = np.where(visible, part, filled)


def depth_meta(grid, depth: np.ndarray, weights: np.ndarray, occlusion: str, boundary: str, seconds: float) -> dict:
    """What the depth-aware convolution did."""
    finite = [d for d in grid.distances_m if np.isfinite(d)]
    return {"method": "depth", "occlusion": occlusion, "boundary": boundary, "seconds": seconds,
            "distances_m": [d if np.isfinite(d) else "inf" for d in grid.distances_m],
            "pixels_per_node": [float(w.sum()) for w in weights],
            "pixels_nearer_than_nearest_node": int((depth < min(finite)).sum()) if finite else 0,
            "pixels_farther_than_farthest_node": int((depth > max(grid.distances_m)).sum()),
            "depth": "metres along the optical axis; PSFs interpolated linearly in 1/distance between nodes, "
                     "clamped beyond the outermost"}
