"""Cross-validation for the fisheye: an equidistant environment image rendered directly through the
lens geometry against its ideal sensor image degraded by the lens's own sensor-space PSF grid."""

import numpy as np
import pytest
from strict_json import strict_loads

from solas_mi import Lens, SolasError
from solas_mi.validation.fisheye import compare_fisheye

STEP_DEG, FOV_DEG = 0.5, 95.75  # 383 texels span ±95.75°, texel 191 on the axis


def environment() -> np.ndarray:
    n = int(round(2 * FOV_DEG / STEP_DEG))
    yy, xx = np.indices((n, n))
    fx, fy = (xx - n // 2) * STEP_DEG, (n // 2 - yy) * STEP_DEG
    return (0.6 + 0.4 * np.cos(2 * np.pi * fx / 30) * np.cos(2 * np.pi * fy / 30)).astype(np.float32)


def test_render_and_sensor_grid_convolution_agree():
    """A smooth object (30° period: 4 to 10 pixels) over a 64×64 sensor of 0.3 mm pixels, to 90° in
    the corners' direction. Measured: RMS difference 1.5 % of the mean with 0.7 % render noise (256 spp,
    two seeds), so about 1.3 % is the engines' own difference; the means agree to 0.3 % (radiometry:
    irradiance falls to 47 % at 90°). In focus the lens blur is far below these pixels: the unblurred
    ideal sensor image is 1.7 % from the render, and what is left is the pixel model (the render
    averages each pixel's area, the ideal image takes one point per pixel)."""
    r = compare_fisheye(Lens.load("nikkor-fisheye"), environment(), FOV_DEG, 64, 300.0, (5, 5), 256)
    assert r.rms_noise < 0.015
    assert r.rms_error < 0.025
    assert abs(r.convolved.mean() / r.direct.mean() - 1.0) < 0.01
    # the test can tell: the pattern's own contrast is many times the difference
    assert r.direct.std() / r.direct.mean() > 5 * r.rms_error


def test_defocused_fisheye_blur_is_the_psf_grid_blur():
    """The film 3 mm behind the image plane in both engines: the blur (a 1.2 mm disc on the axis,
    radially squeezed toward 90°) spans 4 pixels, so the PSFs must carry it. Measured: convolution
    1.5 % from the render (1.3 % without the render's noise), the unblurred ideal image 3.5 %; per
    annulus 1.2 / 1.3 / 1.7 % against 4.0 / 3.6 / 3.3 %. PSFs that missed the blur, or a render that
    kept the file's image plane, come out near the ideal image's figure."""
    from solas_mi.validation.fisheye import defocused

    r = compare_fisheye(defocused(Lens.load("nikkor-fisheye"), 3.0), environment(), FOV_DEG, 64, 300.0, (5, 5), 256)
    ideal = np.sqrt(np.mean((r.ideal - r.direct) ** 2)) / r.direct.mean()
    denoised = np.sqrt(max(r.rms_error**2 - r.rms_noise**2, 0.0))
    assert ideal > 0.03  # the blur is there to be seen
    assert r.rms_error < 0.022 and denoised < 0.5 * ideal
    for a in r.annuli():
        assert a["rms_error"] < 0.6 * a["rms_ideal"], a


def test_needs_a_lens_of_polar_fields(doublet):
    with pytest.raises(SolasError, match="polar fields"):
        compare_fisheye(doublet, np.ones((8, 8), np.float32), 2.0, 8, 5.0, (3, 3), 1)


def test_crossval_command_on_the_fisheye(tmp_path, capsys):
    """`solas-mi crossval` of a lens of polar fields takes an equidistant environment and writes the
    comparison: images, error map, table and JSON whose figures agree with the images it wrote."""
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr, write_exr

    write_exr(tmp_path / "env.exr", {"Y": environment()})
    out = tmp_path / "cv"
    assert (
        main(
            [
                "crossval",
                "nikkor-fisheye",
                str(tmp_path / "env.exr"),
                "-o",
                str(out),
                "--fov-deg",
                str(FOV_DEG),
                "--size",
                "24",
                "--spp",
                "32",
                "--grid",
                "3x3",
                "--defocus-mm",
                "2",
            ]
        )
        == 0
    )
    meta = strict_loads((out / "crossval.json").read_text())
    direct, convolved = (read_exr(out / f"{name}.exr")[0]["Y"].astype(np.float64) for name in ("direct", "convolved"))
    rms = np.sqrt(np.mean((convolved - direct) ** 2)) / direct.mean()
    assert abs(rms / meta["rms_error"] - 1.0) < 1e-3
    assert meta["sensor_px"] == 24 and meta["grid"] == [3, 3] and meta["fov_deg"] == FOV_DEG
    assert meta["defocus_mm"] == 2.0 and meta["lens_hash"] != Lens.load("nikkor-fisheye").hash
    assert [a["annulus"] for a in meta["annuli"]] == ["centre", "middle", "edge"]
    # at 32 spp the render's noise dominates; what is left besides it is within the 64 px test's budget
    assert meta["rms_error_denoised"] < 0.035 and abs(meta["mean_ratio"] - 1.0) < 0.02
    assert (out / "error.png").stat().st_size > 0 and "| whole image |" in (out / "table.md").read_text()
    assert "Fisheye cross-validation of nikkor-fisheye" in capsys.readouterr().out


@pytest.mark.parametrize(
    "lens, extra, message",
    [
        ("nikkor-fisheye", ["--cases", "interp:geometric:4x3"], "--cases: not for a lens of polar fields"),
        ("nikkor-fisheye", ["--fov-deg", "180"], "--fov-deg 180 must lie in"),
        ("nikkor-fisheye", ["--defocus-mm", "-60"], "defocus -60 mm must be finite and leave the image plane"),
        ("solas-doublet", ["--size", "32"], "--size: only for a lens of polar fields"),
    ],
)
def test_crossval_options_that_do_not_fit_the_lens(tmp_path, capsys, lens, extra, message):
    from solas_mi.cli import main
    from solas_mi.imageio import write_exr

    write_exr(tmp_path / "env.exr", {"Y": np.ones((16, 16), np.float32)})
    assert main(["crossval", lens, str(tmp_path / "env.exr"), "-o", str(tmp_path / "cv")] + extra) != 0
    assert message in capsys.readouterr().err
    assert not (tmp_path / "cv").exists()
