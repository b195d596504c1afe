"""Spatially smooth convolution: the PSF at every pixel interpolated bilinearly between grid nodes.

Overlap-add with a partition of unity: with w_n(x) the bilinear (hat) weight of node n at input
pixel x — tensor-product hats over the nodes' ideal pixel positions (non-uniform where tan θ is),
clamped to 1 beyond the outermost nodes so that they sum to 1 everywhere, the padding included —

    out = Σ_n K_n ⊛ (w_n · in),

i.e. the light of each input pixel spreads with the bilinear blend of its four neighbouring nodes'
kernels (blur, transmission and chief-ray offset alike). No seams: the weights are continuous. It
keeps energy exactly (each input pixel's light is spread by weights that sum to its kernels'
interpolated sum), and a spatially invariant grid gives exactly one ordinary convolution.

What follows from spreading each pixel's light (unlike `patch`, which gathers each output pixel
with one kernel summing to 1): where the chief-ray offsets change across the field, the local
magnification does, and a uniform scene comes out as the lens makes it, not uniform — the doublet's
distortion gives +1 % at the centre and −1.5 % near the left/right edges of a 1280×960 image. Beyond
the outermost nodes (the last half cell, 20 px on a 32×32 grid) the offsets stay at the outermost
node's, so that trend stops there. Between nodes the offsets are blended linearly: a distortion
curving between nodes is followed to h²/8·|offset''| (≈ 0.13 px with the doublet's 0.5° spacing of
an 8×8 grid, 0.01 px on 32×32).

Nodes outside the image take part when their hat reaches into the padded image (the doublet's 32×32
grid on a 1280×960 image: 32×26 nodes). Each term is computed over its hat's support plus the kernel
margin only: the weighted tiles of a batch of nodes are cut from the padded image as one strided
stack, convolved by real FFTs at a size ≥ tile + 2R (a linear convolution, no wrap) and added into
the output; one channel at a time, batches of ~1 M samples on a thread pool, so memory stays a few
image-sized buffers (4K included). Boundary: the image is padded (`kernels.pad`), never wrapped.
"""

from __future__ import annotations

import math

import numpy as np

from ..psf.grid import PSFGrid
from . import curved
from .kernels import Layout, batches, fast_len, fft_convolve, hats_at, kernel_radius, node_kernels, pad, parallel_map

SUMMARY = "PSFs interpolated bilinearly between grid nodes at every pixel: no seams"


def hats(knots: np.ndarray, first: int, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Hat weights of the nodes at `knots` over the pixels first … first+count−1 (clamped at the ends).

    Returns the indices of the nodes with any weight there, each one's first pixel of support (relative
    to `first`), its weights over a common window of L pixels from there, and L."""
    w = hats_at(first + np.arange(count, dtype=np.float64), knots)  # clamped: a partition of unity
    used = np.flatnonzero(w.max(axis=1) > 0)
    nz = w[used] > 0
    lo = np.argmax(nz, axis=1)
    hi = count - np.argmax(nz[:, ::-1], axis=1)
    length = int((hi - lo).max())
    w = np.pad(w[used], ((0, 0), (0, length)))
    windows = np.stack([w[i, a : a + length] for i, a in enumerate(lo)])
    return used, lo, windows, length


def convolve_channel(
    channel: np.ndarray, grid: PSFGrid, lay: Layout, wavelength: int, boundary: str, dtype=np.float32
) -> np.ndarray:
    """One channel (H, W) degraded with bilinearly interpolated PSFs of grid wavelength `wavelength` (in
    field angle on a fisheye frame's layout: `curved`)."""
    if isinstance(lay, curved.CurvedLayout):
        return curved.convolve_channel(channel, grid, lay, wavelength, boundary, dtype)
    height, width = channel.shape
    radius = kernel_radius(grid.size, lay.q)
    shift_max = lay.max_shift([wavelength])
    margin = radius + shift_max  # input pixels beyond this reach no output pixel
    rows, row_lo, row_w, ly = hats(lay.row_knots, -margin, height + 2 * margin)
    cols, col_lo, col_w, lx = hats(lay.col_knots, -margin, width + 2 * margin)
    shape = (fast_len(ly + 2 * radius), fast_len(lx + 2 * radius))
    padded = pad(channel.astype(dtype, copy=False), margin, boundary, (ly, lx))
    windows = np.lib.stride_tricks.sliding_window_view(padded, (ly, lx))
    row_w, col_w = row_w.astype(dtype), col_w.astype(dtype)
    # accumulator: image pixel p at index p + edge; a tile's result index j is pixel lo − margin + j − R + shift
    edge = margin + radius + shift_max
    acc = np.zeros((height + 2 * edge + shape[0], width + 2 * edge + shape[1]), dtype=dtype)
    mi, ni = lit_nodes(padded, row_lo, col_lo, ly, lx)  # a black tile adds nothing (a depth layer's are many)

    def work(sl: slice):
        m, n = mi[sl], ni[sl]
        tiles = windows[row_lo[m], col_lo[n]] * row_w[m][:, :, None] * col_w[n][:, None, :]
        kernels, shift = node_kernels(grid, lay, wavelength, rows[m], cols[n], radius, dtype)
        at = np.stack([row_lo[m], col_lo[n]], axis=1) - margin - radius + shift + edge
        return at, fft_convolve(tiles, kernels, shape)

    for at, result in parallel_map(work, batches(len(mi), math.prod(shape))):
        for (r, c), res in zip(at, result):
            acc[r : r + shape[0], c : c + shape[1]] += res
    return acc[edge : edge + height, edge : edge + width].copy()


def lit_nodes(
    padded: np.ndarray, row_lo: np.ndarray, col_lo: np.ndarray, ly: int, lx: int, block: int = 8
) -> tuple[np.ndarray, np.ndarray]:
    """Row and column indices of the nodes whose ly×lx window of `padded` (from row_lo, col_lo) may hold a
    non-zero value: a summed-area table of the block×block blocks holding any (a few extra nodes at
    most, whose tiles add zeros; the table is 1/block² of the image). Only their tiles are cut and
    convolved."""
    h, w = -(-padded.shape[0] // block), -(-padded.shape[1] // block)
    nz = np.zeros((h * block, w * block), dtype=bool)
    np.not_equal(padded, 0, out=nz[: padded.shape[0], : padded.shape[1]])
    table = np.zeros((h + 1, w + 1), dtype=np.int64)
    table[1:, 1:] = nz.reshape(h, block, w, block).any(axis=(1, 3)).cumsum(axis=0).cumsum(axis=1)
    r0, r1 = (row_lo // block)[:, None], ((row_lo + ly - 1) // block + 1)[:, None]
    c0, c1 = (col_lo // block)[None, :], ((col_lo + lx - 1) // block + 1)[None, :]
    count = (
        table[np.minimum(r1, h), np.minimum(c1, w)]
        - table[r0, np.minimum(c1, w)]
        - table[np.minimum(r1, h), c0]
        + table[r0, c0]
    )
    return np.nonzero(count > 0)


def describe(lay: Layout, radius: int, wavelengths: list[int]) -> dict:
    """The nodes that took part (`methods.ConvolutionMethod.describe`)."""
    if isinstance(lay, curved.CurvedLayout):
        return curved.describe(lay, radius, wavelengths)
    margin = radius + lay.max_shift(wavelengths)
    rows = hats(lay.row_knots, -margin, lay.camera.height + 2 * margin)[0]
    cols = hats(lay.col_knots, -margin, lay.camera.width + 2 * margin)[0]
    return {
        "nodes": [len(cols), len(rows)],
        "node_columns": cols.tolist(),
        "node_rows": rows.tolist(),
        "weights": "bilinear hats over the nodes' ideal pixel positions, clamped beyond the outermost nodes",
    }
