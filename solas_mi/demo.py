"""`make demo`: the bundled doublet's paraxial table, its nine PSFs and 8×8 / 32×32 PSF grids; the
bundled photograph rendered through the doublet's glass and degraded by the PSF grids (patch 8×6,
patch 32×24, interp) with a comparison sheet; a slanted-edge target of known MTF measured by the
e-SFR."""
from __future__ import annotations

import argparse
import json
from contextlib import redirect_stdout
from pathlib import Path

from .cli import main as solas_mi
from .imageio import atomic_path, read_image
from .resources import resource_dir

DEMO_SPP = 192  # 64 per colour line: ≈ 2.5 % noise, ≈ 2 min on two cores


def cli(argv: list[str]) -> None:
    """Run one solas-mi command; stop the demo when it fails."""
    if solas_mi(argv) != 0:
        raise SystemExit(f"demo step failed: solas-mi {' '.join(argv)}")


def run(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for name, extra in (("lens_info.txt", []), ("lens_info.json", ["--json"])):
        with atomic_path(out / name) as tmp, open(tmp, "w") as f, redirect_stdout(f):
            cli(["lens", "info", "solas-doublet", *extra])
    print((out / "lens_info.txt").read_text())
    psfs = out / "psf"
    for field in (0, 2, -2):
        for wl in (486, 531, 656):
            cli(["psf", "solas-doublet", "--field-deg", f"0,{field}", "--wavelengths-nm", str(wl), "--pitch-um", "0.5",
                 "--size", "160", "--normalize", "peak", "-o", str(psfs / f"psf_{field:+d}deg_{wl}nm.exr")])
    for grid in ("8x8", "32x32"):
        cli(["psf-grid", "solas-doublet", "--grid", grid, "--wavelengths-nm", "656,531,486", "--pitch-um", "0.5",
             "--size", "160", "--png", "-o", str(out / f"psf_grid_{grid}.exr")])
    degraded = degrade(out)
    edge = out / "sfr" / "edge_5deg_sigma1px.png"
    cli(["sfr-target", "-o", str(edge), "--angle-deg", "5", "--sigma-px", "1", "--size", "128x128"])
    cli(["sfr", str(edge)])
    cli(["experiment", "street", "--lens", "solas-doublet", "-o", str(out / "street")])
    print(json.dumps({"results": str(out.resolve()), "paraxial": "lens_info.txt", "psfs": "psf/*.exr|png",
                      "grids": "psf_grid_8x8.exr|png, psf_grid_32x32.exr|png", **degraded,
                      "slanted edge": "sfr/edge_5deg_sigma1px.png",
                      "street experiment": "street/street.md (table), street/fig5_render_infinity.png (plot)"},
                     indent=2))


def degrade(out: Path) -> dict:
    """The bundled photograph through the doublet: direct render and the three convolutions, and a
    comparison sheet of the four."""
    from .validation.sheet import comparison_sheet

    photo = str(resource_dir("scenes") / "images" / "rocket.png")
    d = out / "degraded"
    files = {
        "direct render": d / "rocket_render.exr",
        "patch 8x6": d / "rocket_patch_8x6.exr",
        "patch 32x24": d / "rocket_patch_32x24.exr",
        "interp 32x32": d / "rocket_interp.exr",
    }
    cli(["render-image", "solas-doublet", photo, "--response", "lines", "--spp", str(DEMO_SPP),
         "-o", str(files["direct render"])])
    for name, grid, method in (("patch 8x6", "8x8", "patch"), ("patch 32x24", "32x32", "patch"),
                               ("interp 32x32", "32x32", "interp")):
        cli(["degrade", photo, "--psf-grid", str(out / f"psf_grid_{grid}.exr"), "--method", method,
             "-o", str(files[name])])
    sheet = d / "comparison.png"
    comparison_sheet({"input (ideal camera)": read_image(photo), **{k: read_image(v) for k, v in files.items()}},
                     sheet, "SOLAS doublet: direct render (R/G/B = 656/531/486 nm, %d spp) and PSF-grid convolutions"
                     % DEMO_SPP)
    return {"direct render": "degraded/rocket_render.exr|png", "convolutions": "degraded/rocket_{patch_8x6,"
            "patch_32x24,interp}.exr|png", "comparison sheet": "degraded/comparison.png"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="out", help="results folder")
    run(Path(ap.parse_args().out))


if __name__ == "__main__":
    main()
