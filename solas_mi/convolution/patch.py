"""The SOLAS paper's patch-wise convolution: one kernel per image block.

The image is cut into blocks, one per grid node: block borders lie halfway between neighbouring
nodes' ideal pixel positions, and the outer blocks reach the image border. A node takes part when
its cell holds at least one pixel. For the paper's layouts this is exactly its tiling: the doublet's
grids span ±2° in x and y, a 1280×960 image spans ±2° × ±1.5°, so of an 8×8 grid the 6 central rows
fall inside the image and their cells are 8×6 blocks of 160×160 px ("the 8×8 grid resized to
8×6"); a 32×32 grid gives 32×24 blocks of 40×40 px. Each channel uses its own wavelength's PSFs
(R, G, B ← 656, 531, 486 nm). The grid must cover the image (`kernels.check_covers`).

Each output block is the input convolved with its node's kernel and cropped to the block. The
kernel's context (R pixels around the block) comes from the neighbouring blocks' input pixels, and
from the padded border outside the image ("edge", "zero" or "reflect"; never wrapped): blocks are not
zero-padded one by one, so a spatially invariant grid gives exactly one ordinary convolution.
Seams remain where the kernel changes abruptly at a block border — the blur, the chief-ray offset
(distortion, lateral colour) and the transmission jump from one block's node to the next. That is
the method as published; `interp` has none.

Vectorised: the blocks' input tiles (block + 2R, FFT-friendly size) are cut from the padded image as
one strided stack, convolved by batched real FFTs in batches of ~1 M samples on a thread pool.
"""

from __future__ import annotations

import math

import numpy as np

from ..psf.grid import PSFGrid
from .kernels import Layout, batches, fast_len, fft_convolve, kernel_radius, node_kernels, pad, parallel_map

SUMMARY = (
    "the SOLAS paper's one PSF per block (8x6 blocks from an 8x8 grid on a 1280x960 image): seams at block borders"
)


def blocks(knots: np.ndarray, extent: int) -> list[tuple[int, int, int]]:
    """(node index, first pixel, end pixel) of the non-empty cells of nodes at `knots` on [0, extent)."""
    if len(knots) == 1:
        return [(0, 0, extent)]
    mids = np.ceil(0.5 * (knots[1:] + knots[:-1]))  # pixel c lies in node j+1's cell when c ≥ midpoint
    edges = np.concatenate([[0], np.clip(mids, 0, extent), [extent]]).astype(np.int64)
    return [(j, int(edges[j]), int(edges[j + 1])) for j in range(len(knots)) if edges[j + 1] > edges[j]]


def block_layout(lay: Layout) -> tuple[list, list]:
    """Row blocks and column blocks of an image."""
    return blocks(lay.row_knots, lay.camera.height), blocks(lay.col_knots, lay.camera.width)


def convolve_channel(
    channel: np.ndarray, grid: PSFGrid, lay: Layout, wavelength: int, boundary: str, dtype=np.float32
) -> np.ndarray:
    """One channel (H, W) degraded block by block with the PSFs of grid wavelength index `wavelength`."""
    height, width = channel.shape
    row_blocks, col_blocks = block_layout(lay)
    radius = kernel_radius(grid.size, lay.q)
    margin = radius + lay.max_shift([wavelength])
    bh = max(b - a for _, a, b in row_blocks)
    bw = max(b - a for _, a, b in col_blocks)
    shape = (fast_len(bh + 2 * radius), fast_len(bw + 2 * radius))
    padded = pad(channel.astype(dtype, copy=False), margin, boundary, shape)
    windows = np.lib.stride_tricks.sliding_window_view(padded, shape)
    # every block: node (row, column) and its pixel range
    todo = [(m, n, r0, r1, c0, c1) for m, r0, r1 in row_blocks for n, c0, c1 in col_blocks]
    nodes = np.array([(t[0], t[1]) for t in todo], dtype=np.int64)
    starts = np.array([(t[2], t[4]) for t in todo], dtype=np.int64)
    out = np.empty((height, width), dtype=dtype)

    def work(sl: slice):
        kernels, shift = node_kernels(grid, lay, wavelength, nodes[sl, 0], nodes[sl, 1], radius, dtype)
        # tile t ↔ image pixel start − R − shift + t: the output pixel start + u is the result at u + 2R
        top = starts[sl] - radius - shift + margin
        return sl, fft_convolve(windows[top[:, 0], top[:, 1]], kernels, shape)

    for sl, result in parallel_map(work, batches(len(todo), math.prod(shape))):
        for i, res in zip(range(sl.start, sl.stop), result):
            _, _, r0, r1, c0, c1 = todo[i]
            out[r0:r1, c0:c1] = res[2 * radius : 2 * radius + r1 - r0, 2 * radius : 2 * radius + c1 - c0]
    return out


def describe(lay: Layout, radius: int, wavelengths: list[int]) -> dict:
    """The blocks and their nodes (`methods.ConvolutionMethod.describe`; the kernel radius and the
    wavelengths do not change them)."""
    rows, cols = block_layout(lay)
    return {
        "blocks": [len(cols), len(rows)],
        "block_columns": [[n, a, b] for n, a, b in cols],
        "block_rows": [[m, a, b] for m, a, b in rows],
        "blocks_meaning": "[grid index, first pixel, end pixel) of each block column / row",
    }
