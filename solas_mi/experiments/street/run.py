"""The SOLAS paper's experiment on the street scene (`solas-mi experiment street`): the ideal image,
the ideal image degraded by the lens's PSF grid, and the scene rendered through the lens, measured
by the natural-scene SFR on the same edges, per annulus, beside the MTF50 the PSF grid predicts.

Steps (each timed, wall-clock seconds):

(a) ideal: the scene through a `perspective` camera with the lens's field (±field_deg across the
    width), a one-channel film at the lens's primary wavelength (the scene is grey: the mono variant's
    film, or in a spectral variant a specfilm of a ±2 nm band);
    depth: the distance (m) along each pixel's ray (`aov`), to tell near objects from far ones.
(b) the PSF grid (geometric, one wavelength, normalised "none", nodes at the centres of COLS×ROWS
    blocks as in the cross-validation) and `convolution.methods.degrade` of the ideal image: interp
    on the finest grid, patch on each grid (the paper's 8×6 and 32×24), in the lens camera's units;
    and interp with the PSFs of an object at the framing's far distance (the lens still focused as
    its file says: a far subject is not at infinity, and the doublet's defocus depends on it).
(c) the scene through `lens_camera` (same pose, film and sampler; `mono` at the primary wavelength),
    focused at infinity and at the framing's near focus distance.
Every render runs in the settings' variant, by default the spectral one (`render.mitsuba.variant_for`:
the mono variant renders this grey scene alike, 1.5× slower).
(d) NS-SFR (`metrics.nssfr`) of every degraded image against the ideal one, on the edges found in the
    ideal one, per annulus: all edges and the far ones (every pixel of the ROI beyond FAR_M).
(e) relative error maps (interp − render)/RMS(render) for both renders; RMS of the error on near
    pixels (depth < 1.5 × near focus) and far pixels (beyond FAR_M or sky) separately.
(f) the run time of each step.

Units: the convolution takes the ideal image (radiance) to irradiance in units of the ideal camera's
(`validation.engines.convolve`) and divides by k = axis irradiance / ideal irradiance, the lens
camera's unit (a lossless lens's on-axis irradiance).
"""
from __future__ import annotations

import math
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ...errors import SolasError
from ...resources import resource_dir
from .framings import framing
from .measure import FAR_M, measure, write_tables

PATCH_GRIDS = ((8, 6), (32, 24))
INTERP_GRID = (32, 24)
SCENE = resource_dir("scenes") / "street" / "street.xml"
BAND = ((-2.0, 0.0), (-1.0, 1.0), (1.0, 1.0), (2.0, 0.0))  # the ideal film's sensitivity: (nm from λ, weight)
BAND_NM = 3.0  # its integral (nm): specfilm sums sensitivity × radiance, so the ideal image is divided by it


@dataclass
class Settings:
    """Image size (px), samples per pixel of the ideal image, the depth map and the lens renders, the
    convolution grids (columns, rows), the near focus (m; None: the framing's), the Mitsuba variant."""

    width: int = 1280
    height: int = 960
    spp_ideal: int = 64
    spp_lens: int = 64
    spp_depth: int = 4
    interp_grid: tuple[int, int] = INTERP_GRID
    patch_grids: tuple[tuple[int, int], ...] = PATCH_GRIDS
    near_focus_m: float | None = None
    variant: str | None = None
    scene: Path = SCENE

    def check(self) -> None:
        for name in ("width", "height", "spp_ideal", "spp_lens", "spp_depth"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise SolasError(f"{name.replace('_', ' ')} {value!r} must be a positive integer")
        if min(self.width, self.height) < 32:
            raise SolasError(f"image size {self.width}x{self.height} must be at least 32x32 px")
        if self.near_focus_m is not None and not self.near_focus_m > 0:
            raise SolasError(f"near focus {self.near_focus_m!r} m must be a positive distance")


@dataclass
class Outcome:
    """Images (name → H×W float32), the depth map (m, inf: sky), SFR reports per degraded image, error
    statistics, step times (s) and the metadata written to street.json."""

    images: dict[str, np.ndarray]
    depth: np.ndarray
    reports: dict = field(default_factory=dict)
    errors: dict = field(default_factory=dict)
    seconds: dict = field(default_factory=dict)
    meta: dict = field(default_factory=dict)


def experiment_scene(source: Path, out: Path, primary_nm: float, depth: bool = False, spectral: bool = True) -> Path:
    """The street scene as the experiment renders it, written to `out`: a one-channel film at
    `primary_nm` — for a `spectral` variant a specfilm of a ±2 nm band, else the scene's own film
    (Mitsuba's luminance) — or, `depth`, an `aov` depth integrator; texture paths absolute."""
    from ...imageio import write_text

    if not source.is_file():
        raise SolasError(f"no street scene at {source}; write it with `solas-mi experiment street-scene`")
    root = ET.parse(source).getroot()
    for tex in root.iter("texture"):
        for s in tex.iter("string"):
            if s.get("name") == "filename":
                s.set("value", str((source.parent / s.get("value")).resolve()))
    film = root.find("sensor/film")
    if depth:
        root.remove(root.find("integrator"))
        aov = ET.Element("integrator", {"type": "aov"})
        ET.SubElement(aov, "string", {"name": "aovs", "value": "depth:depth"})
        root.insert(0, aov)
    elif not spectral:
        ET.SubElement(film, "string", {"name": "pixel_format", "value": "luminance"})  # Mitsuba's mono film
    else:
        film.set("type", "specfilm")
        band = ", ".join(f"{primary_nm + d:g}:{v:g}" for d, v in BAND)
        ET.SubElement(film, "spectrum", {"name": "Y", "value": band})
    path = out / ("depth.xml" if depth else "scene.xml")
    write_text(path, ET.tostring(root, encoding="unicode"))
    return path


def _render(xml: Path, variant, lens, params: dict, spp: int, log, **lens_options) -> np.ndarray:
    from ...render.stock import render_scene
    from ...render.user_scene import load

    scene = load(xml, variant, lens, params, **lens_options)
    quarters = set()

    def progress(done: int, total: int) -> None:  # a line at each quarter
        if 4 * done // total not in quarters:
            quarters.add(4 * done // total)
            log(f"  {done}/{total} spp")

    return render_scene(scene, spp, progress=progress).image


def run(lens, out: str | Path, settings: Settings | None = None, log=print) -> Outcome:
    """The experiment on `lens` (a Lens), its images and depth map written to `out` as EXR and PNG
    and the tables (street.md, .csv, .json), figure-5 plots and error maps (`measure`)."""
    from ...convolution.kernels import layout
    from ...convolution.methods import degrade
    from ...imageio import image_channels, write_exr, write_png
    from ...optics.camera import pinhole_focal_mm
    from ...optics.illumination import axis_irradiance, ideal_irradiance
    from ...psf.grid import psf_grid
    from ...render import response as responses
    from ...render.mitsuba import spectral, variant_for
    from ...render.user_scene import default_pitch_um
    from ...validation.inputs import tangent_cos3

    s = settings or Settings()
    s.check()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    fr = framing(lens)
    near_focus = s.near_focus_m or fr.near_focus_m
    fov = float(lens.field_deg)
    w, h = s.width, s.height
    primary = float(lens.primary_wavelength)
    seconds: dict[str, float] = {}

    def timed(name: str, fn, *args, **kwargs):
        log(f"street: {name} ...")
        start = time.perf_counter()
        value = fn(*args, **kwargs)
        seconds[name] = time.perf_counter() - start
        log(f"street: {name}: {seconds[name]:.1f} s")
        return value

    variant = variant_for(responses.mono(primary), s.variant)  # grey scene: a mono variant given renders it alike
    xml = experiment_scene(s.scene, out, primary, spectral=spectral(variant))
    depth_xml = experiment_scene(s.scene, out, primary, depth=True)
    params = fr.params(2 * fov, w, h, s.spp_ideal)
    band = BAND_NM if spectral(variant) else 1.0
    ideal = timed("(a) ideal image", _render, xml, variant, None, params, s.spp_ideal, log)[..., 0] / band
    depth = timed("(a) depth map", _render, depth_xml, variant, None, params, s.spp_depth, log)[..., -1]
    depth = np.where(depth > 0, depth, np.inf).astype(np.float32)

    pixel_um = default_pitch_um(lens, fov, "x", w, h)  # the lens camera's pixel, matched to the field
    field_range = (fov, math.degrees(math.atan(math.tan(math.radians(fov)) * h / w)))  # the image's y edge

    def grid_for(subject, blocks: tuple[int, int], label: str):
        return timed(f"(b) PSF grid {blocks[0]}x{blocks[1]}{label}", psf_grid, subject, grid=(blocks[1], blocks[0]),
                     wavelengths_nm=[primary], field_range_deg=field_range, method="geometric",
                     normalization="none", pitch_um=pixel_um / 8, size=160)

    grids = {blocks: grid_for(lens, blocks, "") for blocks in dict.fromkeys((s.interp_grid, *s.patch_grids))}
    # the far subject's PSFs, the lens focused as its file says
    far_grid = grid_for(replace(lens, object_distance=1e3 * fr.far_m), s.interp_grid, f", object at {fr.far_m:g} m")
    k = axis_irradiance(lens, primary) / ideal_irradiance(lens, pinhole_focal_mm(lens, fov), primary)
    weighted = ideal * tangent_cos3(w, h, fov)
    images = {"ideal": ideal}
    cases = [("interp", s.interp_grid)] + [("patch", b) for b in s.patch_grids]
    for method, blocks in cases:
        name = f"{method} {blocks[0]}x{blocks[1]}"
        images[name] = timed(f"(b) {name}", degrade, weighted, grids[blocks], method, "edge") / np.float32(k)
    far_name = f"interp {s.interp_grid[0]}x{s.interp_grid[1]} at {fr.far_m:g} m"
    images[far_name] = timed(f"(b) {far_name}", degrade, weighted, far_grid, "interp", "edge") / np.float32(k)
    lens_params = {key: v for key, v in params.items() if key != "fov"} | {"spp": str(s.spp_lens)}
    render_options = {"response": f"mono:{primary:g}", "pitch_um": pixel_um}
    images["render infinity"] = timed("(c) lens render, focus at infinity", _render, xml, variant, lens,
                                      lens_params, s.spp_lens, log, **render_options)[..., 0]
    images[f"render {near_focus:g} m"] = timed(
        f"(c) lens render, focus at {near_focus:g} m", _render, xml, variant, lens, lens_params, s.spp_lens,
        log, focus_distance=near_focus, **render_options)[..., 0]
    for name, img in images.items():
        stem = name.replace(" ", "_")
        write_exr(out / f"{stem}.exr", image_channels(img), {"lens": lens.name, "image": name, "variant": variant})
        write_png(out / f"{stem}.png", np.clip(img / 0.9, 0, 1))
    write_exr(out / "depth.exr", {"Z": depth}, {"lens": lens.name, "unit": "m", "sky": "inf"})
    lay = layout(grids[s.interp_grid], w, h)
    meta = {"lens": lens.name, "lens_hash": lens.hash, "size": [w, h], "field_deg": fov, "wavelength_nm": primary,
            "framing": params, "near_focus_m": near_focus, "far_m": FAR_M,
            "far_subject_m": fr.far_m, "unit_k": k,
            "pixel_pitch_um": lay.camera.pitch_um, "spp": {"ideal": s.spp_ideal, "lens": s.spp_lens,
                                                          "depth": s.spp_depth}, "variant": variant}
    outcome = Outcome(images, depth, seconds=seconds, meta=meta)
    predictors = {"infinity": grids[s.interp_grid], f"{fr.far_m:g} m": far_grid}
    rows = timed("(d, e) NS-SFR, predictions and error maps", measure, outcome, predictors, lay, near_focus, out)
    write_tables(out, rows, outcome)
    return outcome
