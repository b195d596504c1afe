"""Cross-validation of the PSF-grid convolution against the direct render (`solas_mi.crossval`,
`solas_mi.report`)."""
import argparse
import math

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.metrics.annuli import annulus_map
from solas_mi.validation import crossval as C
from solas_mi.validation import error_vs_time as R

# ------------------------------------------------------------------------------------------ cheap units

def test_annulus_map_follows_the_automotive_annuli():
    rings = annulus_map(240, 320)
    assert rings[120, 160] == 0 and rings[0, 0] == 2 and rings[-1, -1] == 2
    y, x = np.mgrid[0:240, 0:320]
    r = np.hypot(x - 159.5, y - 119.5) / math.hypot(160, 120)  # R: centre to the image's corner
    assert np.array_equal(rings, np.where(r < 0.24, 0, np.where(r < 0.6, 1, 2)))


def test_tangent_cos3_matches_the_camera_tangents():
    c = C.tangent_cos3(4, 2, 2.0)
    t = math.tan(math.radians(2.0)) / 2
    assert c[0, 0] == pytest.approx((1 + (1.5 * t) ** 2 + (0.5 * t) ** 2) ** -1.5)
    assert np.allclose(c, c[::-1, ::-1])


def test_compare_known_errors_and_noise_removal():
    rng = np.random.default_rng(1)
    ref = 0.2 + rng.random((60, 80, 3))
    same = C.compare(ref, ref)
    assert same.rel_rmse == 0 and same.ssim == pytest.approx(1.0) and math.isinf(same.psnr_db)
    img = ref * 1.01
    e = C.compare(img, ref)
    assert e.rel_rmse == pytest.approx(0.01, rel=1e-9)
    assert e.psnr_db == pytest.approx(20 * math.log10(ref.max() / math.sqrt(np.mean((0.01 * ref) ** 2))))
    assert set(e.annuli) == {"centre", "middle", "edge"}
    assert all(v == pytest.approx(0.01, rel=1e-9) for v in e.annuli.values())
    # a noise level given for the reference is removed in quadrature
    rms = math.sqrt(np.mean(ref ** 2))
    assert C.compare(img, ref, ref_noise=0.006 * rms).rel_rmse_denoised == pytest.approx(0.008, rel=1e-6)
    assert C.denoise(0.01, 0.02) == 0.0
    with pytest.raises(SolasError, match="shape"):
        C.compare(ref[:10], ref)


def test_bad_input_is_a_solas_error(tmp_path):
    with pytest.raises(SolasError, match="METHOD:PSF"):
        C.Case.parse("blur:geometric:32x24")
    with pytest.raises(SolasError, match="32x24"):
        C.Case.parse("interp:geometric:32")
    assert C.Case.parse("patch:fraunhofer:8x6") == C.Case("patch", "fraunhofer", (8, 6))
    with pytest.raises(SolasError, match="no such image"):
        C.load_input(str(tmp_path / "missing.png"))
    with pytest.raises(SolasError, match="non-negative"):
        C.load_input(-np.ones((16, 16, 3)))
    with pytest.raises(SolasError, match="H×W"):
        C.load_input(np.ones((16, 16, 4)))
    with pytest.raises(SolasError, match="larger"):
        C.load_input(np.ones((16, 16, 3)), sensor=(32, 32))
    with pytest.raises(SolasError, match="scale"):
        C.load_input(np.ones((16, 16, 3)), scale=2.0)
    with pytest.raises(SolasError, match="comma-separated"):
        R._ints("3,x", (), "--spp")


def test_load_input_area_averages():
    img = np.arange(16 * 16 * 3, dtype=float).reshape(16, 16, 3)
    small = C.load_input(img, sensor=(8, 8))
    assert small.shape == (8, 8, 3)
    assert np.allclose(small[0, 0], img[:2, :2].mean(axis=(0, 1)))
    assert C.load_input(img[..., 0], scale=0.5).shape == (8, 8, 3)


def test_commands_register_and_parse():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command")
    C.register(sub)
    R.register(sub)
    a = parser.parse_args(["crossval", "solas-doublet", "img.png", "-o", "d", "--scale", "0.25", "--spp", "96"])
    assert a.run is C.run_crossval and a.spp == 96 and a.scale == 0.25
    a = parser.parse_args(["report", "error-vs-time", "solas-doublet", "img.png", "-o", "d", "--sensor", "320x240"])
    assert a.run is R.run_error_vs_time and a.sensor == "320x240"
    assert R._grids("4x3,64x48", (), "--interp-grids") == ((4, 3), (64, 48))
    with pytest.raises(SystemExit):
        parser.parse_args(["crossval", "solas-doublet", "img.png", "-o", "d", "--scale", "0.5", "--sensor", "8x8"])


# ------------------------------------------------------------------------------- the two engines agree

def test_uniform_white_radiometry_agrees(doublet):
    """A white object: the render's relative illumination (0.986 at the edge middle, 0.978 at the
    corner, of the on-axis irradiance, which is ≈ 1.01 ideal-camera units) is what interp gives with
    cos³θ, "none" kernels and the unit factor k."""
    from solas_mi.optics.camera import pinhole_focal_mm
    from solas_mi.optics.illumination import axis_irradiance, ideal_irradiance

    w, h = 160, 120
    white = np.ones((h, w, 3))
    grid, _ = C.psf_grid_for(doublet, "geometric", (16, 12), w, h, 2.0)
    conv, _ = C.convolve(white, grid, "interp", doublet, 2.0)
    ref = C.render(doublet, white, 48, 3, 2.0).image.astype(np.float64)
    axis = axis_irradiance(doublet, 531.0) / ideal_irradiance(doublet, pinhole_focal_mm(doublet, 2.0))
    centre = ref[h // 2 - 2:h // 2 + 2, w // 2 - 2:w // 2 + 2, 1].mean()
    assert centre == pytest.approx(axis, abs=2e-3)
    assert ref[h // 2 - 2:h // 2 + 2, :3, 1].mean() / centre == pytest.approx(0.986, abs=3e-3)
    assert ref[:3, :3, 1].mean() / centre == pytest.approx(0.978, abs=3e-3)
    ratio = conv / ref
    # inside the outermost nodes (the 16×12 grid's nodes are 10 px apart, the outer ones 5 px from the border)
    for region in (np.s_[h // 2 - 4:h // 2 + 4, w // 2 - 4:w // 2 + 4], np.s_[h // 2 - 4:h // 2 + 4, 6:10],
                   np.s_[6:10, 6:10], np.s_[6:10, w // 2 - 4:w // 2 + 4], np.s_[:, :]):
        assert ratio[region].mean() == pytest.approx(1.0, abs=3e-3)
    # beyond them interp holds the outermost chief-ray offsets (no distortion there): ~1-2 % too bright
    assert 1.0 < ratio[:2, :2].mean() < 1.03


def test_interp_agrees_with_the_converged_render(doublet, tmp_path):
    """Acceptance: geometric PSFs on a 32×24 grid, interp within 1 % relative RMSE of the direct render
    (reference noise removed), on the bundled photograph at 320×240 (the whole ±2° field); the paper's
    patch method is reported beside it, and the unblurred image is far off (the test can fail)."""
    from solas_mi.resources import resource_dir

    image = C.load_input(str(resource_dir("scenes") / "images" / "rocket.png"), sensor=(240, 320))
    res = C.crossval(doublet, image, tmp_path, spp=256, seeds=2,
                     cases=("interp:geometric:32x24", "patch:geometric:32x24"), log=lambda s: None)
    rows = {r.name: r for r in res.rows}
    noise = res.meta["reference_noise_rel"]
    assert 0 < noise < 0.015
    interp = rows["interp:geometric:32x24"].errors
    patch = rows["patch:geometric:32x24"].errors
    ideal = rows["ideal (no blur)"].errors
    assert interp.rel_rmse_denoised <= 0.01
    assert max(interp.annuli_denoised.values()) <= 0.01
    assert interp.rel_rmse_denoised < patch.rel_rmse_denoised < 0.03
    assert ideal.rel_rmse_denoised > 0.05
    assert interp.ssim > 0.999
    for name in ("table.md", "table.csv", "crossval.json", "reference.exr", "interp_geometric_32x24.exr",
                 "interp_geometric_32x24_error.exr", "interp_geometric_32x24_error.png"):
        assert (tmp_path / name).is_file(), name
    assert "interp:geometric:32x24" in (tmp_path / "table.md").read_text()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # nothing half-written
