"""Frames whose pixels are not the lens's ideal rectilinear image (fisheye calibrations,
`optics.frame`): the PSF of every pixel interpolated in field angle, each node's PSF drawn in the
frame's own pixels.

Why not `interp` as it is: its weights are products of hats over node rows and node columns of the
image, which holds only when a grid column of nodes (one θx) is a column of pixels. In a fisheye
frame the pixels of one θx lie on a curve, so the weights are taken where the grid lives, in field
angle: each pixel p has its field (θx, θy) from the frame's calibration (`FrameCamera.tangents`) and
node n = (i, j) the weight w_n(p) = hat_j(θx(p))·hat_i(θy(p)) (hats over the grid's field nodes,
clamped beyond the outermost: a partition of unity, continuous, so no seams). Then, as in `interp`,

    out = Σ_n K_n ⊛ (w_n · in),

each term over the bounding box of the node's support (found from the pixels' field cells), convolved
by FFT and added in place. A pinhole frame given this way gives `interp`'s result to the difference
between hats linear in angle and linear in tan θ (tests/convolution/test_fisheye_frames.py).

Each node's kernel in frame pixels. The frame's calibration says where each direction lands; the lens
says how light from one direction spreads on its sensor (mm, around its chief ray). The spread is
carried through angle: near node n, a displacement δ on the lens's sensor is the displacement
δθ = J_lens⁻¹·δ of direction (J_lens = ∂ chief ray / ∂(θx, θy), the pinhole part f/cos² exactly and the
lens's distortion by finite differences over the grid), which the frame draws at J_frame·δθ pixels
(J_frame = ∂ pixel / ∂(θx, θy), from `FrameCamera.pixels`). So the PSF sample at δ lands at
J·δ pixels, J = J_frame·J_lens⁻¹, a 2×2 map (radial and tangential scales differ in a fisheye). Each
PSF sample is split into s×s points (s = 2 to 4, from the largest scale) spread by the tent of texel box ⊛
pixel box (bilinear weights), the same pixel model as `kernels.pixel_kernels` with its exact sample
squares replaced by s² points. The point of each direction lands where the frame's calibration says
(the reference wavelength's chief ray is the frame's point); the other wavelengths' chief rays lie
J·(chief_k − chief_ref) away: lateral colour kept, the lens's distortion not added to the frame's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from ..optics.camera import Camera
from ..optics.frame import FISHEYE, FrameCamera
from ..psf.grid import PSFGrid
from .kernels import (
    Layout,
    batches,
    check_frame_covered,
    fast_len,
    fft_convolve,
    hat,
    kernel_radius,
    layout,
    pad,
    parallel_map,
    psf_scale,
)

SUMMARY = "PSFs interpolated bilinearly in field angle at every pixel of a fisheye frame, drawn in its pixels"
MAX_SUBSAMPLES = 4  # points per PSF sample and axis


@dataclass
class CurvedLayout(Layout):
    """A grid on a frame of curved field lines: col_knots are the grid columns' θx and row_knots the
    grid rows' −θy (degrees, increasing; grid row 0 = top), `field` each pixel's (θx, −θy) (2, H + 2M,
    W + 2M) over the frame and a margin M as wide as any kernel reaches (the padding's pixels included),
    `jacobian` each node's frame pixels (column, row) per lens mm (x, y) (ny, nx, 2, 2), `q` the
    largest PSF pitch in pixels (bounds the kernel radius), `frame` the frame's camera."""

    field: np.ndarray | None = None
    jacobian: np.ndarray | None = None
    frame: FrameCamera | None = None


def frame_layout(grid: PSFGrid, width: int, height: int, frame: FrameCamera | None = None) -> Layout:
    """`kernels.layout` for rectilinear frames, `curved_layout` for fisheye ones."""
    if frame is not None and frame.model in FISHEYE and grid.meta.get("layout") != "sensor":
        return curved_layout(grid, width, height, frame)
    return layout(grid, width, height, frame)


def curved_layout(grid: PSFGrid, width: int, height: int, frame: FrameCamera) -> CurvedLayout:
    """The grid's nodes in field angle over the width×height frame of camera `frame` (any model)."""
    check_frame_covered(grid, frame, width, height)
    f = np.asarray(grid.fields_deg, dtype=np.float64)
    if not (
        np.allclose(f[:, :, 0], f[:1, :, 0], rtol=0, atol=1e-9)
        and np.allclose(f[:, :, 1], f[:, :1, 1], rtol=0, atol=1e-9)
    ):
        raise SolasError("the PSF grid's fields are not a grid of x columns and y rows")
    cols, rows = f[0, :, 0], -f[:, 0, 1]
    if (len(cols) > 1 and not np.all(np.diff(cols) > 0)) or (len(rows) > 1 and not np.all(np.diff(rows) > 0)):
        raise SolasError(
            "the PSF grid's fields must be distinct and ordered (columns left to right, rows top to bottom)"
        )
    ref = int(np.argmin(np.abs(np.asarray(grid.wavelengths_nm) - float(grid.meta["reference_wavelength_nm"]))))
    jac = frame_jacobian(frame, f, width, height) @ np.linalg.inv(lens_jacobian(grid, ref))
    off = np.einsum("yxab,wyxb->wyxa", jac, grid.chief_ray_mm - grid.chief_ray_mm[ref][None])
    half = (grid.size // 2 + 0.5) * grid.pitch_um * 1e-3  # the PSF window's corners, mm
    corners = np.array([[1, 1], [1, -1]]) * half
    reach = np.abs(np.einsum("yxab,kb->yxka", jac, corners)).max()
    q = reach / (max(grid.size // 2, grid.size - 1 - grid.size // 2) + 0.5)
    margin = kernel_radius(grid.size, q) + int(np.abs(np.rint(off)).max())  # input pixels reaching the frame
    r, c = np.mgrid[-margin : height + margin, -margin : width + margin].astype(np.float64)
    tx, ty = frame.tangents(c, r, width, height, clamp=True)  # the padding continues the frame's mapping
    field = np.degrees(np.stack([np.arctan(tx), -np.arctan(ty)]))
    fx = frame_jacobian(frame, np.zeros((1, 1, 2)), width, height)[0, 0, 0, 0]  # pixels per radian on the axis
    focal = float(grid.meta["pinhole_focal_mm"])
    camera = Camera(
        int(width),
        int(height),
        1e3 * focal / fx,
        focal,
        float(frame.extent_deg(width, height)[0]),
        float(grid.meta["reference_wavelength_nm"]),
        "frame",
        principal=tuple(float(v) for v in frame.pixels(0.0, 0.0, width, height)),
    )
    return CurvedLayout(camera, cols, rows, off, q, field=field, jacobian=jac, frame=frame)


def lens_jacobian(grid: PSFGrid, ref: int) -> np.ndarray:
    """∂(x, y) mm of the chief ray at wavelength `ref` / ∂(θx, θy) radians at every node (ny, nx, 2, 2): the
    pinhole part f/cos²θ exactly, the distortion (chief ray − pinhole point) by finite differences."""
    f = np.radians(np.asarray(grid.fields_deg, dtype=np.float64))
    focal = float(grid.meta["pinhole_focal_mm"])
    distortion = grid.chief_ray_mm[ref] - focal * np.tan(f)
    jac = np.zeros(f.shape[:2] + (2, 2))
    jac[..., 0, 0] = focal / np.cos(f[..., 0]) ** 2
    jac[..., 1, 1] = focal / np.cos(f[..., 1]) ** 2
    for b, (axis, knots) in enumerate(((1, f[0, :, 0]), (0, f[:, 0, 1]))):
        if len(knots) > 1:
            jac[..., :, b] += np.gradient(distortion, knots, axis=axis)
    return jac


def frame_jacobian(
    frame: FrameCamera, fields_deg: np.ndarray, width: int, height: int, step: float = 1e-5
) -> np.ndarray:
    """∂(column, row) / ∂(θx, θy) radians of the frame at the fields (…, 2) degrees (central differences)."""
    t = np.radians(fields_deg)
    jac = np.zeros(t.shape[:-1] + (2, 2))
    for b in range(2):
        d = np.zeros(2)
        d[b] = step
        hi, lo = (
            frame.pixels(*np.tan(t + d).transpose(2, 0, 1), width, height),
            frame.pixels(*np.tan(t - d).transpose(2, 0, 1), width, height),
        )
        for a in range(2):
            jac[..., a, b] = (hi[a] - lo[a]) / (2 * step)
    return jac


def node_kernels(
    grid: PSFGrid, lay: CurvedLayout, wavelength: int, rows: np.ndarray, cols: np.ndarray, radius: int, dtype=np.float64
) -> tuple[np.ndarray, np.ndarray]:
    """Kernels (n, 2R+1, 2R+1) and integer shifts (n, 2) (rows, columns) of the nodes (rows[i], cols[i]) in
    the frame's pixels: each PSF sample's s×s points at J·δ + the offset's fraction, spread bilinearly."""
    size, pitch = grid.size, grid.pitch_um * 1e-3
    s = int(min(MAX_SUBSAMPLES, max(2, math.ceil(2 * lay.q))))
    sub = ((np.arange(size * s) + 0.5) / s - 0.5 - size // 2) * pitch  # sample j's points, mm from its origin
    x, y = np.meshgrid(sub, -sub)  # PSF rows run down the image: +y up
    jac = lay.jacobian[rows, cols]
    offsets = lay.offsets[wavelength, rows, cols]
    shift = np.rint(offsets)
    frac = offsets - shift
    col = np.einsum("n,ij->nij", jac[:, 0, 0], x) + np.einsum("n,ij->nij", jac[:, 0, 1], y) + frac[:, 0, None, None]
    row = np.einsum("n,ij->nij", jac[:, 1, 0], x) + np.einsum("n,ij->nij", jac[:, 1, 1], y) + frac[:, 1, None, None]
    weight = np.repeat(np.repeat(grid.data[wavelength, rows, cols].astype(np.float64), s, axis=1), s, axis=2)
    weight *= (psf_scale(grid, wavelength, rows, cols) / s**2)[:, None, None]
    k = 2 * radius + 1
    c0, r0 = np.floor(col), np.floor(row)
    fc, fr = col - c0, row - r0
    base = (
        np.arange(len(rows))[:, None, None] * k * k + (r0.astype(np.int64) + radius) * k + c0.astype(np.int64) + radius
    )
    out = np.zeros(len(rows) * k * k)
    for dr, dc, w in ((0, 0, (1 - fr) * (1 - fc)), (0, 1, (1 - fr) * fc), (1, 0, fr * (1 - fc)), (1, 1, fr * fc)):
        out += np.bincount((base + dr * k + dc).ravel(), (weight * w).ravel(), minlength=out.size)
    return out.reshape(len(rows), k, k).astype(dtype), shift[:, ::-1].astype(np.int64)


def supports(field: np.ndarray, lay: CurvedLayout) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The nodes with weight somewhere on `field` (2, h, w) and each one's bounding box there: node rows,
    node columns, first (row, column) (n, 2) and last + 1 (n, 2). Node (i, j) has weight in the field cells
    i, i+1 by j, j+1 (cell c of knots k: k[c−1] ≤ θ < k[c])."""
    from scipy.ndimage import find_objects

    ny, nx = len(lay.row_knots), len(lay.col_knots)
    cx = np.searchsorted(lay.col_knots, field[0], side="right")
    cy = np.searchsorted(lay.row_knots, field[1], side="right")
    boxes = find_objects(cy * (nx + 1) + cx + 1, max_label=(ny + 1) * (nx + 1))
    lo = np.full((ny + 1, nx + 1, 2), np.iinfo(np.int64).max)
    hi = np.full((ny + 1, nx + 1, 2), -1)
    for label, box in enumerate(boxes):
        if box is not None:
            lo[label // (nx + 1), label % (nx + 1)] = (box[0].start, box[1].start)
            hi[label // (nx + 1), label % (nx + 1)] = (box[0].stop, box[1].stop)
    node_lo = np.minimum.reduce([lo[a : a + ny, b : b + nx] for a in (0, 1) for b in (0, 1)])
    node_hi = np.maximum.reduce([hi[a : a + ny, b : b + nx] for a in (0, 1) for b in (0, 1)])
    i, j = np.nonzero(node_hi[..., 0] >= 0)
    return i, j, node_lo[i, j], node_hi[i, j]


def convolve_channel(
    channel: np.ndarray, grid: PSFGrid, lay: CurvedLayout, wavelength: int, boundary: str, dtype=np.float32
) -> np.ndarray:
    """One channel (H, W) of the frame degraded with the grid's PSFs interpolated in field angle."""
    height, width = channel.shape
    radius = kernel_radius(grid.size, lay.q)
    shift_max = lay.max_shift([wavelength])
    margin = radius + shift_max
    extra = (lay.field.shape[1] - height) // 2 - margin
    field = lay.field[:, extra : lay.field.shape[1] - extra, extra : lay.field.shape[2] - extra]
    rows, cols, lo, hi = supports(field, lay)
    ly, lx = (int(v) for v in (hi - lo).max(axis=0))
    shape = (fast_len(ly + 2 * radius), fast_len(lx + 2 * radius))
    padded = pad(channel.astype(dtype, copy=False), margin, boundary, (ly, lx))
    field = np.pad(field, ((0, 0), (0, ly), (0, lx)), mode="edge")
    inside = np.zeros(padded.shape, dtype=bool)
    inside[: height + 2 * margin, : width + 2 * margin] = True
    edge = margin + radius + shift_max
    acc = np.zeros((height + 2 * edge + shape[0], width + 2 * edge + shape[1]), dtype=dtype)

    def work(sl: slice):
        tiles = np.empty((sl.stop - sl.start, ly, lx), dtype=dtype)
        for t, (i, j, (r0, c0)) in enumerate(zip(rows[sl], cols[sl], lo[sl])):
            box = (slice(r0, r0 + ly), slice(c0, c0 + lx))
            w = hat(field[0][box], lay.col_knots, j) * hat(field[1][box], lay.row_knots, i)
            tiles[t] = padded[box] * (w * inside[box])
        kernels, shift = node_kernels(grid, lay, wavelength, rows[sl], cols[sl], radius, dtype)
        return lo[sl] - margin - radius + shift + edge, fft_convolve(tiles, kernels, shape)

    for at, result in parallel_map(work, batches(len(rows), math.prod(shape))):
        for (r, c), res in zip(at, result):
            acc[r : r + shape[0], c : c + shape[1]] += res
    return acc[edge : edge + height, edge : edge + width].copy()


def describe(lay: CurvedLayout, radius: int, wavelengths: list[int]) -> dict:
    """The nodes that took part and how (`methods.ConvolutionMethod.describe` for fisheye frames)."""
    scales = np.linalg.svd(lay.jacobian, compute_uv=False) * 1e-3  # pixels per µm
    return {
        "nodes": [len(lay.col_knots), len(lay.row_knots)],
        "weights": "bilinear hats over the nodes' field angles (theta x, theta y) at every pixel of the frame",
        "psf_pixels_per_um": [float(scales.min()), float(scales.max())],
        "kernels": "each node's PSF drawn in the frame's pixels through the frame's and the lens's Jacobians",
    }
