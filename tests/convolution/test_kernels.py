"""PSF grid → pixel kernels: exact pixel integration, kernel sums, interpolation hats, the paper's block layouts."""

import numpy as np
import pytest

from solas_mi.convolution.interp import hats
from solas_mi.convolution.kernels import kernel_radius, layout, node_kernels, overlap_matrices
from solas_mi.convolution.patch import block_layout


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
def test_kernel_sums(normalization, synthetic):
    pix = synthetic.pixel_um(128)
    pitch = pix / 3
    p = synthetic.gaussian(33, 1.5 * pix, pitch)
    scale = {"sum": 1.0, "none": 0.7 / pitch**2, "peak": 1 / p.max()}[normalization]
    g = synthetic.make_grid(np.broadcast_to(p * scale, (1, 2, 2, 33, 33)), pitch, normalization=normalization)
    lay = layout(g, 128, 128)
    k, _ = node_kernels(g, lay, 0, np.array([0, 1]), np.array([1, 0]), kernel_radius(33, lay.q))
    expected = 0.7 if normalization == "none" else 1.0
    np.testing.assert_allclose(k.sum(axis=(1, 2)), expected, rtol=1e-6)


def test_hats_are_a_partition_of_unity():
    knots = np.array([3.2, 10.0, 17.5, 40.0])
    used, lo, w, length = hats(knots, -5, 60)
    total = np.zeros(60 + length)
    for a, row in zip(lo, w):
        total[a : a + length] += row
    np.testing.assert_allclose(total[:60], 1.0, atol=1e-12)
    assert list(used) == [0, 1, 2, 3]


def test_paper_block_layouts(synthetic):
    """±2° grids on a 1280×960 image: 8×8 → 8×6 blocks of 160 px, 32×32 → 32×24 blocks of 40 px."""
    for n, block in ((8, 160), (32, 40)):
        g = synthetic.make_grid(np.ones((1, n, n, 3, 3)) / 9, 0.5)
        rows, cols = block_layout(layout(g, 1280, 960))
        assert [b - a for _, a, b in cols] == [block] * n
        assert [b - a for _, a, b in rows] == [block] * (n * 3 // 4)
        assert [m for m, _, _ in rows] == list(range(n // 8, n - n // 8))  # the rows inside the image
        assert cols[0][1] == 0 and cols[-1][2] == 1280 and rows[0][1] == 0 and rows[-1][2] == 960
