"""Flare in the frame, as a user meets it (`make demo`, the docs' flare page): a night street with a car's two
headlights and a day view with the sun in the frame, each rendered through a coated lens with its ghosts (`render
--lens --ghosts`: the flare label beside the image), then through a sensor preset and the image processor (`camera`),
on one sheet per view: the render, its flare layer and the developed frame (`flare_sheet`).

The scenes (`view_xml`) are small and our own: a perspective camera 1.2 m above a grey road plane, a uniform sky
(night: `NIGHT_SKY`; day: `DAY_SKY`), and the sources: two headlights (discs of 0.1 m, 1.5 m apart, 20 m
ahead, `flare_routes.HEADLIGHT_RADIANCE`) or the sun (a far sphere of 0.27 deg, `flare_routes.SUN_RADIANCE`, up
and to the right), in linear units of the scene (an HDR frame: the sources far above the sky, as they are).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .flare_routes import headlights, scene_head, sun_sphere

NIGHT_SKY, DAY_SKY = 0.02, 1.0  # the sky's radiance at night and by day
SUN_DEG = (6.0, 4.0)  # the sun's direction (deg right, up)
VIEWS = {"night street": "headlights", "sun in frame": "sun"}  # view: its sources
SENSOR, EXPOSURE_MS = "imx490-hdr", "auto"


def view_xml(sources: str, half_fov_deg: float, size: tuple[int, int]) -> str:
    """The scene of `sources` ("headlights": night, "sun": day) for a perspective camera of `half_fov_deg` across
    a `size` (width, height) film."""
    if sources == "headlights":
        sky, lights = NIGHT_SKY, headlights(-0.5)
    else:
        far = 1e3  # inside the perspective camera's far clip (1e4 by default)
        tx, ty = (math.tan(math.radians(v)) for v in SUN_DEG)
        radius = far * math.hypot(1.0, tx, ty) * math.radians(0.27)
        sky, lights = DAY_SKY, sun_sphere((-tx * far, ty * far, far), radius)
    return f"""{scene_head(half_fov_deg, size, 3)}
    <shape type="rectangle">
        <transform name="to_world"><scale x="40" y="200"/><rotate x="1" angle="-90"/><translate y="-1.2" z="150"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.15"/></bsdf>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="{sky}"/></emitter>{lights}
</scene>"""


def flare_views(lens, folder, run, size=(320, 240), spp=16, half_fov_deg=15.0) -> dict[str, dict]:
    """Each of `VIEWS` through `lens` (a Lens, written to `folder` as a lens file) with its ghosts, developed by
    `SENSOR` and the default image processor, and its sheet (`flare_sheet`); per view its files. `run(*args)` runs one
    solas-mi command (`solas_mi.cli.main` of its arguments as strings)."""
    from ..render.scene import lens_file

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lens_path = lens_file(lens, folder)
    written = {}
    for view, sources in VIEWS.items():
        stem = folder / view.replace(" ", "_")
        xml = stem.with_suffix(".xml")
        xml.write_text(view_xml(sources, half_fov_deg, size))
        render, raw = Path(f"{stem}_render.exr"), Path(f"{stem}_raw.exr")
        run("render", xml, "--lens", lens_path, "--ghosts", "--spp", spp, "-o", render)
        run("camera", render, "--sensor-model", SENSOR, "--exposure-ms", EXPOSURE_MS, "--isp", "default", "-o", raw)
        sheet = Path(f"{stem}_sheet.png")
        flare_sheet(render, raw.with_suffix(".png"), sheet, f"{view}: {lens.name}, {spp} spp, {SENSOR}")
        written[view] = {"render": str(render), "developed": str(raw.with_suffix(".png")), "sheet": str(sheet)}
    return written


def flare_sheet(render, developed, path, title: str) -> None:
    """One row: the render through the lens (irradiance, log scale), its flare layer (`flare.irradiance`, log scale,
    its hit mask `flare.ratio` > 1e-3 outlined) and the developed frame."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..imageio import read_exr, read_image
    from .flare_routes import HIT_RATIO

    channels, _ = read_exr(render)
    image = np.mean([channels[c] for c in "RGB"], axis=0)
    flare, ratio = channels["flare.irradiance"], channels["flare.ratio"]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    floor = max(float(image[image > 0].min()) if (image > 0).any() else 1e-6, 1e-6)
    shown = axes[0].imshow(np.log10(np.maximum(image, floor)), cmap="magma")
    fig.colorbar(shown, ax=axes[0], fraction=0.04, label="log10 irradiance")
    axes[0].set_title("through the lens, ghosts and starburst (log)")
    lit = flare[flare > 0]
    low = float(np.quantile(lit, 0.01)) if len(lit) else 1e-9
    shown = axes[1].imshow(np.log10(np.maximum(flare, low)), cmap="viridis")
    axes[1].contour(ratio > HIT_RATIO, levels=[0.5], colors="white", linewidths=0.6)
    fig.colorbar(shown, ax=axes[1], fraction=0.04, label="log10 flare.irradiance")
    axes[1].set_title(f"flare layer; white: flare.ratio > {HIT_RATIO:g} ({100 * (ratio > HIT_RATIO).mean():.0f} %)")
    axes[2].imshow(read_image(developed, linearize=False))
    axes[2].set_title("sensor + image processor (8-bit sRGB)")
    finish(fig, axes, title, path, 70)


def ghost_figure(lens, field_deg: tuple[float, float], path, size_mm: float = 24.0, pixels: int = 480) -> None:
    """The lens's ghosts of a far point source at `field_deg` (the ghost grid's, `psf.ghost_grid`, at its reference
    wavelength): on the image plane (log10 of each pixel's fraction of the direct image's light, `size_mm` square
    about the axis) beside the energies of the twelve strongest."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..psf import ghost_grid

    polar = math.degrees(lens.field_type.polar(field_deg)[0])
    wavelength = float(lens.primary_wavelength)
    grid = ghost_grid(lens, radii=3, field_deg=polar, wavelengths_nm=[wavelength])
    ghosts = grid.at(field_deg)
    pitch_um = size_mm * 1e3 / pixels
    image = ghosts.image(pitch_um, pixels, centre_mm=(0.0, 0.0))[0]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    half = size_mm / 2
    floor = max(float(image[image > 0].min()) if (image > 0).any() else 1e-12, 1e-12)
    shown = axes[0].imshow(np.log10(np.maximum(image, floor)), cmap="magma", extent=(-half, half, -half, half))
    axes[0].plot(*ghosts.direct_mm[0], "c+", markersize=12)
    fig.colorbar(shown, ax=axes[0], fraction=0.04, label="log10 fraction of the direct image per pixel")
    axes[0].set_xlabel("x (mm)")
    axes[0].set_ylabel("y (mm)")
    axes[0].set_title(f"every ghost on the image plane (+: the direct image), {pitch_um:.0f} µm pixels")
    order = np.argsort(-ghosts.energy[0])[:12]
    axes[1].barh([f"{grid.paths[k][0]},{grid.paths[k][1]}" for k in order][::-1], ghosts.energy[0, order][::-1])
    axes[1].set_xscale("log")
    axes[1].set_xlabel("energy (fraction of the direct image)")
    axes[1].set_title(f"the 12 strongest of {len(grid.paths)} (surfaces j, i: reflected at j, then i)")
    title = (f"{lens.name}: ghosts of a far point at field ({field_deg[0]:g}, {field_deg[1]:g}) deg, {wavelength:g} "
             f"nm; all: {ghosts.energy[0].sum():.2e}")  # fmt: skip
    finish(fig, [], title, path, 90)


def sun_through(renders: dict, path, title: str) -> None:
    """One row: each render (name → `render --ghosts` EXR) of the sun in the frame, log10 irradiance from its 1st to
    its 99.5th percentile."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..imageio import read_exr

    fig, axes = plt.subplots(1, len(renders), figsize=(5.2 * len(renders), 4.2))
    for ax, (name, exr) in zip(np.atleast_1d(axes), renders.items()):
        channels, _ = read_exr(exr)
        image = np.mean([channels[c] for c in "RGB"], axis=0)
        lit = np.log10(image[image > 0]) if (image > 0).any() else np.zeros(1)
        low, high = np.quantile(lit, [0.01, 0.995])  # the sun's few pixels above the range: the ghosts in it
        ax.imshow(np.log10(np.maximum(image, 10.0**low)), cmap="magma", vmin=low, vmax=high)
        ax.set_title(name)
    finish(fig, axes, title, path, 90)


def finish(fig, axes, title: str, path, dpi: int) -> None:
    """A sheet's last steps: its axes without ticks, its title, laid out and written to `path` (PNG, whole or not at
    all), the figure closed."""
    import matplotlib.pyplot as plt

    from ..imageio import atomic_path

    for ax in np.atleast_1d(axes):
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    plt.close(fig)
