"""`degrade` with each registered method: one ordinary convolution for invariant grids, energy, seams, chief-ray offsets, the doublet's grid against the tracer, bad input."""

import math

import numpy as np
import pytest

from solas_mi.convolution import METHODS, degrade
from solas_mi.convolution.kernels import grid_camera, kernel_radius, layout, pixel_kernels
from solas_mi.convolution.patch import block_layout
from solas_mi.errors import SolasError
from solas_mi.psf import psf, psf_grid
from solas_mi.psf.grid import PSFGrid


@pytest.mark.parametrize("boundary", ["edge", "zero", "reflect"])
@pytest.mark.parametrize("method", list(METHODS))
def test_invariant_grid_is_one_convolution(method, boundary, synthetic):
    rng = np.random.default_rng(0)
    h, w = 72, 96
    pix = synthetic.pixel_um(w)
    pitch = pix / 5
    p = synthetic.gaussian(41, 1.3 * pix, pitch)
    p = np.roll(p, 2, axis=1)  # asymmetric
    offset = np.broadcast_to([2.4 * pix, -1.3 * pix], (1, 8, 8, 2))  # the same chief-ray offset everywhere
    g = synthetic.make_grid(np.broadcast_to(p, (1, 8, 8, 41, 41)), pitch, offset)
    img = rng.random((h, w))
    lay = layout(g, w, h)
    k, shift = pixel_kernels(g.data[0, :1, 0], lay.q, lay.offsets[0, :1, 0], np.ones(1), kernel_radius(41, lay.q))
    ref = synthetic.reference_convolution(img, k[0], shift[0], boundary)
    out = degrade(img, g, method, boundary)
    assert out.dtype == np.float32
    assert np.abs(out - ref).max() < 1e-6
    assert np.abs(degrade(img, g, method, boundary, dtype=np.float64) - ref).max() < 1e-12


@pytest.mark.parametrize("method", list(METHODS))
def test_invariant_rgb_grid_uses_longest_wavelength_for_red(method, synthetic):
    rng = np.random.default_rng(1)
    h, w = 48, 64
    pix = synthetic.pixel_um(w)
    pitch = pix / 4
    p = np.stack([synthetic.gaussian(21, s * pix, pitch) for s in (0.6, 1.0, 2.0)])  # for 486, 656, 531 nm
    g = synthetic.make_grid(
        np.broadcast_to(p[:, None, None], (3, 4, 4, 21, 21)), pitch, wavelengths=(486.0, 656.0, 531.0)
    )
    img = rng.random((h, w, 3))
    out = degrade(img, g, method, dtype=np.float64)
    lay = layout(g, w, h)
    radius = kernel_radius(21, lay.q)
    for channel, k in zip(range(3), (1, 2, 0)):  # R ← 656, G ← 531, B ← 486
        kern, shift = pixel_kernels(g.data[k, :1, 0], lay.q, np.zeros((1, 2)), np.ones(1), radius)
        np.testing.assert_allclose(
            out[..., channel], synthetic.reference_convolution(img[..., channel], kern[0], shift[0]), atol=1e-12
        )


@pytest.mark.parametrize("method", list(METHODS))
def test_delta_grid_returns_input(method, synthetic):
    rng = np.random.default_rng(2)
    h, w = 60, 80
    delta = np.zeros((5, 5))
    delta[2, 2] = 1.0
    pitch = synthetic.pixel_um(w) * 1e-4  # a PSF sample 1e-4 px wide: a point
    g = synthetic.make_grid(np.broadcast_to(delta, (1, 8, 8, 5, 5)), pitch)
    img = rng.random((h, w))
    assert np.abs(degrade(img, g, method) - img).max() < 1e-4
    # offset by whole pixels (3 right, 2 up): the image moves, exactly
    g = synthetic.make_grid(
        np.broadcast_to(delta, (1, 8, 8, 5, 5)),
        pitch,
        np.broadcast_to([3 * synthetic.pixel_um(w), 2 * synthetic.pixel_um(w)], (1, 8, 8, 2)),
    )
    out = degrade(img, g, method, "zero")
    assert np.abs(out[:-2, 3:] - img[2:, :-3]).max() < 1e-4
    assert np.abs(out[-2:]).max() < 1e-4 and np.abs(out[:, :3]).max() < 1e-4


@pytest.mark.parametrize("method", list(METHODS))
def test_energy_is_preserved(method, synthetic):
    """Sum-normalised kernels: Σ out = Σ in for light away from the image border (interp: any content;
    patch: content away from block borders, where each block's kernel spreads its own light)."""
    rng = np.random.default_rng(3)
    h, w = 192, 256  # 8×6 blocks of 32 px; kernels reach 11 px
    g = synthetic.varied_grid(rng, w)
    img = np.zeros((h, w))
    if method == "interp":
        img[20:-20, 20:-20] = rng.random((h - 40, w - 40))
    else:
        img[16::32, 16::32] = rng.random((6, 8))  # a dot at every block centre
    out = degrade(img, g, method, "zero", dtype=np.float64)
    assert out.sum() == pytest.approx(img.sum(), rel=1e-9)
    assert np.abs(out - img).max() > 0.01  # it did blur


def test_transmission_normalised_energy(synthetic):
    """ "none" grids: PSF·pitch² sums to the transmitted fraction; with interp each input pixel keeps
    the bilinear blend of its nodes' transmissions (vignetting carried)."""
    rng = np.random.default_rng(4)
    h, w = 96, 128
    t = rng.uniform(0.5, 1.0, (8, 8))
    g = synthetic.varied_grid(rng, w, normalization="none", transmission=t)
    img = np.zeros((h, w))
    img[20:-20, 20:-20] = rng.random((h - 40, w - 40))
    out = degrade(img, g, "interp", "zero", dtype=np.float64)
    lay = layout(g, w, h)
    wy = np.stack([np.interp(np.arange(h), lay.row_knots, e) for e in np.eye(8)])
    wx = np.stack([np.interp(np.arange(w), lay.col_knots, e) for e in np.eye(8)])
    t_map = wy.T @ t @ wx
    assert out.sum() == pytest.approx((img * t_map).sum(), rel=1e-6)
    # a uniform transmission scales the output exactly
    g = synthetic.varied_grid(np.random.default_rng(5), w, normalization="none", transmission=np.full((8, 8), 0.8))
    assert degrade(img, g, "interp", "zero", dtype=np.float64).sum() == pytest.approx(0.8 * img.sum(), rel=1e-9)


def test_uniform_input_stays_uniform(synthetic):
    """patch: every output pixel's kernel sums to 1, so a uniform input stays uniform, borders included
    ("edge"), whatever the PSFs and offsets. interp spreads each input pixel with its own blended PSF
    (light is conserved, as in the lens): a uniform input stays uniform to the second derivative of
    the PSF field — exactly for a spatially invariant grid, within 2e-3 for a smoothly varying one."""
    rng = np.random.default_rng(6)
    g = synthetic.varied_grid(rng, 128, max_offset_px=3.0)
    np.testing.assert_allclose(degrade(np.full((96, 128, 3), 0.25), g, "patch"), 0.25, rtol=2e-6)
    pix = synthetic.pixel_um(128)
    f = np.linspace(0.0, 1.0, 8)
    sigma = (1.0 + 0.5 * f[None, :] + 0.3 * f[:, None]) * pix  # 1–1.8 px across the field
    g = synthetic.make_grid(
        np.stack([[synthetic.gaussian(65, s, pix / 4) for s in row] for row in sigma])[None], pix / 4
    )
    np.testing.assert_allclose(degrade(np.full((96, 128), 0.25), g, "interp"), 0.25, rtol=2e-3)


def test_interp_has_no_seams_and_patch_has(synthetic):
    """Gradient energy across block borders relative to that between the other pixel pairs."""
    rng = np.random.default_rng(7)
    h, w = 192, 256  # blocks of 32 px
    g = synthetic.varied_grid(rng, w)
    img = synthetic.smooth_texture(rng, h, w)
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


@pytest.mark.parametrize("method", list(METHODS))
def test_chief_ray_offset_moves_a_dot(method, synthetic):
    h, w = 96, 128
    pix = synthetic.pixel_um(w)
    pitch = pix / 4
    g = synthetic.make_grid(
        np.broadcast_to(synthetic.gaussian(33, 1.5 * pix, pitch), (1, 8, 8, 33, 33)),
        pitch,
        np.broadcast_to([3.7 * pix, -2.2 * pix], (1, 8, 8, 2)),
    )  # 3.7 px right, 2.2 px down
    img = np.zeros((h, w))
    img[40, 50] = 1.0
    np.testing.assert_allclose(synthetic.centroid(degrade(img, g, method, dtype=np.float64)), [53.7, 42.2], atol=1e-9)


def test_interp_blends_the_offsets_of_the_nodes(synthetic):
    """Random offsets per node: a dot anywhere moves by the bilinear blend of its nodes' offsets."""
    rng = np.random.default_rng(8)
    h, w = 96, 128
    g = synthetic.varied_grid(rng, w, max_offset_px=3.0)
    g.data[:] = g.data[0, 0, 0]  # one PSF, symmetric: only the offsets differ
    lay = layout(g, w, h)
    for row, col in ((40, 50), (14, 115), (84, 13)):  # ≥ R + 3 px from the borders
        img = np.zeros((h, w))
        img[row, col] = 1.0
        ry = np.array([np.interp(row, lay.row_knots, e) for e in np.eye(8)])
        rx = np.array([np.interp(col, lay.col_knots, e) for e in np.eye(8)])
        expected = np.einsum("m,n,mnk->k", ry, rx, lay.offsets[0])
        c = synthetic.centroid(degrade(img, g, "interp", "zero", dtype=np.float64))
        np.testing.assert_allclose(c - [col, row], expected, atol=1e-9)


@pytest.fixture(scope="module")
def doublet_grid(doublet):
    return psf_grid(doublet, grid=(4, 4), size=64, pitch_um=1.0, pupil_samples=32, wavelengths_nm=[656, 531, 486])


def tracer_centroids(lens, cam, field, synthetic) -> np.ndarray:
    """(column, row) pixel positions, 656/531/486 nm, of the tracer's chief ray at `field` plus the
    PSF's own centroid there (its energy is not centred on the chief ray)."""
    from solas_mi.optics.pupil import chief_rays

    found = []
    for wl in (656.0, 531.0, 486.0):
        xy = chief_rays(lens, np.array([field]), np.array([wl])).image_xy[0] * 1e3  # µm
        p = psf(lens, tuple(field), wl, size=64, pitch_um=1.0, pupil_samples=32)
        dx, dy = synthetic.centroid(p.data) - 32  # µm right, µm down from the chief ray
        found.append(
            [(xy[0] + dx) / cam.pitch_um + cam.width / 2 - 0.5, cam.height / 2 - 0.5 - (xy[1] - dy) / cam.pitch_um]
        )
    return np.array(found)


def test_dot_lands_where_the_tracer_says(doublet, doublet_grid, synthetic):
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
        found = np.array(
            [
                synthetic.centroid(out[row - 20 : row + 21, col - 20 : col + 21, c]) + [col - 20, row - 20]
                for c in range(3)
            ]
        )
        expected = tracer_centroids(doublet, cam, field, synthetic)
        np.testing.assert_allclose(found, expected, atol=tolerance)
        if tolerance < 0.1:
            on_node = (img, row, col, expected)
    # the offsets matter: discarding them (chief rays on the ideal points) misplaces R by > 1 px
    img, row, col, expected = on_node
    g = PSFGrid(
        doublet_grid.data,
        doublet_grid.fields_deg,
        np.repeat(cam.ideal_mm(doublet_grid.fields_deg)[None], 3, axis=0),
        doublet_grid.wavelengths_nm,
        doublet_grid.pitch_um,
        doublet_grid.meta,
    )
    out = degrade(img, g, "interp")
    wrong = synthetic.centroid(out[row - 20 : row + 21, col - 20 : col + 21, 0]) + [col - 20, row - 20]
    assert np.abs(wrong - expected[0]).max() > 1.0
    # lateral colour: the chief rays of 656 and 486 nm are 0.57 px apart in x at (1.5°, 0.5°); their
    # PSFs' centroids bring the R and B centroids to 0.12 px
    m, n = np.argwhere(np.isclose(doublet_grid.fields_deg, [1.5, 0.5]).all(axis=-1))[0]
    lay = layout(doublet_grid, w, h)
    assert lay.offsets[0, m, n, 0] - lay.offsets[2, m, n, 0] == pytest.approx(-0.57, abs=0.02)


def test_bad_method_and_boundary(synthetic):
    img = np.zeros((30, 40))
    with pytest.raises(SolasError, match="method 'fft'.*interp, patch"):
        degrade(img, synthetic.small_grid(), "fft")
    with pytest.raises(SolasError, match="boundary 'wrap'.*edge, reflect, zero"):
        degrade(img, synthetic.small_grid(), "interp", "wrap")


def test_grid_without_camera_metadata(synthetic):
    g = synthetic.small_grid()
    del g.meta["pinhole_focal_mm"]
    with pytest.raises(SolasError, match="solas-mi psf-grid"):
        degrade(np.zeros((30, 40)), g)


def test_image_not_covered(synthetic):
    g = synthetic.small_grid(field=(2.0, 1.0))  # ±1° in y cannot cover a square image spanning ±2°
    with pytest.raises(SolasError, match="does not cover the image.*rows"):
        degrade(np.zeros((40, 40)), g)
    degrade(np.zeros((20, 40)), g)  # ±1° tall: covered


def test_channel_count_mismatch(synthetic):
    g = synthetic.make_grid(np.broadcast_to(synthetic.gaussian(9, 2.0, 1.0), (3, 4, 4, 9, 9)), 1.0)
    with pytest.raises(SolasError, match="3 wavelengths.*1 channel"):
        degrade(np.zeros((30, 40)), g)
    with pytest.raises(SolasError, match="H×W or H×W×C"):
        degrade(np.zeros(5), g)


def test_tiny_image_and_large_kernel(synthetic):
    g = synthetic.make_grid(
        np.broadcast_to(synthetic.gaussian(61, 5000.0, 800.0), (1, 4, 4, 61, 61)), 800.0
    )  # ±14 px on 3×4 px
    for boundary in ("edge", "zero", "reflect"):
        for method in METHODS:
            out = degrade(np.full((3, 4), 0.5), g, method, boundary)
            assert out.shape == (3, 4) and np.isfinite(out).all()
            if boundary != "zero":
                np.testing.assert_allclose(out, 0.5, rtol=1e-5)
