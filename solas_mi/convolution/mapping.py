"""Where the lens puts each point of an input frame in the degraded frame: the mapping the convolution
applies (`Mapping`), which the frame's labels follow (`convolution.labels`).

`interp` spreads the light of input pixel p by the blend of its nodes' kernels, node n weighing it
w_n(p) (hats over the nodes' ideal pixels; in a fisheye frame over their field angles, `curved`) and
its kernel centred on its chief ray, off_n away (`kernels.Layout.offsets`). So the light of p lands
around

    M(p) = p + O(p),   O(p) = Σ_n w_n(p) · off_n,

at the grid's reference wavelength (the one the pinhole focal length and a fisheye frame's points are
set at; the grid's nearest where it lacks it): the same hats at any point, clamped beyond the outermost
nodes. In a fisheye frame that wavelength's offsets are zero (its chief ray is the frame's own point),
so M is the identity there. With a depth map (`depth`) each pixel's offset is the blend of the distance
nodes' offsets by its hat weights in 1/distance, as its light is split between them (the depth map's
silhouettes moved as the convolution moves them). `patch` gathers instead: the output pixel q of a
block takes the input at q − off_n of the block's node, so there O is taken at the output point.

Labels need the inverse, the input point p with M(p) = q of each output pixel q: the fixed point of
p ← q − O(p), which converges as O changes by far less than a pixel per pixel (the distortion's slope;
the wide angle's is below 0.02), to TOLERANCE_PX in a few iterations; `patch` gives it directly. Where a
depth edge moves two surfaces differently the iteration may end between them (at most the difference of
their offsets away: a fraction of a pixel between neighbouring distance nodes); the metadata gives the
largest residual |M(p) − q|.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .curved import CurvedLayout, frame_layout
from .kernels import Layout

MAX_ITERATIONS = 30
TOLERANCE_PX = 1e-6
CHUNK_PIXELS = 1 << 18  # output pixels inverted at once: bounds the working memory (a few MB)


def reference_index(grid) -> int:
    """The grid's wavelength whose chief rays the mapping follows: its reference wavelength, or the nearest."""
    return int(np.argmin(np.abs(np.asarray(grid.wavelengths_nm) - float(grid.meta["reference_wavelength_nm"]))))


def _cells(knots: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For points `x`, the two neighbouring knots (indices) and the fraction t toward the second: the hats
    of `kernels.hat` (clamped beyond the ends; one knot: its own)."""
    if len(knots) == 1:
        zero = np.zeros(np.shape(x), dtype=np.int64)
        return zero, zero, np.zeros(np.shape(x))
    i = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, len(knots) - 2)
    t = np.clip((x - knots[i]) / (knots[i + 1] - knots[i]), 0.0, 1.0)
    return i, i + 1, t


def blend(col_knots: np.ndarray, row_knots: np.ndarray, table: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The node values `table` (ny, nx, 2) blended at the points (x, y) by the nodes' hats: Σ hat_i(y)·hat_j(x)·
    table[i, j], (…, 2)."""
    j0, j1, s = _cells(col_knots, x)
    i0, i1, t = _cells(row_knots, y)
    nx = table.shape[1]
    corners = [(i * nx + j, w) for i, ws in ((i0, 1 - t), (i1, t)) for j, w in ((j0, (1 - s) * ws), (j1, s * ws))]
    out = np.empty(np.shape(x) + table.shape[2:])
    for a in range(table.shape[-1]):  # a flat gather per component: far faster than indexing (ny, nx, 2) by pairs
        flat = np.ascontiguousarray(table[..., a]).ravel()
        out[..., a] = sum(flat.take(index) * w for index, w in corners)
    return out


def layout_offsets(lay: Layout, ref: int, cols: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """O at the input points (cols, rows) (…, 2) as (columns, rows) of a grid laid out by `lay`, wavelength `ref`."""
    if isinstance(lay, CurvedLayout):  # hats over field angle, the pixel's as `curved_layout` finds it
        tx, ty = lay.frame.tangents(cols, rows, lay.camera.width, lay.camera.height, clamp=True)
        return blend(
            lay.col_knots, lay.row_knots, lay.offsets[ref], np.degrees(np.arctan(tx)), -np.degrees(np.arctan(ty))
        )
    return blend(lay.col_knots, lay.row_knots, lay.offsets[ref], cols, rows)


def block_offsets(lay: Layout, ref: int, cols: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """O at the output points (cols, rows) of `patch`: the offset of the node whose block holds the pixel."""

    def node(knots, x, extent):
        if len(knots) == 1:
            return np.zeros(np.shape(x), dtype=np.int64)
        mids = np.ceil(0.5 * (knots[1:] + knots[:-1]))  # `patch.blocks`: pixel c is node j+1's when c ≥ mids[j]
        return np.searchsorted(mids, np.clip(np.rint(x), 0, extent - 1), side="right")

    return lay.offsets[ref][node(lay.row_knots, rows, lay.camera.height), node(lay.col_knots, cols, lay.camera.width)]


def psf_centroids(grid, lay: Layout, ref: int) -> np.ndarray:
    """Where each node's light lands relative to its chief ray (the first moment of its PSF at wavelength
    `ref`), in the frame's pixels (ny, nx, 2) as (columns, rows): the lens's coma and vignetting, which the
    image carries and labels following the chief ray do not."""
    x = (np.arange(grid.size) - grid.size // 2) * grid.pitch_um * 1e-3  # mm from the chief ray, +x right, rows down
    cols, rows = grid.data[ref].sum(axis=-2, dtype=np.float64), grid.data[ref].sum(axis=-1, dtype=np.float64)
    total = np.where(cols.sum(axis=-1) > 0, cols.sum(axis=-1), 1.0)
    mm = np.stack([cols @ x / total, -(rows @ x) / total], axis=-1)  # (x, y) mm, +y up
    if isinstance(lay, CurvedLayout):
        return np.einsum("yxab,yxb->yxa", lay.jacobian, mm)
    return mm * np.array([1.0, -1.0]) / (lay.camera.pitch_um * 1e-3)


@dataclass
class Mapping:
    """The mapping of a width×height frame (module docstring): `layouts` (one per distance node of a depth
    grid, else one), `ref` the wavelength index, `gathered` for `patch`, and with a depth grid its nodes'
    1/distance (`inverse`) and the frame's depth map (m, silhouettes as the convolution moved them)."""

    width: int
    height: int
    layouts: list
    ref: int
    wavelength_nm: float
    centroid_px: float = 0.0  # the largest distance of a node's light centroid from its chief ray (`psf_centroids`)
    gathered: bool = False
    inverse: np.ndarray | None = None
    depth: np.ndarray | None = None

    def offsets(self, cols: np.ndarray, rows: np.ndarray, at: tuple | None = None) -> np.ndarray:
        """O (…, 2) at the points (cols, rows); with a depth map, blended by the depth of the pixel at `at`
        (default: the points themselves; the border's beyond the frame)."""
        if self.gathered:
            return block_offsets(self.layouts[0], self.ref, cols, rows)
        if self.depth is None:
            return layout_offsets(self.layouts[0], self.ref, cols, rows)
        c, r = (cols, rows) if at is None else at
        d = self.depth[
            np.clip(np.rint(r), 0, self.height - 1).astype(np.int64),
            np.clip(np.rint(c), 0, self.width - 1).astype(np.int64),
        ]
        k0, k1, t = _cells(self.inverse, np.where(np.isinf(d), 0.0, 1.0 / d))
        each = np.stack([layout_offsets(lay, self.ref, cols, rows) for lay in self.layouts])
        pick = np.indices(np.shape(cols))
        return (1 - t)[..., None] * each[(k0, *pick)] + t[..., None] * each[(k1, *pick)]

    def forward(self, cols, rows, at: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Where the input points (cols, rows) land in the output (`at`: as `offsets`)."""
        cols, rows = np.asarray(cols, dtype=np.float64), np.asarray(rows, dtype=np.float64)
        if not self.gathered:
            o = self.offsets(cols, rows, at)
            return cols + o[..., 0], rows + o[..., 1]
        return self._solve(cols, rows, +1)[:2]

    def _solve(self, cols: np.ndarray, rows: np.ndarray, sign: int) -> tuple[np.ndarray, np.ndarray, int]:
        """The fixed point x = (cols, rows) + sign·O(x), and the iterations it took."""
        x, y, iterations, change = cols.copy(), rows.copy(), 0, np.inf
        while iterations < MAX_ITERATIONS and change >= TOLERANCE_PX:
            o = self.offsets(x, y)
            nx, ny = cols + sign * o[..., 0], rows + sign * o[..., 1]
            change = max(float(np.abs(nx - x).max(initial=0.0)), float(np.abs(ny - y).max(initial=0.0)))
            x, y, iterations = nx, ny, iterations + 1
        return x, y, iterations

    def sources(self) -> tuple[np.ndarray, np.ndarray, dict]:
        """The input point (columns, rows), each (H, W), that lands on each output pixel's centre, and how it
        was found (iterations, the largest residual in pixels)."""
        cols, rows = np.empty((self.height, self.width)), np.empty((self.height, self.width))
        step = max(1, CHUNK_PIXELS // self.width)
        iterations, residual = 0, 0.0
        for top in range(0, self.height, step):
            r, c = np.mgrid[top : min(self.height, top + step), 0 : self.width].astype(np.float64)
            if self.gathered:  # patch: the block's own offset, no iteration
                o = self.offsets(c, r)
                x, y, n = c - o[..., 0], r - o[..., 1], 1
            else:
                x, y, n = self._solve(c, r, -1)
            fx, fy = self.forward(x, y)
            residual = max(residual, float(np.hypot(fx - c, fy - r).max()))
            cols[top : top + len(r)], rows[top : top + len(r)] = x, y
            iterations = max(iterations, n)
        return cols, rows, {"iterations": iterations, "max_residual_px": residual}

    def meta(self) -> dict:
        """What the mapping is, for the metadata."""
        nodes = np.stack([lay.offsets[self.ref] for lay in self.layouts])
        how = (
            "patch: each output block takes the input at its node's chief-ray offset"
            if self.gathered
            else "interp: each input point moves by its nodes' chief-ray offsets blended by the convolution's hats"
            + (", and by its depth's hats in 1/distance" if self.depth is not None else "")
        )
        return {
            "wavelength_nm": self.wavelength_nm,
            "max_chief_ray_offset_px": float(np.abs(nodes).max()),
            "mapping": how,
            "max_psf_centroid_px": self.centroid_px,
            "psf_centroid": "the labels follow the chief ray; the light of a point lands around it, its centroid "
            "up to max_psf_centroid_px away (the PSF's first moment: coma, vignetting)",
        }


def mapping_for(
    grid, width: int, height: int, frame=None, method: str = "interp", depth: np.ndarray | None = None
) -> Mapping:
    """The mapping a width×height frame (taken by `frame`, `optics.frame.FrameCamera`; None: spanning the
    grid's x field) goes through when degraded by `grid` with `method`; with a depth grid
    (`psf.depth.DepthGrid`), its depth map `depth` (m, as the convolution used it: `depth.silhouette_depth`)."""
    grids = grid.layers if depth is not None else [grid]
    lays = [frame_layout(g, width, height, frame) for g in grids]
    ref = reference_index(grids[0])
    centroid = max(float(np.hypot(*psf_centroids(g, lay, ref).transpose(2, 0, 1)).max()) for g, lay in zip(grids, lays))
    return Mapping(
        width,
        height,
        lays,
        ref,
        float(grids[0].wavelengths_nm[ref]),
        centroid,
        gathered=method == "patch",
        inverse=grid.inverse if depth is not None else None,
        depth=depth,
    )
