"""Cross-validation of the PSF-grid convolution against the direct render (`solas_mi.validation.crossval`)."""

from strict_json import strict_loads

from solas_mi.validation.crossval import crossval
from solas_mi.validation.inputs import load_input


def test_interp_agrees_with_the_converged_render(doublet, tmp_path):
    """Acceptance: geometric PSFs on a 32×24 grid, interp within 1 % relative RMSE of the direct render
    (reference noise removed), on the bundled photograph at 320×240 (the whole ±2° field); the paper's
    patch method is reported beside it, and the unblurred image is far off (the test can fail)."""
    from solas_mi.resources import resource_dir

    image = load_input(str(resource_dir("scenes") / "images" / "rocket.png"), sensor=(240, 320))
    res = crossval(
        doublet,
        image,
        tmp_path,
        spp=256,
        seeds=2,
        cases=("interp:geometric:32x24", "patch:geometric:32x24"),
        log=lambda s: None,
    )
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
    for name in (
        "table.md",
        "table.csv",
        "crossval.json",
        "reference.exr",
        "interp_geometric_32x24.exr",
        "interp_geometric_32x24_error.exr",
        "interp_geometric_32x24_error.png",
    ):
        assert (tmp_path / name).is_file(), name
    assert "interp:geometric:32x24" in (tmp_path / "table.md").read_text()
    assert strict_loads((tmp_path / "crossval.json").read_text())["reference_noise_rel"] == noise
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # nothing half-written
