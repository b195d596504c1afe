"""Spatially variant PSF-grid convolution (`solas_mi.convolution`, `solas-mi degrade`)."""
import argparse
import math

import numpy as np
import pytest

from solas_mi.convolution import degrade
from solas_mi.convolution.commands import register
from solas_mi.convolution.interp import hats
from solas_mi.convolution.kernels import (
    grid_camera,
    kernel_radius,
    layout,
    node_kernels,
    overlap_matrices,
    pixel_kernels,
)
from solas_mi.convolution.patch import block_layout
from solas_mi.errors import SolasError
from solas_mi.psf import psf, psf_grid
from solas_mi.psf.grid import PSFGrid, field_nodes

FOCAL = 100.0  # synthetic pinhole focal length (mm)
METHODS = ("interp", "patch")


def pixel_um(width: int, fov: float = 2.0) -> float:
    return 2e3 * FOCAL * math.tan(math.radians(fov)) / width


def gaussian(size: int, sigma_um: float, pitch_um: float) -> np.ndarray:
    x = (np.arange(size) - size // 2) * pitch_um
    g = np.exp(-0.5 * (x[None, :] ** 2 + x[:, None] ** 2) / sigma_um ** 2)
    return g / g.sum()


def make_grid(psfs, pitch_um, offsets_um=None, field=(2.0, 2.0), wavelengths=None, normalization="sum",
              sampling="centers") -> PSFGrid:
    """A PSFGrid without the tracer: psfs (n_wavelengths, ny, nx, s, s); chief rays = the ideal image
    points + offsets_um (n_wavelengths, ny, nx, 2) µm (x right, y up)."""
    psfs = np.asarray(psfs, dtype=np.float32)
    nw, ny, nx = psfs.shape[:3]
    fx = field_nodes(nx, field[0], sampling)
    fy = field_nodes(ny, field[1], sampling)[::-1]
    fields = np.stack(np.meshgrid(fx, fy), axis=-1)
    chief = np.repeat(FOCAL * np.tan(np.radians(fields))[None], nw, axis=0)
    if offsets_um is not None:
        chief = chief + np.asarray(offsets_um, dtype=np.float64) * 1e-3
    meta = {"normalization": normalization, "field_range_deg": list(field), "field_sampling": sampling,
            "pinhole_focal_mm": FOCAL, "reference_wavelength_nm": 531.0}
    wl = tuple(wavelengths) if wavelengths else tuple(531.0 + 50.0 * k for k in range(nw))
    return PSFGrid(psfs, fields, chief, wl, float(pitch_um), meta)


def reference_convolution(image: np.ndarray, kernel: np.ndarray, shift, boundary="edge") -> np.ndarray:
    """Direct float64 convolution with one kernel (shift: whole pixels, rows, columns), padded."""
    mode = {"edge": "edge", "zero": "constant", "reflect": "symmetric"}[boundary]
    r = kernel.shape[0] // 2
    m = r + int(np.abs(shift).max())
    p = np.pad(image.astype(np.float64), m, mode=mode)
    out = np.zeros(image.shape)
    h, w = image.shape
    for a in range(2 * r + 1):
        for b in range(2 * r + 1):
            y0, x0 = m - (a - r) - shift[0], m - (b - r) - shift[1]
            out += kernel[a, b] * p[y0:y0 + h, x0:x0 + w]
    return out


def centroid(image: np.ndarray) -> np.ndarray:
    """(column, row) centroid."""
    r, c = np.indices(image.shape)
    return np.array([(image * c).sum(), (image * r).sum()]) / image.sum()


def varied_grid(rng, width, ny=8, nx=8, pitch_div=4, max_offset_px=1.0, normalization="sum", transmission=None):
    """Gaussian PSFs of random widths (0.5–4 px) and random chief-ray offsets on an 8×8 grid."""
    pix = pixel_um(width)
    pitch = pix / pitch_div
    size = 2 * int(math.ceil(8 * pitch_div)) + 1  # ±8 px
    sig = rng.uniform(0.5, 4.0, (ny, nx)) * pix
    psfs = np.stack([[gaussian(size, s, pitch) for s in row] for row in sig])[None]
    if transmission is not None:
        psfs = psfs * (transmission / pitch ** 2)[None, :, :, None, None]
    off = rng.uniform(-max_offset_px, max_offset_px, (1, ny, nx, 2)) * pix
    return make_grid(psfs, pitch, off, normalization=normalization)


def smooth_texture(rng, h, w):
    y, x = np.mgrid[0:h, 0:w]
    img = np.zeros((h, w))
    for _ in range(40):
        k = rng.normal(0, 0.25, 2)
        img += np.cos(k[0] * x + k[1] * y + rng.uniform(0, 2 * np.pi))
    return 0.5 + 0.5 * img / np.abs(img).max()


# ---- kernels ---------------------------------------------------------------------------------------

def test_kernel_of_a_pixel_sized_sample_is_the_quadratic_bspline():
    """One PSF sample as wide as a pixel, texel box ⊛ sample box ⊛ pixel box = B-spline of degree 2."""
    a = overlap_matrices(np.array([0.0]), 1.0, 1, 2)[0, :, 0]
    np.testing.assert_allclose(a, [0, 1 / 8, 3 / 4, 1 / 8, 0], atol=1e-15)
    # offset by half a pixel: B2(±0.5) = 1/2, B2(1.5) = 0
    a = overlap_matrices(np.array([0.5]), 1.0, 1, 2)[0, :, 0]
    np.testing.assert_allclose(a, [0, 0, 0.5, 0.5, 0], atol=1e-15)


def test_overlap_matrix_against_quadrature():
    q, size, d = 0.37, 7, -0.23
    radius = kernel_radius(size, q)
    a = overlap_matrices(np.array([d]), q, size, radius)[0]
    s = (np.arange(size) - size // 2) * q
    u = (np.arange(20000) + 0.5) / 20000 - 0.5  # midpoints over one sample, in units of q
    for j in range(size):
        for i, k in enumerate(range(-radius, radius + 1)):
            t = k - d - (s[j] + u * q)
            assert a[i, j] == pytest.approx(np.maximum(0, 1 - np.abs(t)).mean(), abs=1e-7)
    np.testing.assert_allclose(a.sum(axis=0), 1.0, atol=1e-12)  # every sample's light is kept


@pytest.mark.parametrize("normalization", ["sum", "none", "peak"])
def test_kernel_sums(normalization):
    pix = pixel_um(128)
    pitch = pix / 3
    p = gaussian(33, 1.5 * pix, pitch)
    scale = {"sum": 1.0, "none": 0.7 / pitch ** 2, "peak": 1 / p.max()}[normalization]
    g = make_grid(np.broadcast_to(p * scale, (1, 2, 2, 33, 33)), pitch, normalization=normalization)
    lay = layout(g, 128, 128)
    k, _ = node_kernels(g, lay, 0, np.array([0, 1]), np.array([1, 0]), kernel_radius(33, lay.q))
    expected = 0.7 if normalization == "none" else 1.0
    np.testing.assert_allclose(k.sum(axis=(1, 2)), expected, rtol=1e-6)


def test_hats_are_a_partition_of_unity():
    knots = np.array([3.2, 10.0, 17.5, 40.0])
    used, lo, w, length = hats(knots, -5, 60)
    total = np.zeros(60 + length)
    for a, row in zip(lo, w):
        total[a:a + length] += row
    np.testing.assert_allclose(total[:60], 1.0, atol=1e-12)
    assert list(used) == [0, 1, 2, 3]


def test_paper_block_layouts():
    """±2° grids on a 1280×960 image: 8×8 → 8×6 blocks of 160 px, 32×32 → 32×24 blocks of 40 px."""
    for n, block in ((8, 160), (32, 40)):
        g = make_grid(np.ones((1, n, n, 3, 3)) / 9, 0.5)
        rows, cols = block_layout(layout(g, 1280, 960))
        assert [b - a for _, a, b in cols] == [block] * n
        assert [b - a for _, a, b in rows] == [block] * (n * 3 // 4)
        assert [m for m, _, _ in rows] == list(range(n // 8, n - n // 8))  # the rows inside the image
        assert cols[0][1] == 0 and cols[-1][2] == 1280 and rows[0][1] == 0 and rows[-1][2] == 960


# ---- acceptance --------------------------------------------------------------------------------------

@pytest.mark.parametrize("boundary", ["edge", "zero", "reflect"])
@pytest.mark.parametrize("method", METHODS)
def test_invariant_grid_is_one_convolution(method, boundary):
    rng = np.random.default_rng(0)
    h, w = 72, 96
    pix = pixel_um(w)
    pitch = pix / 5
    p = gaussian(41, 1.3 * pix, pitch)
    p = np.roll(p, 2, axis=1)  # asymmetric
    offset = np.broadcast_to([2.4 * pix, -1.3 * pix], (1, 8, 8, 2))  # the same chief-ray offset everywhere
    g = make_grid(np.broadcast_to(p, (1, 8, 8, 41, 41)), pitch, offset)
    img = rng.random((h, w))
    lay = layout(g, w, h)
    k, shift = pixel_kernels(g.data[0, :1, 0], lay.q, lay.offsets[0, :1, 0], np.ones(1), kernel_radius(41, lay.q))
    ref = reference_convolution(img, k[0], shift[0], boundary)
    out = degrade(img, g, method, boundary)
    assert out.dtype == np.float32
    assert np.abs(out - ref).max() < 1e-6
    assert np.abs(degrade(img, g, method, boundary, dtype=np.float64) - ref).max() < 1e-12


@pytest.mark.parametrize("method", METHODS)
def test_invariant_rgb_grid_uses_longest_wavelength_for_red(method):
    rng = np.random.default_rng(1)
    h, w = 48, 64
    pix = pixel_um(w)
    pitch = pix / 4
    p = np.stack([gaussian(21, s * pix, pitch) for s in (0.6, 1.0, 2.0)])  # for 486, 656, 531 nm
    g = make_grid(np.broadcast_to(p[:, None, None], (3, 4, 4, 21, 21)), pitch, wavelengths=(486.0, 656.0, 531.0))
    img = rng.random((h, w, 3))
    out = degrade(img, g, method, dtype=np.float64)
    lay = layout(g, w, h)
    radius = kernel_radius(21, lay.q)
    for channel, k in zip(range(3), (1, 2, 0)):  # R ← 656, G ← 531, B ← 486
        kern, shift = pixel_kernels(g.data[k, :1, 0], lay.q, np.zeros((1, 2)), np.ones(1), radius)
        np.testing.assert_allclose(out[..., channel], reference_convolution(img[..., channel], kern[0], shift[0]),
                                   atol=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_delta_grid_returns_input(method):
    rng = np.random.default_rng(2)
    h, w = 60, 80
    delta = np.zeros((5, 5))
    delta[2, 2] = 1.0
    pitch = pixel_um(w) * 1e-4  # a PSF sample 1e-4 px wide: a point
    g = make_grid(np.broadcast_to(delta, (1, 8, 8, 5, 5)), pitch)
    img = rng.random((h, w))
    assert np.abs(degrade(img, g, method) - img).max() < 1e-4
    # offset by whole pixels (3 right, 2 up): the image moves, exactly
    g = make_grid(np.broadcast_to(delta, (1, 8, 8, 5, 5)), pitch,
                  np.broadcast_to([3 * pixel_um(w), 2 * pixel_um(w)], (1, 8, 8, 2)))
    out = degrade(img, g, method, "zero")
    assert np.abs(out[:-2, 3:] - img[2:, :-3]).max() < 1e-4
    assert np.abs(out[-2:]).max() < 1e-4 and np.abs(out[:, :3]).max() < 1e-4


@pytest.mark.parametrize("method", METHODS)
def test_energy_is_preserved(method):
    """Sum-normalised kernels: Σ out = Σ in for light away from the image border (interp: any content;
    patch: content away from block borders, where each block's kernel spreads its own light)."""
    rng = np.random.default_rng(3)
    h, w = 192, 256  # 8×6 blocks of 32 px; kernels reach 11 px
    g = varied_grid(rng, w)
    img = np.zeros((h, w))
    if method == "interp":
        img[20:-20, 20:-20] = rng.random((h - 40, w - 40))
    else:
        img[16::32, 16::32] = rng.random((6, 8))  # a dot at every block centre
    out = degrade(img, g, method, "zero", dtype=np.float64)
    assert out.sum() == pytest.approx(img.sum(), rel=1e-9)
    assert np.abs(out - img).max() > 0.01  # it did blur


def test_transmission_normalised_energy():
    """"none" grids: PSF·pitch² sums to the transmitted fraction; with interp each input pixel keeps
    the bilinear blend of its nodes' transmissions (vignetting carried)."""
    rng = np.random.default_rng(4)
    h, w = 96, 128
    t = rng.uniform(0.5, 1.0, (8, 8))
    g = varied_grid(rng, w, normalization="none", transmission=t)
    img = np.zeros((h, w))
    img[20:-20, 20:-20] = rng.random((h - 40, w - 40))
    out = degrade(img, g, "interp", "zero", dtype=np.float64)
    lay = layout(g, w, h)
    wy = np.stack([np.interp(np.arange(h), lay.row_knots, e) for e in np.eye(8)])
    wx = np.stack([np.interp(np.arange(w), lay.col_knots, e) for e in np.eye(8)])
    t_map = wy.T @ t @ wx
    assert out.sum() == pytest.approx((img * t_map).sum(), rel=1e-6)
    # a uniform transmission scales the output exactly
    g = varied_grid(np.random.default_rng(5), w, normalization="none", transmission=np.full((8, 8), 0.8))
    assert degrade(img, g, "interp", "zero", dtype=np.float64).sum() == pytest.approx(0.8 * img.sum(), rel=1e-9)


def test_uniform_input_stays_uniform():
    """patch: every output pixel's kernel sums to 1, so a uniform input stays uniform, borders included
    ("edge"), whatever the PSFs and offsets. interp spreads each input pixel with its own blended PSF
    (light is conserved, as in the lens): a uniform input stays uniform to the second derivative of
    the PSF field — exactly for a spatially invariant grid, within 2e-3 for a smoothly varying one."""
    rng = np.random.default_rng(6)
    g = varied_grid(rng, 128, max_offset_px=3.0)
    np.testing.assert_allclose(degrade(np.full((96, 128, 3), 0.25), g, "patch"), 0.25, rtol=2e-6)
    pix = pixel_um(128)
    f = np.linspace(0.0, 1.0, 8)
    sigma = (1.0 + 0.5 * f[None, :] + 0.3 * f[:, None]) * pix  # 1–1.8 px across the field
    g = make_grid(np.stack([[gaussian(65, s, pix / 4) for s in row] for row in sigma])[None], pix / 4)
    np.testing.assert_allclose(degrade(np.full((96, 128), 0.25), g, "interp"), 0.25, rtol=2e-3)


def test_interp_has_no_seams_and_patch_has():
    """Gradient energy across block borders relative to that between the other pixel pairs."""
    rng = np.random.default_rng(7)
    h, w = 192, 256  # blocks of 32 px
    g = varied_grid(rng, w)
    img = smooth_texture(rng, h, w)
    rows, cols = block_layout(layout(g, w, h))
    bx = np.zeros(w - 1, bool)
    bx[[a - 1 for _, a, _ in cols if a > 0]] = True
    by = np.zeros(h - 1, bool)
    by[[a - 1 for _, a, _ in rows if a > 0]] = True

    def seam_ratio(o):
        dx, dy = np.diff(o, axis=1) ** 2, np.diff(o, axis=0) ** 2
        border = (dx[:, bx].sum() + dy[by].sum()) / (bx.sum() * h + by.sum() * w)
        inside = (dx[:, ~bx].sum() + dy[~by].sum()) / ((~bx).sum() * h + (~by).sum() * w)
        return border / inside

    assert seam_ratio(degrade(img, g, "interp")) <= 1.0
    assert seam_ratio(degrade(img, g, "patch")) > 2.0  # the test can tell a seam


@pytest.mark.parametrize("method", METHODS)
def test_chief_ray_offset_moves_a_dot(method):
    h, w = 96, 128
    pix = pixel_um(w)
    pitch = pix / 4
    g = make_grid(np.broadcast_to(gaussian(33, 1.5 * pix, pitch), (1, 8, 8, 33, 33)), pitch,
                  np.broadcast_to([3.7 * pix, -2.2 * pix], (1, 8, 8, 2)))  # 3.7 px right, 2.2 px down
    img = np.zeros((h, w))
    img[40, 50] = 1.0
    np.testing.assert_allclose(centroid(degrade(img, g, method, dtype=np.float64)), [53.7, 42.2], atol=1e-9)


def test_interp_blends_the_offsets_of_the_nodes():
    """Random offsets per node: a dot anywhere moves by the bilinear blend of its nodes' offsets."""
    rng = np.random.default_rng(8)
    h, w = 96, 128
    g = varied_grid(rng, w, max_offset_px=3.0)
    g.data[:] = g.data[0, 0, 0]  # one PSF, symmetric: only the offsets differ
    lay = layout(g, w, h)
    for row, col in ((40, 50), (14, 115), (84, 13)):  # ≥ R + 3 px from the borders
        img = np.zeros((h, w))
        img[row, col] = 1.0
        ry = np.array([np.interp(row, lay.row_knots, e) for e in np.eye(8)])
        rx = np.array([np.interp(col, lay.col_knots, e) for e in np.eye(8)])
        expected = np.einsum("m,n,mnk->k", ry, rx, lay.offsets[0])
        c = centroid(degrade(img, g, "interp", "zero", dtype=np.float64))
        np.testing.assert_allclose(c - [col, row], expected, atol=1e-9)


@pytest.fixture(scope="module")
def doublet_grid(doublet):
    return psf_grid(doublet, grid="4x4", size=64, pitch_um=1.0, pupil_samples=32, wavelengths_nm=[656, 531, 486])


def tracer_centroids(lens, cam, field) -> np.ndarray:
    """(column, row) pixel positions, 656/531/486 nm, of the tracer's chief ray at `field` plus the
    PSF's own centroid there (its energy is not centred on the chief ray)."""
    from solas_mi.optics.pupil import chief_rays

    found = []
    for wl in (656.0, 531.0, 486.0):
        xy = chief_rays(lens, np.array([field]), np.array([wl])).image_xy[0] * 1e3  # µm
        p = psf(lens, tuple(field), wl, size=64, pitch_um=1.0, pupil_samples=32)
        dx, dy = centroid(p.data) - 32  # µm right, µm down from the chief ray
        found.append([(xy[0] + dx) / cam.pitch_um + cam.width / 2 - 0.5,
                      cam.height / 2 - 0.5 - (xy[1] - dy) / cam.pitch_um])
    return np.array(found)


def test_dot_lands_where_the_tracer_says(doublet, doublet_grid):
    """Dots degraded with interp, 1280×960 RGB: each channel's centroid is the tracer's chief ray plus
    the PSF's own centroid, to 0.02 px on a node; between nodes the chief-ray offsets are interpolated
    bilinearly, off by ≤ h²/8·|offset''| (≈ 0.13 px per 0.5° node spacing for this lens, 0.01 px on a
    32×32 grid)."""
    h, w = 960, 1280
    cam = grid_camera(doublet_grid, w, h)
    for field_deg, tolerance in (((1.5, 0.5), 0.02), ((1.5, 0.75), 0.3)):
        col, row = np.rint(cam.ideal_pixel(np.array(field_deg))).astype(int)
        tan = np.array([col + 0.5 - w / 2, h / 2 - row - 0.5]) * math.tan(math.radians(2.0)) / (w / 2)
        field = np.degrees(np.arctan(tan))  # the dot pixel's own field
        img = np.zeros((h, w, 3))
        img[row, col] = 1.0
        out = degrade(img, doublet_grid, "interp")
        found = np.array([centroid(out[row - 20:row + 21, col - 20:col + 21, c]) + [col - 20, row - 20]
                          for c in range(3)])
        expected = tracer_centroids(doublet, cam, field)
        np.testing.assert_allclose(found, expected, atol=tolerance)
        if tolerance < 0.1:
            on_node = (img, row, col, expected)
    # the offsets matter: discarding them (chief rays on the ideal points) misplaces R by > 1 px
    img, row, col, expected = on_node
    g = PSFGrid(doublet_grid.data, doublet_grid.fields_deg,
                np.repeat(cam.ideal_mm(doublet_grid.fields_deg)[None], 3, axis=0), doublet_grid.wavelengths_nm,
                doublet_grid.pitch_um, doublet_grid.meta)
    out = degrade(img, g, "interp")
    wrong = centroid(out[row - 20:row + 21, col - 20:col + 21, 0]) + [col - 20, row - 20]
    assert np.abs(wrong - expected[0]).max() > 1.0
    # lateral colour: the chief rays of 656 and 486 nm are 0.57 px apart in x at (1.5°, 0.5°); their
    # PSFs' centroids bring the R and B centroids to 0.12 px
    m, n = np.argwhere(np.isclose(doublet_grid.fields_deg, [1.5, 0.5]).all(axis=-1))[0]
    lay = layout(doublet_grid, w, h)
    assert lay.offsets[0, m, n, 0] - lay.offsets[2, m, n, 0] == pytest.approx(-0.57, abs=0.02)


# ---- bad input -----------------------------------------------------------------------------------------

def small_grid(**kw):
    return make_grid(np.broadcast_to(gaussian(9, 2.0, 1.0), (1, 4, 4, 9, 9)), 1.0, **kw)


def test_bad_method_and_boundary():
    img = np.zeros((30, 40))
    with pytest.raises(SolasError, match="method 'fft'.*interp, patch"):
        degrade(img, small_grid(), "fft")
    with pytest.raises(SolasError, match="boundary 'wrap'.*edge, reflect, zero"):
        degrade(img, small_grid(), "interp", "wrap")


def test_grid_without_camera_metadata():
    g = small_grid()
    del g.meta["pinhole_focal_mm"]
    with pytest.raises(SolasError, match="solas-mi psf-grid"):
        degrade(np.zeros((30, 40)), g)


def test_image_not_covered():
    g = small_grid(field=(2.0, 1.0))  # ±1° in y cannot cover a square image spanning ±2°
    with pytest.raises(SolasError, match="does not cover the image.*rows"):
        degrade(np.zeros((40, 40)), g)
    degrade(np.zeros((20, 40)), g)  # ±1° tall: covered


def test_channel_count_mismatch():
    g = make_grid(np.broadcast_to(gaussian(9, 2.0, 1.0), (3, 4, 4, 9, 9)), 1.0)
    with pytest.raises(SolasError, match="3 wavelengths.*1 channel"):
        degrade(np.zeros((30, 40)), g)
    with pytest.raises(SolasError, match="H×W or H×W×C"):
        degrade(np.zeros(5), g)


def test_tiny_image_and_large_kernel():
    g = make_grid(np.broadcast_to(gaussian(61, 5000.0, 800.0), (1, 4, 4, 61, 61)), 800.0)  # ±14 px on 3×4 px
    for boundary in ("edge", "zero", "reflect"):
        for method in METHODS:
            out = degrade(np.full((3, 4), 0.5), g, method, boundary)
            assert out.shape == (3, 4) and np.isfinite(out).all()
            if boundary != "zero":
                np.testing.assert_allclose(out, 0.5, rtol=1e-5)


# ---- command line --------------------------------------------------------------------------------------

def parser():
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="command"))
    return p


def test_command_line(tmp_path):
    from solas_mi.imageio import read_exr, read_image, write_png

    g = make_grid(np.broadcast_to(gaussian(15, 8.0, 2.0), (3, 4, 4, 15, 15)), 2.0, wavelengths=(656, 531, 486))
    g.write(str(tmp_path / "grid.exr"))
    img = np.zeros((48, 64, 3))
    img[:, :32] = [0.2, 0.5, 0.8]
    img[:, 32:] = 0.6
    write_png(tmp_path / "in.png", img)
    args = parser().parse_args(["degrade", str(tmp_path / "in.png"), "--psf-grid", str(tmp_path / "grid.exr"),
                                "--method", "patch", "-o", str(tmp_path / "out.exr")])
    assert args.run(args) == 0
    _, meta = read_exr(tmp_path / "out.exr")
    out = read_image(tmp_path / "out.exr")
    assert out.shape == (48, 64, 3)
    assert meta["method"] == "patch" and meta["boundary"] == "edge" and meta["blocks"] == [4, 4]  # 8, 16, 16, 8 rows
    assert meta["channel_wavelengths_nm"] == [656, 531, 486] and "camera" in meta and meta["seconds"] >= 0
    linear_in = read_image(tmp_path / "in.png")  # sRGB decoded
    # far from the edge the output equals the linearised input; the PNG re-encodes it
    assert np.abs(out[:, :20] - linear_in[:, :20]).max() < 1e-5
    assert np.abs(read_image(tmp_path / "out.png", linearize=False)[:, :20]
                  - read_image(tmp_path / "in.png", linearize=False)[:, :20]).max() <= 1 / 255 + 1e-9
    # default: interp
    args = parser().parse_args(["degrade", str(tmp_path / "out.exr"), "--psf-grid", str(tmp_path / "grid.exr"),
                                "-o", str(tmp_path / "twice.exr"), "--boundary", "reflect"])
    assert args.run(args) == 0
    assert read_exr(tmp_path / "twice.exr")[1]["method"] == "interp"
    assert (tmp_path / "twice.png").is_file()


def test_command_line_errors_leave_nothing(tmp_path):
    g = small_grid()
    del g.meta["pinhole_focal_mm"]
    g.write(str(tmp_path / "old.exr"))
    write = tmp_path / "in.exr"
    from solas_mi.imageio import write_exr

    write_exr(write, {"Y": np.zeros((30, 40), np.float32)})
    for extra, message in ((["--psf-grid", str(tmp_path / "old.exr"), "-o", str(tmp_path / "o.exr")], "psf-grid"),
                           (["--psf-grid", str(tmp_path / "old.exr"), "-o", str(tmp_path / "o.png")], ".exr")):
        args = parser().parse_args(["degrade", str(write), *extra])
        with pytest.raises(SolasError, match=message):
            args.run(args)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.exr", "old.exr"]
    with pytest.raises(SystemExit):
        parser().parse_args(["degrade", str(write), "--psf-grid", "g.exr", "-o", "o.exr", "--method", "fft"])
