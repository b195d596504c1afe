"""`make demo`: the bundled doublet's paraxial table, its nine PSFs and 8×8 / 32×32 PSF grids; the
bundled photograph rendered through the doublet's glass and degraded by the PSF grids (patch 8×6,
patch 32×24, interp) with a comparison sheet; a slanted-edge target of known MTF measured by the
e-SFR; the street scene through the doublet, a sensor preset and the image processor, on a sheet beside
its depth and instance layers; a night street with headlights and a sun in the frame through a coated lens with
its ghosts (render, flare layer, developed frame); the street experiment. Each step is announced before it runs, with the
files it writes (`steps`)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from contextlib import redirect_stdout
from pathlib import Path

from . import jsonio
from .cli import main as solas_mi
from .imageio import atomic_path, read_image
from .outputs import safe_name
from .resources import resource_dir

DEMO_SPP = 192  # 64 per colour line: ≈ 2.5 % noise; measured ≈ 2 min on two idle cores, far longer on busy ones
# the camera step: the street scene framed along the street (the doublet's field is ±4 deg), small and
# few spp, through an automotive HDR sensor preset (its four readouts merged; its radiance read through the
# render's own f-number, auto-exposed) and the default processor
STREET_SET = ("width=480", "height=360", "fov=8", "target=0, 2, 140")
STREET_SPP = 32
STREET_SENSOR, STREET_EXPOSURE_MS = "imx490-hdr", "auto"
CAMERA_FILES = {
    "camera": "camera/street_render.exr|png (irradiance + every label's layers), "
    "camera/street_raw.exr|png (RAW, developed frame)",
    "camera sheet": "camera/camera_sheet.png",
}  # what `camera_frame` writes
FLARE_LENS, FLARE_SPP = "double-gauss-50mm", 16  # the flare step's lens (given the typical AR coating) and spp
PHOTO = "images/rocket.png"  # under the shipped scenes
GRIDS = ("8x8", "32x32")
CONVOLUTIONS = (("patch 8x6", "8x8", "patch"), ("patch 32x24", "32x32", "patch"), ("interp 32x32", "32x32", "interp"))


def cli(argv: list[str]) -> None:
    """Run one solas-mi command; stop the demo when it fails."""
    if solas_mi(argv) != 0:
        raise SystemExit(f"demo step failed: solas-mi {' '.join(argv)}")


def steps() -> list[tuple[str, dict[str, str], Callable[[Path], None]]]:
    """The demo's steps in order: what each does, what it writes (name → files under the results folder;
    `a.exr|png`: a.exr and a.png) and the function that does it."""
    return [
        ("the doublet's paraxial table", {"paraxial": "lens_info.txt, lens_info.json"}, lens_info),
        ("nine PSFs: fields 0, +2 and -2 deg at 486, 531 and 656 nm", {"psfs": "psf/psf_*deg_*nm.exr|png"}, psfs),
        (
            "PSF grids " + " and ".join(GRIDS) + " at 656, 531 and 486 nm, each with its PNG mosaic",
            {"grids": ", ".join(f"psf_grid_{g}.exr|png" for g in GRIDS)},
            grids,
        ),
        (
            f"the bundled photograph rendered through the doublet's glass at {DEMO_SPP} spp, one of the two long "
            "steps: its progress reports the time left at the rate it measures",
            {"direct render": "degraded/rocket_render.exr|png"},
            render,
        ),
        (
            "the photograph degraded by the PSF grids (" + ", ".join(c[0] for c in CONVOLUTIONS) + ") and a "
            "comparison sheet of the four",
            {
                "convolutions": ", ".join(f"degraded/rocket_{safe_name(c[0])}.exr|png" for c in CONVOLUTIONS),
                "comparison sheet": "degraded/comparison.png",
            },
            convolutions,
        ),
        (
            "a slanted-edge target of known MTF, measured by the e-SFR",
            {"slanted edge": "sfr/edge_5deg_sigma1px.png"},
            slanted_edge,
        ),
        (
            f"the street scene through the doublet ({STREET_SPP} spp) with its labels, the {STREET_SENSOR} sensor and "
            "the default image processor",
            CAMERA_FILES,
            camera_frame,
        ),
        (
            f"flare: a night street with a car's headlights and a view with the sun in the frame through the "
            f"{FLARE_LENS} (typical AR coating) with its ghosts and the iris's starburst ({FLARE_SPP} spp), the "
            "imx490-hdr sensor and the default image processor; a sheet per view of the render, its flare layer and "
            "the developed frame",
            {"flare": "flare/night_street_*, flare/sun_in_frame_* (render .exr|png, raw .exr|png, sheet .png)"},
            flare,
        ),
        (
            "the street experiment (the SOLAS paper's natural-scene SFR), the other long step: renders through an "
            "ideal camera and the lens focused at infinity and near, PSF grids and convolutions, each reported with "
            "its time as it ends",
            {"street experiment": "street/street.md (table), street/fig5_*.png (plots), street/*.exr|png"},
            street_experiment,
        ),
    ]


def run(out: Path) -> None:
    """Every step, each announced before it runs with what it writes, then where the results are."""
    out.mkdir(parents=True, exist_ok=True)
    every = steps()
    written: dict[str, str] = {}
    for k, (what, writes, step) in enumerate(every, start=1):
        print(
            f"\n== demo step {k} of {len(every)}: {what}\n   writes (in {out}): {'; '.join(writes.values())}",
            flush=True,
        )
        step(out)
        written.update(writes)
    print(jsonio.dumps({"results": str(out.resolve()), **written}, indent=2))


def lens_info(out: Path) -> None:
    for name, extra in (("lens_info.txt", []), ("lens_info.json", ["--json"])):
        with atomic_path(out / name) as tmp, open(tmp, "w") as f, redirect_stdout(f):
            cli(["lens", "info", "solas-doublet", *extra])
    print((out / "lens_info.txt").read_text())


def psfs(out: Path) -> None:
    for field in (0, 2, -2):
        for wl in (486, 531, 656):
            cli(
                [
                    "psf",
                    "solas-doublet",
                    "--field-deg",
                    f"0,{field}",
                    "--wavelengths-nm",
                    str(wl),
                    "--pitch-um",
                    "0.5",
                    "--size",
                    "160",
                    "--normalize",
                    "peak",
                    "-o",
                    str(out / "psf" / f"psf_{field:+d}deg_{wl}nm.exr"),
                ]
            )


def grids(out: Path) -> None:
    for grid in GRIDS:
        cli(
            [
                "psf-grid",
                "solas-doublet",
                "--grid",
                grid,
                "--wavelengths-nm",
                "656,531,486",
                "--pitch-um",
                "0.5",
                "--size",
                "160",
                "--mosaic",
                "-o",
                str(out / f"psf_grid_{grid}.exr"),
            ]
        )


def _photo() -> str:
    return str(resource_dir("scenes") / PHOTO)


def render(out: Path) -> None:
    cli(
        [
            "render-image",
            "solas-doublet",
            _photo(),
            "--response",
            "lines",
            "--spp",
            str(DEMO_SPP),
            "-o",
            str(out / "degraded" / "rocket_render.exr"),
        ]
    )


def convolutions(out: Path) -> None:
    """The photograph degraded by each PSF grid, and a comparison sheet of the direct render and the three."""
    from .validation.sheet import comparison_sheet

    d = out / "degraded"
    files = {"direct render": d / "rocket_render.exr"}
    for name, grid, method in CONVOLUTIONS:
        files[name] = d / f"rocket_{safe_name(name)}.exr"
        cli(
            [
                "degrade",
                _photo(),
                "--psf-grid",
                str(out / f"psf_grid_{grid}.exr"),
                "--method",
                method,
                "-o",
                str(files[name]),
            ]
        )
    comparison_sheet(
        {"input (ideal camera)": read_image(_photo()), **{k: read_image(v) for k, v in files.items()}},
        d / "comparison.png",
        f"SOLAS doublet: direct render (R/G/B = 656/531/486 nm, {DEMO_SPP} spp) and PSF-grid convolutions",
    )


def slanted_edge(out: Path) -> None:
    edge = out / "sfr" / "edge_5deg_sigma1px.png"
    cli(["sfr-target", "-o", str(edge), "--angle-deg", "5", "--sigma-px", "1", "--size", "128x128"])
    cli(["sfr", str(edge)])


def flare(out: Path) -> None:
    """The flare views (`validation.flare_views`) through the coated FLARE_LENS."""
    from .optics.lens import Lens
    from .optics.typical_ar import with_typical_ar
    from .validation.flare_views import flare_views

    flare_views(
        with_typical_ar(Lens.load(FLARE_LENS)), out / "flare", spp=FLARE_SPP, run=lambda *a: cli(list(map(str, a)))
    )


def street_experiment(out: Path) -> None:
    cli(["experiment", "street", "--lens", "solas-doublet", "-o", str(out / "street")])


def camera_frame(out: Path) -> dict:
    """The street scene through the doublet with its labels, then through a sensor preset and the
    default image processor (`solas-mi camera`), and a sheet of the frame beside its depth and instance
    layers."""
    from .imageio import read_exr
    from .render.labels import LABELS

    d = out / "camera"
    render, raw = d / "street_render.exr", d / "street_raw.exr"
    sets = [a for value in STREET_SET for a in ("--set", value)]
    cli(
        [
            "render",
            str(resource_dir("scenes") / "street" / "street.xml"),
            "--lens",
            "solas-doublet",
            *sets,
            "--spp",
            str(STREET_SPP),
            "--labels",
            ",".join(LABELS),
            "-o",
            str(render),
        ]
    )
    cli(
        [
            "camera",
            str(render),
            "--sensor-model",
            STREET_SENSOR,
            "--exposure-ms",
            STREET_EXPOSURE_MS,
            "--isp",
            "default",
            "-o",
            str(raw),
        ]
    )
    channels, meta = read_exr(render)
    camera_sheet(
        channels,
        meta["labels"],
        read_image(raw.with_suffix(".png"), linearize=False),
        d / "camera_sheet.png",
        f"street scene, solas-doublet ({STREET_SPP} spp) → {STREET_SENSOR} (exposure {STREET_EXPOSURE_MS}) "
        "→ default image processor; labels along each pixel's chief ray",
    )
    return CAMERA_FILES


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
    from .validation.flare_views import finish

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
    boxes = [
        axes[3].add_patch(Rectangle((x0 - 0.5, y0 - 0.5), x1 - x0, y1 - y0, fill=False, edgecolor="white"))
        for x0, y0, x1, y1 in (box["box"] for box in labels.get("boxes", {}).values())
    ]
    for name, box in labels.get("boxes", {}).items():
        axes[3].text(box["box"][0], box["box"][1], name, color="white", fontsize=6, va="bottom")
    axes[3].set_title(f"instances: {len(labels.get('instances', {}))} shapes, {len(boxes)} named (boxed)")
    finish(fig, axes, title, path, 100)
    return len(boxes)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="out", help="results folder")
    run(Path(ap.parse_args().out))


if __name__ == "__main__":
    main()
