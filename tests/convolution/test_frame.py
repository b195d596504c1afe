"""The frame's own camera (`optics.frame`) on the convolution: pixels mapped to field angles, frames the
lens does not cover refused with the numbers."""

import math

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.convolution.kernels import layout
from solas_mi.convolution.methods import degrade
from solas_mi.optics.frame import FrameCamera, parse_frame
from solas_mi.psf.grid import psf_grid

W, H = 320, 240


@pytest.fixture(scope="module")
def grid(doublet):
    return psf_grid(
        doublet,
        grid=(6, 8),
        wavelengths_nm=[531.0],
        size=64,
        pitch_um=1.0,
        method="geometric",
        rays=64,
        field_range_deg=(2.0, 1.5),
    )


def test_kannala_brandt_and_polynomial_map_radius_to_angle():
    kb = FrameCamera("kannala-brandt", intrinsics=(300.0, 300.0, 100.0, 50.0), coefficients=(0.0, 0.0, 0.0, 0.0))
    tx, ty = kb.tangents(np.array([100.0 + 300 * 0.5]), np.array([50.0]), 400, 300)  # θ = 0.5 rad, equidistant
    assert tx[0] == pytest.approx(math.tan(0.5), rel=1e-5) and ty[0] == pytest.approx(0, abs=1e-12)
    k1 = FrameCamera("kannala-brandt", intrinsics=(300.0, 300.0, 100.0, 50.0), coefficients=(0.1, 0.0, 0.0, 0.0))
    _, ty = k1.tangents(np.array([100.0]), np.array([50.0 - 300 * 0.5 * (1 + 0.1 * 0.25)]), 400, 300)  # up: +y
    assert ty[0] == pytest.approx(math.tan(0.5), rel=1e-5)
    poly = FrameCamera("polynomial", intrinsics=(1.0, 1.0, 0.0, 0.0), coefficients=(330.0, 10.0))
    r = 330 * 0.3 + 10 * 0.09
    tx, _ = poly.tangents(np.array([r]), np.array([0.0]), 10, 10)
    assert tx[0] == pytest.approx(math.tan(0.3), rel=1e-5)


def test_a_frame_spanning_the_grids_field_is_the_default(grid):
    img = np.random.default_rng(0).random((H, W))
    same = degrade(img, grid, frame=FrameCamera("fov", fov_deg=2.0))
    assert np.allclose(same, degrade(img, grid), atol=1e-6)
    fx = (W / 2) / math.tan(math.radians(2.0))
    assert np.allclose(
        degrade(img, grid, frame=parse_frame(intrinsics=f"{fx},{fx},{W / 2 - 0.5},{H / 2 - 0.5}")), same, atol=1e-6
    )


def test_a_narrower_frame_has_larger_pixels_blur(grid):
    """A frame spanning ±1 deg on the same pixels: each pixel is half as wide on the sensor, so the
    blur spans twice the pixels."""
    point = np.zeros((H, W))
    point[H // 2, W // 2] = 1.0
    width = []
    for fov in (2.0, 1.0):
        out = degrade(point, grid, frame=FrameCamera("fov", fov_deg=fov))
        x = np.arange(W) - W / 2
        line = out.sum(axis=0)
        mean = (x * line).sum() / line.sum()
        width.append(math.sqrt(((x - mean) ** 2 * line).sum() / line.sum()))
    assert width[1] / width[0] == pytest.approx(2.0, rel=0.15)


def test_the_principal_point_moves_the_nodes(grid):
    fx = (W / 2) / math.tan(math.radians(1.5))
    a = layout(grid, W, H, FrameCamera("pinhole", intrinsics=(fx, fx, W / 2 - 0.5, H / 2 - 0.5)))
    b = layout(grid, W, H, FrameCamera("pinhole", intrinsics=(fx, fx, W / 2 + 9.5, H / 2 - 4.5)))
    assert np.allclose(b.col_knots - a.col_knots, 10) and np.allclose(b.row_knots - a.row_knots, -4)


@pytest.mark.parametrize(
    "frame, what",
    [
        (FrameCamera("fov", fov_deg=3.0), "up to 3 deg in x"),
        (FrameCamera("fov", fov_deg=2.0, fov_axis="y"), "in y"),
        (FrameCamera("pinhole", intrinsics=(10000.0, 9000.0, 160.0, 120.0)), "square"),
        (
            FrameCamera("kannala-brandt", intrinsics=(200.0, 200.0, 160.0, 120.0), coefficients=(0, 0, 0, 0)),
            "does not cover",
        ),
    ],
)
def test_frames_the_grid_does_not_take_are_refused_with_numbers(grid, frame, what):
    with pytest.raises(SolasError, match=what):
        degrade(np.ones((H, W)), grid, frame=frame)


def test_a_fisheye_frame_the_lens_covers_is_degraded(grid):
    """Refused until fisheye frames were laid out in field angle (`convolution.curved`,
    tests/convolution/test_fisheye_frames.py); on the axis an equidistant frame is the pinhole frame of the
    same focal length."""
    point = np.zeros((H, W))
    point[120, 160] = 1.0
    fisheye = degrade(
        point,
        grid,
        frame=FrameCamera("kannala-brandt", intrinsics=(20000.0, 20000.0, 160.0, 120.0), coefficients=(0, 0, 0, 0)),
    )
    pinhole = degrade(point, grid, frame=FrameCamera("pinhole", intrinsics=(20000.0, 20000.0, 160.0, 120.0)))
    r, c = np.indices(point.shape)
    for out in (fisheye, pinhole):
        assert out.sum() == pytest.approx(1, abs=1e-5) and np.isfinite(out).all()
        assert ((out * c).sum(), (out * r).sum()) == (pytest.approx(160, abs=0.01), pytest.approx(120, abs=0.01))
    # widths to 1 %: the pinhole frame blends the four nearest nodes' kernels placed ±0.6 px apart by the
    # lens's distortion, the fisheye frame draws them at the frame's point, scaled by the lens's local focal length
    widths = [np.sqrt((out * (c - 160) ** 2).sum()) for out in (fisheye, pinhole)]
    assert widths[0] == pytest.approx(widths[1], rel=0.01)


def test_bad_frame_cameras_are_refused():
    for kwargs in (
        {"model": "fov", "fov_deg": 95.0},
        {"model": "pinhole", "intrinsics": (0, 1, 0, 0)},
        {"model": "kannala-brandt", "intrinsics": (1, 1, 0, 0), "coefficients": (1.0,)},
        {"model": "x"},
    ):
        with pytest.raises(SolasError):
            FrameCamera(**kwargs)
    with pytest.raises(SolasError, match="one frame camera"):
        parse_frame(fov=1.0, intrinsics="1,1,0,0")
