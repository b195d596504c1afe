"""`make demo`: the bundled doublet's paraxial table, its nine PSFs and 8×8 / 32×32 PSF grids; the
bundled photograph rendered through the doublet's glass and degraded by the PSF grids (patch 8×6,
patch 32×24, interp) with a comparison sheet; a slanted-edge target of known MTF measured by the
e-SFR; the street scene through the doublet, a sensor preset and the image processor, on a sheet beside
its depth and instance layers."""
from __future__ import annotations

import argparse
from contextlib import redirect_stdout
from pathlib import Path

from . import jsonio
from .cli import main as solas_mi
from .imageio import atomic_path, read_image
from .resources import resource_dir

DEMO_SPP = 192  # 64 per colour line: ≈ 2.5 % noise, ≈ 2 min on two cores
# the camera step: the street scene framed along the street (the doublet's field is ±4 deg), small and
# few spp (≈ 30 s on two cores), through an automotive sensor preset (its radiance read through the
# render's own f-number, auto-exposed) and the default processor
STREET_SET = ("width=480", "height=360", "fov=8", "target=0, 2, 140")
STREET_SPP = 32
STREET_SENSOR, STREET_EXPOSURE_MS = "ar0132at", "auto"


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
    camera = camera_frame(out)
    cli(["experiment", "street", "--lens", "solas-doublet", "-o", str(out / "street")])
    print(jsonio.dumps({"results": str(out.resolve()), "paraxial": "lens_info.txt", "psfs": "psf/*.exr|png",
                      "grids": "psf_grid_8x8.exr|png, psf_grid_32x32.exr|png", **degraded,
                      "slanted edge": "sfr/edge_5deg_sigma1px.png",
                      **camera,
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


def camera_frame(out: Path) -> dict:
    """The street scene through the doublet with its labels, then through a sensor preset and the
    default image processor (`solas-mi camera`), and a sheet of the frame beside its depth and instance
    layers."""
    from .imageio import read_exr

    d = out / "camera"
    render, raw = d / "street_render.exr", d / "street_raw.exr"
    sets = [a for value in STREET_SET for a in ("--set", value)]
    cli(["render", str(resource_dir("scenes") / "street" / "street.xml"), "--lens", "solas-doublet", *sets,
         "--spp", str(STREET_SPP), "--labels", "depth,normal,instance", "-o", str(render)])
    cli(["camera", str(render), "--sensor-model", STREET_SENSOR, "--exposure-ms", STREET_EXPOSURE_MS,
         "--isp", "default", "-o", str(raw)])
    channels, meta = read_exr(render)
    exposure = read_exr(raw)[1]["exposure_ms"]
    camera_sheet(channels, meta["labels"], read_image(raw.with_suffix(".png"), linearize=False), d / "camera_sheet.png",
                 f"street scene, solas-doublet ({STREET_SPP} spp) → {STREET_SENSOR} ({exposure:.3g} ms, "
                 f"{STREET_EXPOSURE_MS}) → default image processor; labels along each pixel's chief ray")
    return {"camera": "camera/street_render.exr|png (irradiance + depth, normal, instance layers), "
                      "camera/street_raw.exr|png (RAW, developed frame)",
            "camera sheet": "camera/camera_sheet.png"}


def camera_sheet(channels: dict, labels: dict, frame, path: Path, title: str) -> int:
    """One row: the lens's irradiance image, the developed frame, the depth layer (colour-mapped, its
    range on the colour bar) and the instance layer (a colour per id, the scene's named shapes boxed: the
    street names its cars, pedestrians, poles, signs and posts); the number of boxes drawn."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.patches import Rectangle

    from .imageio import srgb_encode

    valid = channels["labels.valid"] > 0
    depth = np.where(valid, channels["depth.Z"], np.nan)
    ids = np.unique(channels["instance.id"], return_inverse=True)[1].reshape(valid.shape)
    linear = np.stack([channels[c] for c in "RGB"], axis=-1)
    fig, axes = plt.subplots(1, 4, figsize=(18, 4.4))
    axes[0].imshow(np.clip(srgb_encode(np.clip(linear / linear.max(), 0.0, None)), 0.0, 1.0))
    axes[0].set_title("through the lens (irradiance, scaled)")
    axes[1].imshow(frame)
    axes[1].set_title("sensor + image processor (8-bit sRGB)")
    shown = axes[2].imshow(depth, cmap="viridis")
    fig.colorbar(shown, ax=axes[2], fraction=0.04, label="range (m)")
    axes[2].set_title(f"depth: {np.nanmin(depth):.1f} to {np.nanmax(depth):.1f} m")
    axes[3].imshow(np.ma.masked_where(~valid, ids % 20), cmap="tab20", vmin=0, vmax=19, interpolation="nearest")
    boxes = [axes[3].add_patch(Rectangle((x0 - 0.5, y0 - 0.5), x1 - x0, y1 - y0, fill=False, edgecolor="white"))
             for x0, y0, x1, y1 in (box["box"] for box in labels.get("boxes", {}).values())]
    for name, box in labels.get("boxes", {}).items():
        axes[3].text(box["box"][0], box["box"][1], name, color="white", fontsize=6, va="bottom")
    axes[3].set_title(f"instances: {len(labels.get('instances', {}))} shapes, {len(boxes)} named (boxed)")
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
    return len(boxes)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="out", help="results folder")
    run(Path(ap.parse_args().out))


if __name__ == "__main__":
    main()
