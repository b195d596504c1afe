"""Flare two ways: a frame rendered with a pinhole camera and degraded with the lens's ghosts (`degrade --ghosts`)
against the lens camera's render of the same scene with its ghosts (`render SCENE --lens LENS --ghosts`).

The scene (`scene_xml`): a perspective camera of half field of view `half_fov_deg` across its width, a sun (a far
sphere of `SUN_RADIUS_DEG`) up and to the side, two headlights (discs of 0.1 m, 1.5 m apart, 20 m ahead and 1 m
below the axis) and, for the flare label, a dim uniform sky. Both routes run their commands as a user would, in
this process (the caller's `run`: `cli.main`, which this stage does not import): the pinhole frame (`render SCENE`, HDR), the lens's PSF grid over that frame's field
(`psf-grid LENS --field-range-deg`) and `degrade FRAME --ghosts` (threshold `DEFAULT_THRESHOLD`); and `render SCENE
--lens LENS --ghosts --response mono:531`, both renders in Mitsuba's mono variant (both routes at the grid's one
wavelength, `WAVELENGTH_NM`, so that they weigh the coatings alike; `--response mono:531` in a spectral variant writes
an RGB film whose R and B are negative, a fifth of the light in G). The degraded frame's pixels are the grid's camera's (`convolution.kernels.grid_camera`: its pinhole focal length and
the frame's field of view, `degrade --fov-deg`), and the lens camera's film takes their pitch (`render --lens --pitch-um`): the same
image points, distortion and all.

What is compared:
- each of the `PATHS` ghosts that put the most light in the degraded frame, alone in both routes (the ghost grid
  of one path in `convolution.ghosts.frame_ghosts`; the lens camera's `ghosts` "j,i"), of the sun alone and of the
  headlights alone without sky (the sky's own ghosts would veil every path; each source group apart, as the
  routes weigh sources at different fields differently: the render's direct light carries the lens's relative
  illumination, the degraded frame's does not): its centroid (px) and its light over the direct light of the
  sources (the degraded frame's: the sources' pinhole light; the render's: its direct image light-traced,
  `render.ghost_light.direct_light`: a render of a sun under a pixel at the frame's spp is no such reference, its
  seeds spread by tens of per cent, and every ghost over it reads off together);
- the flare label's hit mask, `flare.ratio` > `HIT_RATIO`, of the whole scene, sky included: its IoU between the routes, and
  the flare light (`flare.irradiance`) in the frame.
Lengths in mm, angles in degrees, pixels of the frame.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

WAVELENGTH_NM = 531.0  # both routes' one wavelength: the grid's (serving every channel) and the lens camera's response
VARIANT = "llvm_ad_mono"  # both renders' Mitsuba variant: one channel, the lens camera's response mono at WAVELENGTH_NM
PATHS = 5  # the ghosts compared one by one: the strongest in the degraded frame
HIT_RATIO = 1e-3  # the flare label's hit mask: flare.ratio above this
SUN_RADIUS_DEG = 0.27
SUN_FIELD = (0.45, 0.3)  # the sun's direction: these fractions of the half field of view across x and y
FAR_M = 1e3  # the sun's distance: inside the perspective camera's far clip (1e4 by default)
SUN_RADIANCE = 2e4
HEADLIGHT_RADIANCE = 2e3
SKY_RADIANCE = 0.05
PINHOLE_SPP = 256  # the pinhole frame's: a sun of a tenth of a pixel needs hundreds of samples to hold its light
GRID_MARGIN = 1.25  # the PSF grid's field range over the frame's (at most the lens's field): its nodes cover the frame
MAX_HALF_FOV_DEG = 60.0  # a perspective camera's half field of view: far from its tan θ pole


@dataclass
class RouteComparison:
    """One lens's two routes (module docstring)."""

    lens: str
    half_fov_deg: float
    paths: list = field(default_factory=list)  # per ghost: path, centroids (px) and light fractions of both routes
    iou: float = math.nan  # the hit masks' intersection over union
    hit_pixels: tuple = (0, 0)  # the hit masks' pixels: degraded, rendered
    flare_light: tuple = (0.0, 0.0)  # Σ flare.irradiance: degraded, rendered
    seconds: dict = field(default_factory=dict)

    def worst(self) -> tuple[float, float]:
        """The largest centroid distance (px) and relative light difference over the compared ghosts."""
        if not self.paths:
            return math.nan, math.nan
        return (max(p["centroid_px"] for p in self.paths), max(abs(p["light_ratio"] - 1.0) for p in self.paths))


def scene_xml(half_fov_deg: float, size: tuple[int, int], parts=("sun", "headlights", "sky")) -> str:
    """The test scene (module docstring) of `parts` ("sun", "headlights", "sky") for a perspective camera of
    `half_fov_deg` across a `size` (width, height) film."""
    width, height = size
    half_y = math.degrees(math.atan(math.tan(math.radians(half_fov_deg)) * height / width))
    tx, ty = math.tan(math.radians(SUN_FIELD[0] * half_fov_deg)), math.tan(math.radians(SUN_FIELD[1] * half_y))
    sun = np.array([tx, ty, 1.0]) * FAR_M
    radius = FAR_M * math.hypot(1.0, tx, ty) * math.radians(SUN_RADIUS_DEG)
    shapes = {
        "sun": sun_sphere(sun, radius),
        "headlights": headlights(-1),
        "sky": f'\n    <emitter type="constant"><rgb name="radiance" value="{SKY_RADIANCE}"/></emitter>',
    }
    return scene_head(half_fov_deg, size, 2) + "".join(shapes[p] for p in parts) + "\n</scene>"


def sun_sphere(centre, radius: float) -> str:
    """The sun, a sphere emitting `SUN_RADIANCE` at `centre` (x, y, z) of `radius`, as scene XML."""
    return f"""
    <shape type="sphere">
        <point name="center" x="{centre[0]}" y="{centre[1]}" z="{centre[2]}"/>
        <float name="radius" value="{radius}"/>
        <emitter type="area"><rgb name="radiance" value="{SUN_RADIANCE}"/></emitter>
    </shape>"""


def headlights(height_m: float) -> str:
    """Two headlights (discs of 0.1 emitting `HEADLIGHT_RADIANCE`, 1.5 apart) 20 ahead at `height_m`, as scene XML."""
    return "".join(
        f"""
    <shape type="disk">
        <transform name="to_world"><scale value="0.1"/><rotate x="1" angle="180"/><translate x="{x}" y="{height_m:g}" z="20"/></transform>
        <emitter type="area"><rgb name="radiance" value="{HEADLIGHT_RADIANCE}"/></emitter>
    </shape>"""
        for x in (-0.75, 0.75)
    )


def scene_head(half_fov_deg: float, size: tuple[int, int], max_depth: int) -> str:
    """A scene file's opening: a path integrator of `max_depth` and a perspective camera at the origin looking along
    +z (+y up), of `half_fov_deg` across a `size` (width, height) HDR film."""
    width, height = size
    return f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="{2 * half_fov_deg}"/>
        <string name="fov_axis" value="x"/>
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/>
            <rfilter type="box"/></film>
    </sensor>"""


def half_fov(lens) -> float:
    """The perspective camera's half field of view for `lens`: 0.8 of its field, at most `MAX_HALF_FOV_DEG`."""
    return min(0.8 * float(lens.field_deg), MAX_HALF_FOV_DEG)


def mean_image(path) -> tuple[np.ndarray, dict, dict]:
    """An EXR's image (the mean of its colour channels), its layers and its metadata."""
    from ..imageio import read_exr

    channels, meta = read_exr(path)
    colours = [name for name in channels if "." not in name]
    return np.mean([channels[c].astype(np.float64) for c in colours], axis=0), channels, meta


def centroid(image: np.ndarray) -> np.ndarray:
    """The light's centroid (column, row), pixel centres at integers + 0.5."""
    rows, cols = np.indices(image.shape)
    return np.array([(cols * image).sum(), (rows * image).sum()]) / image.sum() + 0.5


SCENES = {"sky": ("sun", "headlights", "sky"), "sun": ("sun",), "headlights": ("headlights",)}  # scene: its parts


def compare(lens, folder, run, size=(160, 120), spp=64, path_spp=256, paths=PATHS, grid=5) -> RouteComparison:
    """Both routes of `lens` (a Lens; written to `folder` as a lens file) over a `size` frame (module docstring);
    `run(*args)` runs one solas-mi command (`solas_mi.cli.main` of its arguments as strings, failing unless it exits 0)."""
    from ..render.scene import lens_file

    folder = Path(folder)
    lens_path = lens_file(lens, folder)
    hx = half_fov(lens)
    out = RouteComparison(lens.name, hx)
    hy = math.degrees(math.atan(math.tan(math.radians(hx)) * size[1] / size[0]))
    start = time.perf_counter()
    reach = [min(GRID_MARGIN * h, float(lens.field_deg)) for h in (hx, hy)]
    run("psf-grid", lens_path, "--grid", f"{grid}x{grid}", "--wavelengths-nm", WAVELENGTH_NM, "--field-range-deg",
        f"{reach[0]},{reach[1]}", "--psf-method", "geometric", "--rays", 64, "--size", 32, "-o", folder / "grid.exr")  # fmt: skip
    out.seconds["psf_grid"] = time.perf_counter() - start
    pitch_um = frame_pitch_um(folder / "grid.exr", size, hx)
    for name, parts in SCENES.items():
        xml = folder / f"{name}.xml"
        xml.write_text(scene_xml(hx, size, parts))
        start = time.perf_counter()
        run("render", xml, "--variant", VARIANT, "--spp", PINHOLE_SPP, "-o", folder / f"{name}_pinhole.exr")
        run("degrade", folder / f"{name}_pinhole.exr", "--psf-grid", folder / "grid.exr", "--ghosts", "--fov-deg", hx,
            "-o", folder / f"{name}_degraded.exr")  # fmt: skip
        out.seconds[f"degraded {name}"] = time.perf_counter() - start
        start = time.perf_counter()
        run("render", xml, "--variant", VARIANT, "--lens", lens_path, "--ghosts", "--response",
            f"mono:{WAVELENGTH_NM}", "--spp", spp, "--pitch-um", pitch_um, "-o", folder / f"{name}_rendered.exr")  # fmt: skip
        out.seconds[f"rendered {name}"] = time.perf_counter() - start
        start = time.perf_counter()
        if name == "sky":
            hits(out, folder / "sky_degraded.labels.exr", folder / "sky_rendered.exr")
        else:
            out.paths += [{"sources": name, **row} for row in ghost_paths(lens, folder, name, paths, path_spp)]
        out.seconds[f"ghosts one by one {name}"] = time.perf_counter() - start
    return out


def frame_pitch_um(grid_path, size: tuple[int, int], half_fov_deg: float) -> float:
    """The degraded frame's pixel pitch (µm) on the lens's image plane (`convolution.kernels.grid_camera` of the frame
    of `half_fov_deg` across its width): the lens camera's film takes it, so that both routes' pixels are the same
    image points."""
    from ..convolution.kernels import grid_camera
    from ..optics.frame import parse_frame
    from ..psf.grid_file import PSFGrid

    frame = parse_frame(half_fov_deg, "x", None, None)
    return float(grid_camera(PSFGrid.read(str(grid_path)), size[0], size[1], frame).pitch_um)


def hits(out: RouteComparison, degraded_labels, rendered) -> None:
    """The flare labels' hit masks' IoU, pixels and the flare light of both routes, into `out`."""
    from ..imageio import read_exr

    labels, _ = read_exr(degraded_labels)
    _, layers, _ = mean_image(rendered)
    masks = [labels["flare.ratio"] > HIT_RATIO, layers["flare.ratio"] > HIT_RATIO]
    union = (masks[0] | masks[1]).sum()
    out.iou = float((masks[0] & masks[1]).sum() / union) if union else math.nan
    out.hit_pixels = (int(masks[0].sum()), int(masks[1].sum()))
    out.flare_light = (float(labels["flare.irradiance"].sum()), float(layers["flare.irradiance"].sum()))


def traced_direct(xml, lens) -> float:
    """The light of the lens camera's direct image of scene `xml`'s sources, light-traced (module docstring)."""
    from ..render.ghost_light import direct_light
    from ..render.user_scene import load

    scene = load(xml, VARIANT, lens, response=f"mono:{WAVELENGTH_NM}")
    return float(direct_light(scene, scene.sensors()[0]).mean(axis=-1).sum())


def ghost_paths(lens, folder: Path, name: str, count: int, spp: int) -> list[dict]:
    """The `count` ghosts that put the most light in scene `name`'s degraded frame, each alone in both routes."""
    from ..convolution.ghosts import FrameGhosts, frame_ghosts
    from ..convolution.spec import DegradeSpec
    from ..errors import SolasError
    from ..imageio import read_image
    from ..optics.frame import parse_frame
    from ..psf.grid_file import PSFGrid
    from ..render.stock import render_scene
    from ..render.user_scene import load

    pinhole = folder / f"{name}_pinhole.exr"
    grid = PSFGrid.read(str(folder / "grid.exr"))
    spec = DegradeSpec(ghosts=True, frame=parse_frame(half_fov(lens), "x", None, None))  # the frame `degrade` was given
    planner = FrameGhosts.plan(pinhole, grid, spec, force=False, lens=lens)
    image = np.atleast_3d(read_image(pinhole))
    source = float(image[image.max(axis=-1) > planner.threshold].sum() / image.shape[-1])
    if not source > 0:
        raise SolasError(f"{pinhole}: no pixel above the ghost threshold {planner.threshold:g}: no source to compare")
    direct = traced_direct(folder / f"{name}.xml", lens)
    found = []
    for k, path in enumerate(planner.grid.paths):
        flare = frame_ghosts(image, planner.grid.only(k), planner.fields, planner.channels, planner.threshold)[0]
        found.append((float(flare.sum()), k, path, flare.mean(axis=-1)))
    rows = []
    for light, _, path, degraded in sorted(found, key=lambda f: -f[0])[:count]:
        scene = load(
            folder / f"{name}.xml", VARIANT, lens, ghosts=f"{path[0]},{path[1]}", response=f"mono:{WAVELENGTH_NM}"
        )
        image_r = np.asarray(render_scene(scene, spp).image, dtype=np.float64).mean(axis=-1)
        fraction_d, fraction_r = light / image.shape[-1] / source, float(image_r.sum()) / direct
        rows.append({"path": list(path), "centroid_degraded": centroid(degraded).tolist(),
                     "centroid_rendered": centroid(image_r).tolist(),
                     "centroid_px": float(np.hypot(*(centroid(degraded) - centroid(image_r)))),
                     "light_degraded": fraction_d, "light_rendered": fraction_r,
                     "light_ratio": fraction_d / fraction_r})  # fmt: skip
    return rows
