"""A PSF grid on an input image's pixels: node positions, chief-ray offsets, pixel kernels, padding.

Geometry (`optics.camera`): the input image is the ideal rectilinear image of the scene and the sensor is
its pixel grid. A grid node of field (θx, θy) sits at the ideal pixel `Camera.ideal_pixel` of its
field; the node's PSF for wavelength k is centred on that wavelength's real chief ray, which lies
`offset = chief_ray_mm − ideal_mm(field)` away (+x → +column, +y → −row). The offset is the lens's
distortion and lateral colour and is carried exactly, sub-pixel included.

Kernel of a node (pixel units, q = PSF pitch / sensor pitch): each PSF sample is uniform over its
q×q square; light from one input texel (a unit box: the input is a piecewise-constant texture)
spreads by the PSF, shifted by the chief-ray offset, and is averaged over one sensor pixel (another
unit box). Box ⊛ box is the tent T(t) = max(0, 1 − |t|), so the weight that the texel at relative
position (−kr, −kc) gives to an output pixel is K[kr, kc] = Σ_ij Ay[kr, i]·P[i, j]·Ax[kc, j] with

    A[k, j] = (1/q) ∫ over sample j's interval of T(k − d − s) ds,   d = the offset's fractional part,

an exact, separable overlap. Σ_k A[k, j] = 1 for every j, so a kernel sums to exactly what its PSF
sums to: 1 for "sum"-normalised grids; the transmitted fraction (relative to on-axis) for "none"
grids, whose PSF·pitch² is used, so vignetting is carried. "peak" grids keep no energy scale and are
normalised to unit sum. The offset's integer part is applied as a shift of where a kernel's output
lands, so kernels stay small even with large distortion.

Output pixel value = the mean irradiance over the pixel, in the units of the linear input (a uniform
input 1 with sum-normalised kernels gives 1).

Boundary: the image is padded, never wrapped around: "edge" (default) replicates the border pixels,
"zero" pads with 0 (a dark surround), "reflect" mirrors the image about its border (the border pixel
repeats).
"""

from __future__ import annotations

import math
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..errors import SolasError
from ..optics.camera import BOUNDARIES, Camera
from ..optics.frame import FISHEYE, FrameCamera
from ..psf.grid import PSFGrid
from ..threads import pool_threads

_PAD_MODES = {"edge": "edge", "zero": "constant", "reflect": "symmetric"}
COVER_TOLERANCE = 0.1  # the image may reach this fraction of a node spacing beyond the outermost node's cell
TILE_SAMPLES = 1 << 20  # samples per batch of FFT tiles (≈4 MB in float32): bounds memory, fits caches
# widest pixel kernel (2R+1 px): a PSF window spanning more of the image than this means the grid does
# not match the image (a tiny field range makes each PSF sample many pixels wide); the padded planes and
# FFT tiles grow with its square (a 2049-px kernel: tiles of about 2500² px, 25 MB each in float32)
MAX_KERNEL_PX = 2049


def check_boundary(boundary: str) -> str:
    if boundary not in BOUNDARIES:
        raise SolasError(f"boundary {boundary!r} must be one of {', '.join(BOUNDARIES)}")
    return boundary


def grid_camera(grid: PSFGrid, width: int, height: int, frame: FrameCamera | None = None) -> Camera:
    """The camera whose sensor is a width×height input image spanning the grid's ±x field range, or,
    given the frame's camera (`optics.frame`), the pinhole frame's: one pixel is 1/fx of a tangent, so
    the sensor's pitch is pinhole_focal_mm / fx, the axis at (cx, cy)."""
    meta = grid.meta
    if "pinhole_focal_mm" not in meta or "reference_wavelength_nm" not in meta:
        raise SolasError(
            "the PSF grid has no pinhole_focal_mm/reference_wavelength_nm metadata (written by an "
            "older version, or with a zero x field range): regenerate it with `solas-mi psf-grid`"
        )
    fov = float(meta["field_range_deg"][0])
    focal = float(meta["pinhole_focal_mm"])
    if frame is None:
        pitch_um = 2e3 * focal * math.tan(math.radians(fov)) / width
        return Camera(int(width), int(height), pitch_um, focal, fov, float(meta["reference_wavelength_nm"]))
    check_frame_covered(grid, frame, width, height)
    if frame.model in FISHEYE:
        raise SolasError(
            f"a {frame.model} frame's pixels are not a rectilinear image: lay the grid out with "
            "convolution.curved.frame_layout"
        )
    fx, fy, cx, cy = frame.pinhole(width, height)
    if abs(fx / fy - 1) > 1e-3:
        raise SolasError(
            f"frame intrinsics fx {fx:g}, fy {fy:g} px: the sensor's pixels are square; resample the "
            "frame so that fx = fy"
        )
    return Camera(
        int(width),
        int(height),
        1e3 * focal / fx,
        focal,
        math.degrees(math.atan((width / 2) / fx)),
        float(meta["reference_wavelength_nm"]),
        principal=(float(cx), float(cy)),
    )


def check_frame_covered(grid: PSFGrid, frame: FrameCamera, width: int, height: int) -> None:
    """SolasError with the numbers when the frame's field reaches beyond the grid's nodes' cells."""
    f = np.asarray(grid.fields_deg, dtype=np.float64)
    reach = []
    for nodes in (f[0, :, 0], f[::-1, 0, 1]):
        half = 0.5 * (nodes[-1] - nodes[0]) / max(len(nodes) - 1, 1) if len(nodes) > 1 else math.inf
        reach.append(max(abs(nodes[0]), abs(nodes[-1])) + half * (1 + 2 * COVER_TOLERANCE))
    ex, ey = frame.extent_deg(width, height)
    if ex > reach[0] or ey > reach[1]:
        raise SolasError(
            f"the {width}x{height} frame ({frame.model} camera) spans field angles up to {ex:.4g} deg "
            f"in x and {ey:.4g} deg in y; the lens's PSF grid covers {reach[0]:.4g} x {reach[1]:.4g} "
            f"deg (lens {grid.meta.get('lens')}): the lens "
            "does not cover this frame; give the frame's true camera or a lens with a wider field"
        )


def channel_wavelengths(grid: PSFGrid, channels: int) -> list[int]:
    """Grid wavelength index of each image channel: longest wavelength first (R ← 656, G ← 531,
    B ← 486 nm); a one-wavelength grid serves every channel."""
    n = len(grid.wavelengths_nm)
    if n == 1:
        return [0] * channels
    if n == channels:
        return [int(i) for i in np.argsort(grid.wavelengths_nm, kind="stable")[::-1]]
    raise SolasError(
        f"the PSF grid has {n} wavelengths {list(grid.wavelengths_nm)} nm but the image has {channels} "
        f"channel(s): use an image with {n} channels (R, G, B ← longest to shortest) or a grid of one "
        "wavelength"
    )


def psf_scale(grid: PSFGrid, wavelength: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Factor (n,) that turns the stored PSFs of nodes (rows[i], cols[i]) at one wavelength into sample
    weights (energy per sample), times meta["flux_scale"] where a grid has one (not for "peak": unit sum)."""
    how = grid.meta.get("normalization", "sum")
    flux = float(grid.meta.get("flux_scale", 1.0))  # a depth node seen from another viewpoint (`psf.depth`)
    if how == "sum":
        return np.full(len(rows), flux)
    if how == "none":  # irradiance per µm²: weights sum to the transmitted fraction
        return np.full(len(rows), flux * grid.pitch_um**2)
    if how == "peak":  # no energy scale kept: unit sum (of these nodes' PSFs only: a batch's, not the grid's)
        total = grid.data[wavelength, rows, cols].sum(axis=(-2, -1), dtype=np.float64)
        return 1.0 / np.where(total > 0, total, 1.0)
    raise SolasError(f"PSF grid normalization {how!r} must be sum, none or peak")


@dataclass
class Layout:
    """Where the nodes of a PSF grid fall on an input image, and their chief-ray offsets."""

    camera: Camera
    col_knots: np.ndarray  # (nx,) ideal pixel column of each grid column, increasing
    row_knots: np.ndarray  # (ny,) ideal pixel row of each grid row, increasing (grid row 0 = top)
    offsets: np.ndarray  # (n_wavelengths, ny, nx, 2): chief-ray offset (columns, rows) in pixels
    q: float  # PSF pitch in sensor pixels

    def max_shift(self, wavelengths: list[int]) -> int:
        """Largest integer part of the offsets (pixels) over the given wavelengths."""
        return int(np.abs(np.rint(self.offsets[sorted(set(wavelengths))])).max())


def layout(grid: PSFGrid, width: int, height: int, frame: FrameCamera | None = None) -> Layout:
    """Node positions and offsets of `grid` on a width×height image (taken by the camera `frame`; None:
    spanning the grid's x field range); fails if the grid's nodes are not a tensor product of x and y
    fields or do not cover the image."""
    if width < 1 or height < 1:
        raise SolasError(f"image size {width}x{height} must be at least 1x1")
    if grid.meta.get("layout") == "sensor":
        if frame is not None:
            raise SolasError("a PSF grid laid out on the sensor takes the sensor image itself: no frame camera")
        return sensor_layout(grid, width, height)
    camera = grid_camera(grid, width, height, frame)
    f = np.asarray(grid.fields_deg, dtype=np.float64)
    if not (
        np.allclose(f[:, :, 0], f[:1, :, 0], rtol=0, atol=1e-9)
        and np.allclose(f[:, :, 1], f[:, :1, 1], rtol=0, atol=1e-9)
    ):
        raise SolasError("the PSF grid's fields are not a grid of x columns and y rows")
    px = camera.ideal_pixel(f)  # (ny, nx, 2) = (column, row)
    cols, rows = px[0, :, 0], px[:, 0, 1]
    for name, knots, extent in (("x", cols, width), ("y", rows, height)):
        if len(knots) > 1 and not np.all(np.diff(knots) > 0):
            raise SolasError(
                f"the PSF grid's {name} fields must be distinct and ordered (columns left to right, rows top to bottom)"
            )
        check_covers(knots, extent, name)
    off = (grid.chief_ray_mm - camera.ideal_mm(f)[None]) * (1e3 / camera.pitch_um)
    offsets = np.stack([off[..., 0], -off[..., 1]], axis=-1)
    return Layout(camera, cols, rows, offsets, grid.pitch_um / camera.pitch_um)


def sensor_layout(grid: PSFGrid, width: int, height: int) -> Layout:
    """Layout of a grid whose nodes lie on the sensor (`psf.sensor`): the width×height input image is
    the sensor (meta["sensor_mm"], square pixels), each node sits at its image point (meta["node_mm"])
    and its offset is only what its chief ray at each wavelength lies away from that point."""
    w_mm, h_mm = (float(v) for v in grid.meta["sensor_mm"])
    pitch_mm = w_mm / width
    if abs(h_mm / height / pitch_mm - 1.0) > 1e-3:
        raise SolasError(
            f"image size {width}x{height} does not have the PSF grid's sensor aspect {w_mm:g} x {h_mm:g} mm "
            f"(pixels would not be square); use an image of {width}x{round(width * h_mm / w_mm)}"
        )
    camera = Camera(
        int(width), int(height), pitch_mm * 1e3, 0.0, 0.0, float(grid.meta["reference_wavelength_nm"]), "sensor"
    )
    nodes = np.asarray(grid.meta["node_mm"], dtype=np.float64)  # (ny, nx, 2)
    cols = nodes[0, :, 0] / pitch_mm + width / 2 - 0.5
    rows = height / 2 - 0.5 - nodes[:, 0, 1] / pitch_mm
    for name, knots, extent in (("x", cols, width), ("y", rows, height)):
        check_covers(knots, extent, name)
    off = (grid.chief_ray_mm - nodes[None]) / pitch_mm
    return Layout(camera, cols, rows, np.stack([off[..., 0], -off[..., 1]], axis=-1), grid.pitch_um / camera.pitch_um)


def check_covers(knots: np.ndarray, extent: int, axis: str) -> None:
    """The nodes' cells (half a spacing beyond the outermost nodes) must reach the image's borders
    (pixel edges −0.5 and extent − 0.5), give or take COVER_TOLERANCE of a spacing."""
    if len(knots) == 1:
        return  # one node: invariant along this axis
    first, last = knots[1] - knots[0], knots[-1] - knots[-2]
    lo, hi = knots[0] - first * (0.5 + COVER_TOLERANCE), knots[-1] + last * (0.5 + COVER_TOLERANCE)
    if lo > -0.5 or hi < extent - 0.5:
        what = "columns" if axis == "x" else "rows"
        raise SolasError(
            f"the PSF grid does not cover the image: its {axis} nodes reach pixel {what} "
            f"{knots[0] - first / 2:.1f} … {knots[-1] + last / 2:.1f}, the image spans -0.5 … "
            f"{extent - 0.5:g}; regenerate the grid with a larger --field-range-deg"
        )


def check_kernel(grid: PSFGrid, lay: Layout) -> int:
    """The kernel radius R (pixels) of `grid` on the image of `lay`; SolasError, before anything is
    allocated, when the kernel would be wider than MAX_KERNEL_PX."""
    radius = kernel_radius(grid.size, lay.q)
    if 2 * radius + 1 > MAX_KERNEL_PX:
        cam = lay.camera
        padded_gb = 4 * (cam.width + 2 * radius) * (cam.height + 2 * radius) / 1e9
        raise SolasError(
            f"the PSF grid's {grid.size}-sample windows of {grid.pitch_um:g} um span "
            f"{grid.size * lay.q:.4g} pixels of this {cam.width}x{cam.height} image, whose pixels are "
            f"{cam.pitch_um:.4g} um (PSF pitch {lay.q:.4g} px): kernels of {2 * radius + 1} px exceed "
            f"{MAX_KERNEL_PX} px (padded planes of about {padded_gb:.3g} GB); the grid's field range is "
            "far smaller than the image's — use a grid that spans it"
        )
    return radius


def hat(x: np.ndarray, knots: np.ndarray, node: int) -> np.ndarray:
    """The hat (tent) weight of node `node` of the increasing `knots` at the points `x` (float64): 1 at
    its knot, falling linearly to 0 at its neighbours', the end nodes held at 1 beyond the ends, so
    that the weights of all the nodes sum to 1 (linear interpolation between nodes, clamped); one
    knot: 1 everywhere. The weights of the PSF grid's nodes across the field and across depth."""
    unit = np.zeros(len(knots))
    unit[node] = 1.0
    return np.interp(x, knots, unit)


def hats_at(x: np.ndarray, knots: np.ndarray) -> np.ndarray:
    """Every node's `hat` weight at `x`: (len(knots), *x.shape)."""
    return np.stack([hat(x, knots, k) for k in range(len(knots))])


def tent_cdf(t: np.ndarray) -> np.ndarray:
    """∫_{−∞}^{t} max(0, 1 − |u|) du = 1/2 + t − t·|t|/2 for |t| ≤ 1 (t is overwritten)."""
    np.clip(t, -1.0, 1.0, out=t)
    g = np.abs(t)
    g *= t
    g *= -0.5
    g += t
    g += 0.5
    return g


def kernel_radius(size: int, q: float) -> int:
    """Half-width R of the (2R+1)² kernels of size×size PSFs of pitch q pixels (any fractional offset)."""
    half = max(size // 2, size - 1 - size // 2) * q
    return int(math.ceil(half + 0.5 * q + 1.0 + 0.5 - 1e-9))


def overlap_matrices(frac: np.ndarray, q: float, size: int, radius: int) -> np.ndarray:
    """A (n, 2R+1, size): overlap of PSF sample j with the tent around kernel tap k, for offsets `frac`."""
    k = np.arange(-radius, radius + 1, dtype=np.float64)
    edges = (np.arange(size + 1) - size // 2 - 0.5) * q  # sample j spans edges[j] … edges[j + 1]
    g = tent_cdf(k[None, :, None] - np.asarray(frac, dtype=np.float64)[:, None, None] - edges[None, None, :])
    return (g[..., :-1] - g[..., 1:]) / q


def pixel_kernels(
    psfs: np.ndarray, q: float, offsets: np.ndarray, scale: np.ndarray, radius: int, dtype=np.float64
) -> tuple[np.ndarray, np.ndarray]:
    """Kernels (n, 2R+1, 2R+1) and integer shifts (n, 2) as (rows, columns) of PSFs (n, s, s) with
    chief-ray offsets (n, 2) as (columns, rows) pixels and weight factors `scale` (n,); the products
    are taken in `dtype`.

    K[R + kr, R + kc] is the weight an input texel gives to the output pixel kr rows and kc columns
    from it, after the shift; the shift moves the whole kernel by whole pixels."""
    offsets = np.asarray(offsets, dtype=np.float64)
    shift = np.rint(offsets)
    frac = offsets - shift
    size = psfs.shape[-1]
    ax = overlap_matrices(frac[:, 0], q, size, radius).astype(dtype, copy=False)
    ay = overlap_matrices(frac[:, 1], q, size, radius).astype(dtype, copy=False)
    ay *= np.asarray(scale, dtype=np.float64)[:, None, None].astype(dtype)
    k = ay @ psfs.astype(dtype, copy=False) @ ax.transpose(0, 2, 1)
    return k, shift[:, ::-1].astype(np.int64)


def node_kernels(
    grid: PSFGrid, lay: Layout, wavelength: int, rows: np.ndarray, cols: np.ndarray, radius: int, dtype=np.float64
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel kernels and shifts of the grid nodes (rows[i], cols[i]) for one wavelength index."""
    scale = psf_scale(grid, wavelength, rows, cols)
    return pixel_kernels(
        grid.data[wavelength, rows, cols], lay.q, lay.offsets[wavelength, rows, cols], scale, radius, dtype
    )


def pad(channel: np.ndarray, margin: int, boundary: str, extra: tuple[int, int] = (0, 0)) -> np.ndarray:
    """The channel padded by `margin` on every side (plus `extra` rows/columns at the bottom/right),
    by the boundary rule; never wrapped around."""
    widths = ((margin, margin + extra[0]), (margin, margin + extra[1]))
    return np.pad(channel, widths, mode=_PAD_MODES[check_boundary(boundary)])


def fast_len(n: int) -> int:
    """Smallest 2^a·3^b·5^c ≥ n (fast FFT size)."""
    best = 1 << max(0, (n - 1).bit_length())
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            p = p35
            while p < n:
                p *= 2
            best = min(best, p)
            p35 *= 3
        p5 *= 5
    return best


def fft_convolve(tiles: np.ndarray, kernels: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Circular convolution at `shape` of tiles (b, ≤Ny, ≤Nx) with kernels (b, 2R+1, 2R+1) placed at the
    top-left corner: out[j] = Σ_k' K[k'] tile[j − k'], tile index j − R's true output at j."""
    spec = np.fft.rfft2(tiles, s=shape)
    spec *= np.fft.rfft2(kernels.astype(tiles.dtype, copy=False), s=shape)
    return np.fft.irfft2(spec, s=shape)


def batches(n: int, per_item: int) -> list[slice]:
    """Slices over n items, each holding about TILE_SAMPLES samples of per_item, at least 2 per worker."""
    size = max(1, min(TILE_SAMPLES // max(per_item, 1), -(-n // (2 * workers()))))
    return [slice(a, min(n, a + size)) for a in range(0, n, size)]


def workers() -> int:
    """The pool's threads: this process's (`threads.pool_threads`: its share where it is one of a batch's workers), 8 at most."""
    return max(1, min(pool_threads(), 8))


def parallel_map(fn, items: list):
    """fn over items on a thread pool (NumPy's FFTs release the GIL), results in order, at most two
    per worker in flight so that memory stays bounded."""
    n = workers()
    if n == 1 or len(items) <= 1:
        yield from map(fn, items)
        return
    with ThreadPoolExecutor(n) as pool:
        pending: deque = deque()
        for item in items:
            pending.append(pool.submit(fn, item))
            if len(pending) >= 2 * n:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
