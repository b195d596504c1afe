"""Fisheye frames (`convolution.curved`): every pixel's PSF interpolated in field angle and drawn in the
frame's own pixels. Checked against routes that do not go through the curved layout: a point placed at a
node's field lands where the calibration's own formula says, with that node's PSF scaled by the
Jacobians derived here by hand; a pinhole frame laid out this way gives `interp`'s separable result."""

import argparse
import math

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.convolution import interp
from solas_mi.convolution.commands import register
from solas_mi.convolution.curved import CurvedLayout, curved_layout
from solas_mi.convolution.depth import degrade_depth
from solas_mi.convolution.kernels import layout
from solas_mi.convolution.methods import degrade
from solas_mi.imageio import read_exr, write_exr
from solas_mi.optics.frame import FrameCamera
from solas_mi.psf.depth import DepthGrid

W, H = 321, 241
NODE_DEG = 35.0  # grid column 6 of 9 over ±70°, "edges" sampling
FOCAL = 100.0  # the synthetic grids' pinhole focal length (mm)


@pytest.fixture(scope="module")
def wide(synthetic_grid):
    """A rectilinear synthetic lens over ±70° (9×9 nodes, 17.5° apart), a Gaussian of its own width at
    every node (truncated by the 31-sample window: the test uses the PSF's own variance)."""
    sig = np.random.default_rng(7).uniform(1000.0, 2000.0, (9, 9))
    psfs = np.stack([[synthetic_grid.gaussian(31, s, 300.0) for s in row] for row in sig])[None]
    return synthetic_grid.from_psfs(psfs, 300.0, field=(70.0, 70.0), sampling="edges")


def radius_px(model: str, theta: np.ndarray | float):
    """Radius (px) at polar angle θ of the two frames below, written out from their published forms."""
    if model == "kannala-brandt":
        return 160.0 * theta * (1 + 0.02 * theta**2 - 0.004 * theta**4)
    return 150.0 * theta + 12.0 * theta**2 - 4.0 * theta**3 + 0.5 * theta**4  # WoodScape's a1..a4


def frame_for(model: str) -> tuple[FrameCamera, int]:
    """The model's frame, its principal point placed so that field (NODE_DEG, 0) lands on a pixel centre;
    that pixel's column."""
    r = radius_px(model, math.radians(NODE_DEG))
    cx = 160.0 + (round(r) - r)
    if model == "kannala-brandt":
        return FrameCamera(
            model, intrinsics=(160.0, 160.0, cx, 120.0), coefficients=(0.02, -0.004, 0.0, 0.0)
        ), 160 + round(r)
    return FrameCamera(model, intrinsics=(1.0, 1.0, cx, 120.0), coefficients=(150.0, 12.0, -4.0, 0.5)), 160 + round(r)


def moments(img: np.ndarray) -> tuple[float, float, float, float]:
    r, c = np.indices(img.shape)
    m = img.sum()
    cc, rr = (img * c).sum() / m, (img * r).sum() / m
    return cc, rr, (img * (c - cc) ** 2).sum() / m, (img * (r - rr) ** 2).sum() / m


@pytest.mark.parametrize("model", ["kannala-brandt", "polynomial"])
def test_a_point_lands_where_the_calibration_says_blurred_by_its_fields_psf(wide, model):
    frame, col = frame_for(model)
    point = np.zeros((H, W))
    point[120, col] = 1.0
    cc, rr, vc, vr = moments(degrade(point, wide, frame=frame))
    assert (cc, rr) == (pytest.approx(col, abs=0.01), pytest.approx(120, abs=0.01))
    # on the x axis, the radial scale is dr/dθ and the tangential one r/tan θ (θy moves the point by
    # r·sin φ, tan φ = tan θy / tan θx); the rectilinear lens's are f/cos² θx and f
    t, d = math.radians(NODE_DEG), 1e-6
    radial = (radius_px(model, t + d) - radius_px(model, t - d)) / (2 * d) * math.cos(t) ** 2 / FOCAL
    tangential = radius_px(model, t) / math.tan(t) / FOCAL
    psf = wide.data[0, 4, 6].astype(np.float64)
    x = (np.arange(31) - 15) * 0.3
    var_mm = (psf.sum(axis=0) * x**2).sum() / psf.sum()
    for measured, scale in ((vc, radial), (vr, tangential)):  # the PSF's, its samples' and the pixel boxes' variances
        assert measured == pytest.approx(scale**2 * (var_mm + 0.3**2 / 12) + 1 / 6, rel=0.01)


def test_a_pinhole_frame_laid_out_in_field_angle_gives_interp(synthetic):
    rng = np.random.default_rng(3)
    grid = synthetic.varied_grid(rng, W, max_offset_px=0.0)
    img = synthetic.smooth_texture(rng, H, W)
    frame = FrameCamera("fov", fov_deg=2.0)
    curved = curved_layout(grid, W, H, frame)
    assert isinstance(curved, CurvedLayout)
    straight = interp.convolve_channel(img, grid, layout(grid, W, H, frame), 0, "edge", np.float64)
    bent = interp.convolve_channel(img, grid, curved, 0, "edge", np.float64)
    # hats linear in θ rather than in tan θ over ±2°, PSF squares as 2×2 points: measured 8e-6
    assert np.abs(bent - straight).max() < 1e-4 * img.max()


def test_light_is_kept_and_lateral_colour_moves_the_other_wavelengths(wide, synthetic_grid):
    frame, col = frame_for("kannala-brandt")
    img = np.zeros((H, W))
    img[40:200, 60:260] = synthetic_grid.gaussian(200, 40.0, 1.0)[20:180]
    out = degrade(img, wide, boundary="zero", frame=frame)
    assert out.sum() == pytest.approx(img.sum(), rel=1e-6) and np.isfinite(out).all()
    two = synthetic_grid.from_psfs(
        np.repeat(wide.data, 2, axis=0),
        300.0,
        field=(70.0, 70.0),
        sampling="edges",
        offsets_um=np.stack([np.zeros((9, 9, 2)), np.full((9, 9, 2), [300.0, 0.0])]),
    )
    point = np.zeros((H, W, 2))
    point[120, col] = 1.0
    out = degrade(point, two, frame=frame)
    shift = moments(out[..., 0])[0] - moments(out[..., 1])[0]  # channel 0: the longer wavelength, 0.3 mm right
    assert shift == pytest.approx(
        0.3
        * (
            radius_px("kannala-brandt", math.radians(NODE_DEG) + 1e-6)
            - radius_px("kannala-brandt", math.radians(NODE_DEG) - 1e-6)
        )
        / 2e-6
        * math.cos(math.radians(NODE_DEG)) ** 2
        / FOCAL,
        rel=0.01,
    )


def test_fisheye_frames_take_interp_and_a_lens_that_covers_them(wide, synthetic):
    frame, _ = frame_for("polynomial")
    with pytest.raises(SolasError, match="interpolated in field angle"):
        degrade(np.ones((H, W)), wide, method="patch", frame=frame)
    with pytest.raises(SolasError, match="does not cover"):
        degrade(np.ones((H, W)), synthetic.varied_grid(np.random.default_rng(0), W), frame=frame)


def test_a_fisheye_frame_with_a_depth_map_at_one_node_is_that_nodes_convolution(wide, synthetic_grid):
    """The depth-aware convolution lays each distance's grid out the same way: a frame all at one node's
    distance gives that node's fisheye convolution; a near square hides the far light behind it."""
    frame, _ = frame_for("kannala-brandt")
    sharp = synthetic_grid.from_psfs(
        np.broadcast_to(synthetic_grid.delta(31), wide.data.shape), 300.0, field=(70.0, 70.0), sampling="edges"
    )
    both = DepthGrid([sharp, wide], (math.inf, 5.0), {})
    img = synthetic_grid.gaussian(W, 60.0, 1.0)[40 : 40 + H] * 1e4
    assert np.allclose(
        degrade_depth(img, np.full((H, W), 5.0), both, frame=frame),
        degrade(img, wide, frame=frame),
        rtol=0,
        atol=1e-5 * img.max(),
    )
    depth = np.full((H, W), math.inf)
    depth[100:140, 140:180] = 5.0
    flat = np.ones((H, W))
    out = degrade_depth(flat, depth, both, frame=frame)  # filled
    added = degrade_depth(flat, depth, both, occlusion="none", frame=frame)
    assert np.abs(out - 1).max() < 0.02 and added.max() > 1.2  # the near blur is laid over the far, not added


def test_the_command_line_takes_a_fisheye_calibration(wide, tmp_path):
    wide.write(str(tmp_path / "grid.exr"))
    write_exr(tmp_path / "in.exr", {"Y": np.ones((H, W), dtype=np.float32)}, {})
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="command"))
    args = p.parse_args(
        [
            "degrade",
            str(tmp_path / "in.exr"),
            "--psf-grid",
            str(tmp_path / "grid.exr"),
            "-o",
            str(tmp_path / "out.exr"),
            "--fisheye",
            "polynomial:1,1,160,120,150,12,-4,0.5",
        ]
    )
    assert args.run(args) == 0
    _channels, meta = read_exr(tmp_path / "out.exr")
    assert meta["frame_camera"]["model"] == "polynomial" and meta["camera"]["projection"].startswith("frame")
    assert meta["frame_camera"]["extent_deg"][0] == pytest.approx(67.5, abs=1) and meta["nodes"] == [9, 9]
