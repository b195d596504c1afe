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
(g) the depth-aware convolution (`depth`): grids over object distance for both focus settings, as
    depth nodes are added, against both renders with their noise removed (a second seed of each); near
    and far by the ideal depth map and by the render's own (the depth scene through the lens camera).

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
from ...outputs import safe_name
from ...resources import resource_dir
from .depth import LAYERS, check_layers, depth_rows
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
    depth_layers: tuple[int, ...] = LAYERS  # intervals between depth nodes of step (g); () skips it

    def check(self) -> None:
        for name in ("width", "height", "spp_ideal", "spp_lens", "spp_depth"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise SolasError(f"{name.replace('_', ' ')} {value!r} must be a positive integer")
        if min(self.width, self.height) < 32:
            raise SolasError(f"image size {self.width}x{self.height} must be at least 32x32 px")
        if self.near_focus_m is not None and not self.near_focus_m > 0:
            raise SolasError(f"near focus {self.near_focus_m!r} m must be a positive distance")
        if self.depth_layers:
            check_layers(self.depth_layers)


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
    from ...userfiles import read_bytes

    if not source.is_file():
        raise SolasError(f"no street scene at {source}; write it with `solas-mi experiment street-scene`")
    root = ET.fromstring(read_bytes(source, "scene file"))
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


def _render(xml: Path, variant, lens, params: dict, spp: int, seed: int = 0, **lens_options) -> np.ndarray:
    from ...progress import Progress
    from ...render.stock import render_scene
    from ...render.user_scene import load

    scene = load(xml, variant, lens, params, **lens_options)
    with Progress(f"street: render {xml.stem}", spp, "spp") as bar:
        return render_scene(scene, spp, seed=seed, progress=bar).image


class _Steps:
    """The experiment's shared state: its lens, settings, output folder, framing and field, the
    Mitsuba variant, and each timed step's seconds (`timed`, logged)."""

    def __init__(self, lens, out: Path, s: Settings, log):
        from ...render import response as responses
        from ...render.mitsuba import variant_for
        from ...render.user_scene import default_pitch_um

        self.lens, self.out, self.s, self.log = lens, out, s, log
        self.fr = framing(lens)
        self.near_focus = s.near_focus_m or self.fr.near_focus_m
        self.fov = float(lens.field_deg)
        self.w, self.h = s.width, s.height
        self.primary = float(lens.primary_wavelength)
        self.seconds: dict[str, float] = {}
        # grey scene: a mono variant given renders it alike
        self.variant = variant_for(responses.mono(self.primary), s.variant)
        self.pixel_um = default_pitch_um(lens, self.fov, "x", self.w, self.h)  # the lens camera's, matched to the field
        self.params = self.fr.params(2 * self.fov, self.w, self.h, s.spp_ideal)

    def timed(self, name: str, fn, *args, **kwargs):
        self.log(f"street: {name} ...")
        start = time.perf_counter()
        value = fn(*args, **kwargs)
        self.seconds[name] = time.perf_counter() - start
        self.log(f"street: {name}: {self.seconds[name]:.1f} s")
        return value


def check_lens(lens) -> None:
    """SolasError unless a perspective camera can frame the lens's field: the experiment's ideal image is
    a pinhole camera's of the lens's field (±field_deg across the width), which a fisheye's polar
    fields (to ±90 deg and past) are not."""
    from ...render.user_scene import MAX_HALF_FIELD_DEG as MAX_FIELD_DEG

    if not lens.field_type.pinhole or not 0 < lens.field_deg < MAX_FIELD_DEG:
        kind = "a fisheye (polar fields)" if not lens.field_type.pinhole else "a lens"
        raise SolasError(
            f"experiment street compares a lens with the ideal pinhole (perspective) camera of its field, "
            f"and lens {lens.name} is {kind} of ±{lens.field_deg:g} deg, which no pinhole camera frames "
            f"(its field must lie below {MAX_FIELD_DEG:g} deg); run the experiment on a rectilinear "
            "lens, and render the fisheye with `solas-mi render-image` or `solas-mi render SCENE --lens`"
        )


def run(lens, out: str | Path, settings: Settings | None = None, log=print) -> Outcome:
    """The experiment on `lens` (a Lens), its images and depth map written to `out` as EXR and PNG
    and the tables (street.md, .csv, .json), figure-5 plots and error maps (`measure`)."""
    from ...convolution.kernels import layout
    from ...optics.camera import pinhole_focal_mm
    from ...optics.illumination import axis_irradiance, ideal_irradiance

    s = settings or Settings()
    s.check()
    check_lens(lens)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    st = _Steps(lens, out, s, log)
    xml, ideal, depth = _ideal_and_depth(st)
    grids, far_grid = _psf_grids(st)
    k = axis_irradiance(lens, st.primary) / ideal_irradiance(lens, pinhole_focal_mm(lens, st.fov), st.primary)
    images = {"ideal": ideal, **_convolved(st, ideal, grids, far_grid, k), **_lens_renders(st, xml)}
    depth_errors = _depth_aware(st, xml, images, depth, k) if s.depth_layers else {}
    _write_images(st, images, depth)
    lay = layout(grids[s.interp_grid], st.w, st.h)
    meta = {
        "lens": lens.name,
        "lens_hash": lens.hash,
        "size": [st.w, st.h],
        "field_deg": st.fov,
        "wavelength_nm": st.primary,
        "framing": st.params,
        "near_focus_m": st.near_focus,
        "far_m": FAR_M,
        "far_subject_m": st.fr.far_m,
        "unit_k": k,
        "pixel_pitch_um": lay.camera.pitch_um,
        "spp": {"ideal": s.spp_ideal, "lens": s.spp_lens, "depth": s.spp_depth},
        "variant": st.variant,
    }
    outcome = Outcome(images, depth, seconds=st.seconds, meta=meta)
    predictors = {"infinity": grids[s.interp_grid], f"{st.fr.far_m:g} m": far_grid}
    rows = st.timed("(d, e) NS-SFR, predictions and error maps", measure, outcome, predictors, lay, st.near_focus, out)
    outcome.errors.update(depth_errors)
    write_tables(out, rows, outcome)
    return outcome


def _depth_aware(st: _Steps, xml: Path, images: dict, depth: np.ndarray, k: float) -> dict:
    """(g) the depth-aware convolution against both renders, their noise removed with a second seed's
    renders (`depth.depth_rows`); near and far pixels are those both the ideal camera's depth map and the
    render's own (`_lens_renders(depth=True)`) put nearer than 1.5 × the near focus, or beyond FAR_M;
    its images are added to `images`, its error rows returned."""
    from ...validation.inputs import tangent_cos3

    second = _lens_renders(st, xml, seed=1)
    through = _lens_renders(st, st.out / "depth.xml", depth=True)
    labels = ("infinity", f"{st.near_focus:g} m")
    renders = {label: (images[f"render {label}"], second[f"render {label}"]) for label in labels}
    near_m = 1.5 * st.near_focus
    masks = {
        label: (depth < near_m, depth > FAR_M, through[f"render {label}"] < near_m, through[f"render {label}"] > FAR_M)
        for label in labels
    }
    field_range = (st.fov, math.degrees(math.atan(math.tan(math.radians(st.fov)) * st.h / st.w)))
    new, rows = depth_rows(
        st, images["ideal"] * tangent_cos3(st.w, st.h, st.fov), depth, k, renders, masks, field_range
    )
    for row in rows.values():
        row.update(near_m=near_m, far_m=FAR_M)
    images.update(new)
    return rows


def _ideal_and_depth(st: _Steps) -> tuple[Path, np.ndarray, np.ndarray]:
    """(a) the scene as the experiment renders it, its ideal (pinhole) image and its depth map (m, inf: sky)."""
    from ...render.mitsuba import spectral

    s = st.s
    xml = experiment_scene(s.scene, st.out, st.primary, spectral=spectral(st.variant))
    depth_xml = experiment_scene(s.scene, st.out, st.primary, depth=True)
    band = BAND_NM if spectral(st.variant) else 1.0
    ideal = st.timed("(a) ideal image", _render, xml, st.variant, None, st.params, s.spp_ideal)[..., 0] / band
    depth = st.timed("(a) depth map", _render, depth_xml, st.variant, None, st.params, s.spp_depth)[..., -1]
    return xml, ideal, np.where(depth > 0, depth, np.inf).astype(np.float32)


def _psf_grids(st: _Steps) -> tuple[dict, object]:
    """(b) the PSF grids of every grid size, and the far subject's (the lens focused as its file says)."""
    from ...psf.grid import psf_grid

    s, fov = st.s, st.fov
    field_range = (fov, math.degrees(math.atan(math.tan(math.radians(fov)) * st.h / st.w)))  # the image's y edge

    def grid_for(subject, blocks: tuple[int, int], label: str):
        return st.timed(
            f"(b) PSF grid {blocks[0]}x{blocks[1]}{label}",
            psf_grid,
            subject,
            grid=(blocks[1], blocks[0]),
            wavelengths_nm=[st.primary],
            field_range_deg=field_range,
            method="geometric",
            normalization="none",
            pitch_um=st.pixel_um / 8,
            size=160,
        )

    grids = {blocks: grid_for(st.lens, blocks, "") for blocks in dict.fromkeys((s.interp_grid, *s.patch_grids))}
    far_grid = grid_for(
        replace(st.lens, object_distance=1e3 * st.fr.far_m), s.interp_grid, f", object at {st.fr.far_m:g} m"
    )
    return grids, far_grid


def _convolved(st: _Steps, ideal: np.ndarray, grids: dict, far_grid, k: float) -> dict[str, np.ndarray]:
    """(b) the ideal image (weighted by cos³) degraded by each grid, in units of the lens's axis
    irradiance `k` times the ideal camera's; the far subject's grid too."""
    from ...convolution.methods import degrade
    from ...validation.inputs import tangent_cos3

    s = st.s
    weighted = ideal * tangent_cos3(st.w, st.h, st.fov)
    images = {}
    for method, blocks in [("interp", s.interp_grid)] + [("patch", b) for b in s.patch_grids]:
        name = f"{method} {blocks[0]}x{blocks[1]}"
        images[name] = st.timed(f"(b) {name}", degrade, weighted, grids[blocks], method, "edge") / np.float32(k)
    far_name = f"interp {s.interp_grid[0]}x{s.interp_grid[1]} at {st.fr.far_m:g} m"
    images[far_name] = st.timed(f"(b) {far_name}", degrade, weighted, far_grid, "interp", "edge") / np.float32(k)
    return images


def _lens_renders(st: _Steps, xml: Path, seed: int = 0, depth: bool = False) -> dict[str, np.ndarray]:
    """(c) the scene through the lens camera, focused at infinity and at the near focus (sampler `seed`);
    `depth`: the depth scene's (`experiment_scene`), the mean distance along each pixel's rays through
    the lens (st.s.spp_depth samples)."""
    s = st.s
    spp = s.spp_depth if depth else s.spp_lens
    lens_params = {key: v for key, v in st.params.items() if key != "fov"} | {"spp": str(spp)}
    render_options = {"response": f"mono:{st.primary:g}", "pitch_um": st.pixel_um}
    note = (", seed " + str(seed) if seed else "") + (", depth" if depth else "")
    channel = -1 if depth else 0
    return {
        "render infinity": st.timed(
            f"(c) lens render, focus at infinity{note}",
            _render,
            xml,
            st.variant,
            st.lens,
            lens_params,
            spp,
            seed,
            **render_options,
        )[..., channel],
        f"render {st.near_focus:g} m": st.timed(
            f"(c) lens render, focus at {st.near_focus:g} m{note}",
            _render,
            xml,
            st.variant,
            st.lens,
            lens_params,
            spp,
            seed,
            focus_distance=st.near_focus,
            **render_options,
        )[..., channel],
    }


def _write_images(st: _Steps, images: dict[str, np.ndarray], depth: np.ndarray) -> None:
    """Every image as EXR and PNG (÷ 0.9, clipped), and the depth map as EXR, into the output folder."""
    from ...imageio import image_channels, write_exr, write_png

    for name, img in images.items():
        stem = safe_name(name)
        write_exr(
            st.out / f"{stem}.exr", image_channels(img), {"lens": st.lens.name, "image": name, "variant": st.variant}
        )
        write_png(st.out / f"{stem}.png", np.clip(img / 0.9, 0, 1))
    write_exr(st.out / "depth.exr", {"Z": depth}, {"lens": st.lens.name, "unit": "m", "sky": "inf"}, infinite=True)
