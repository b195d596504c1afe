"""Command-line front ends of the direct render: `scene`, `render`, `render-image`."""
from __future__ import annotations

import argparse
import math
import shutil
import sys
from pathlib import Path

from ..errors import SolasError
from ..outputs import add_png_option
from .spec import MAX_SPP, RenderSpec

DEFAULT_IMAGE = "images/rocket.png"  # under the shipped scenes directory
BYTES_PER_SAMPLE = 80  # a pass's wavefront (measured: 1.1 GB peak for 12.6 M samples in one pass)
SAMPLES_PER_SECOND_PER_CORE = 0.9e6  # measured on the bundled image, `lines` (README: 1.8–2 M/s on 2 cores)


def _check_spp(spp) -> None:
    if not (isinstance(spp, int) and 1 <= spp <= MAX_SPP):
        raise SolasError(f"samples per pixel {spp!r} must be an integer from 1 to {MAX_SPP}")


def check_render(width: int, height: int, spp: int, force: bool, labels=()) -> None:
    """Refuse an absurd spp or a render that cannot fit in memory (its label layers, `labels`, counted);
    announce a long one on stderr (how long it takes depends on what else the machine runs: its progress
    tells the time left at the rate measured)."""
    import os

    from ..budget import check_memory
    from .labels import memory_bytes, parse_labels
    from .stock import SAMPLES_PER_PASS  # the larger pass of the two engines (the loop's is at most half of it)

    _check_spp(spp)
    pixels = width * height
    kinds = parse_labels(labels)
    need = max(pixels, SAMPLES_PER_PASS) * BYTES_PER_SAMPLE + 48 * pixels + memory_bytes(pixels, kinds)
    check_memory(f"render {width}x{height}" + (f" with labels {','.join(kinds)}" if kinds else ""), need, force,
                 "a smaller sensor")
    if pixels * spp > 60 * SAMPLES_PER_SECOND_PER_CORE * (os.cpu_count() or 1):  # a minute at least, idle
        print(f"render {width}x{height} at {spp} spp: {pixels * spp:.3g} samples, a long render: its progress "
              "tells the time left at the rate it measures", file=sys.stderr, flush=True)


def _progress(spp: int):
    """The render's progress in samples per pixel (a fraction while a large image's bands are traced)."""
    from ..progress import Progress

    return Progress("render", spp, "spp")


def _default_image() -> str:
    from ..resources import resource_dir

    return str(resource_dir("scenes") / DEFAULT_IMAGE)


def _copy_beside(path: Path, out: Path) -> str:
    """Copy `path` into the scene folder `out` (atomically; nothing when it is already there): its name."""
    from ..imageio import atomic_path

    if not (out / path.name).exists() or not (out / path.name).samefile(path):
        with atomic_path(out / path.name) as tmp:
            shutil.copyfile(path, tmp)
    return path.name


SCENE_SETTINGS = ("sensor", "pitch_um", "fov_deg", "response", "boundary", "fresnel", "rings", "spp")
# every setting but a scene file's focus distance
SCENE_FILE_SETTINGS = ("variant", "seed", "labels")  # `render`'s own (its lens camera's come from its flags)
IMAGE_SETTINGS = ("sensor", "pitch_um", "fov_deg", "response", "boundary", "fresnel", "rings", "mapping", "spp",
                  "variant", "seed")


def _scene(args) -> int:
    from ..optics.camera import camera_for
    from ..optics.commands import load_lens
    from ..outputs import output_folder
    from ..userfiles import check
    from .response import parse
    from .scene import write_scene

    out = output_folder(args.output)
    spec = RenderSpec.from_args(args, SCENE_SETTINGS)
    lens = load_lens(args)
    parse(spec.response, lens.wavelengths_nm)  # a bad response is refused now, not when the scene renders
    camera = camera_for(lens, spec.sensor, spec.fov_deg, spec.pitch_um)
    out.mkdir(parents=True, exist_ok=True)
    image = check(args.image or _default_image(), "image file")  # copied beside the scene: a regular file
    kind, sep, table = spec.response.partition(":")
    if kind.strip().lower() == "table" and table:  # the table travels with the scene, like the image
        spec = spec.replace(response=f"{kind}{sep}{_copy_beside(Path(table), out)}")
    xml = write_scene(lens, out, _copy_beside(image, out), camera, spec)
    print(f"wrote {xml} (meshes in {out / 'meshes'}); render it with: solas-mi render {xml} -o out.exr")
    return 0


# auto: our stratified loop for the scenes it was made for (a lens_sensor before an image_object, from
# `solas-mi scene`: it renders the sensor's response exactly, R/G/B lines included), the scene's own
# integrator for everything else; scene: always the scene's own (stock path where it has none); solas: the loop
INTEGRATORS = ("auto", "scene", "solas")


def scene_params(items) -> dict[str, str]:
    """The scene parameters of --set NAME=VALUE options (a list, or None), as `user_scene.load` takes them."""
    params = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SolasError(f"--set {item!r} must look like name=value (a <default> of the scene)")
        params[key] = value
    return params


def add_set_option(p, where: str = "") -> None:
    """--set NAME=VALUE (`scene_params`), its help opening with `where` it applies."""
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help=f"{where}override a <default> of the scene (e.g. --set image=other.png); repeatable")


def _image_scene(scene) -> bool:
    """A scene of `solas-mi scene`: a lens_sensor looking at one image_object."""
    return (type(scene.sensors()[0]).__name__ == "LensSensor"
            and [type(e).__name__ for e in scene.emitters()] == ["ImageObject"])


def _render(args) -> int:
    from ..optics.commands import load_lens
    from ..outputs import data_and_preview
    from .user_scene import load

    data_file, png = data_and_preview(args.output, args.png, inputs=[args.scene])
    params = scene_params(args.set)
    lens = load_lens(args) if args.lens else None
    if lens is None and any(v is not None for v in (args.pitch_um, args.focus_distance, args.world_unit_mm)):
        raise SolasError("--pitch-um, --focus-distance and --world-unit-mm set the lens camera: give --lens too")
    if lens is not None and args.integrator == "solas":
        raise SolasError("--integrator solas renders lens_sensor scenes (from `solas-mi scene`); with --lens the "
                         "scene's own integrator renders it")
    run = RenderSpec.from_args(args, SCENE_FILE_SETTINGS)
    notes = []
    focus = _focus(args.focus_distance)
    scene = load(args.scene, run.variant, lens, params, notes, pitch_um=args.pitch_um, focus_distance=focus,
                 response=args.response, world_unit_mm=args.world_unit_mm, ghosts="only" if args.ghosts else None)
    for note in notes:
        print(f"render: {note}", file=sys.stderr)
    spp = args.spp if args.spp is not None else int(scene.sensors()[0].sampler().sample_count())
    width, height = (int(v) for v in scene.sensors()[0].film().crop_size())
    check_render(width, height, spp, args.force, run.labels)
    loop = args.integrator == "solas" or (args.integrator == "auto" and lens is None and _image_scene(scene))
    if loop and (run.labels or args.ghosts):
        raise SolasError(f"--{'labels' if run.labels else 'ghosts'} are traced through a lens camera: give --lens, "
                         "or a scene with a lens_camera")
    if args.ghosts and not loop:
        from .flare import render_with_flare

        with _progress(spp) as bar:
            result = render_with_flare(scene, spp, seed=run.seed, progress=bar, labels=run.labels)
    elif loop:
        from .loop import render

        with _progress(spp) as bar:
            result = render(scene, spp, seed=run.seed, progress=bar)
    else:
        from .stock import render_scene

        with _progress(spp) as bar:
            result = render_scene(scene, spp, seed=run.seed, progress=bar, labels=run.labels)
    result.meta["scene"] = str(args.scene)
    if lens is not None:
        from .user_scene import camera_meta

        result.meta.update(lens=lens.name, lens_hash=lens.hash, **camera_meta(scene))
        result.meta["camera"] = lens_camera(scene, args.calibration_model)
    return _write(result, data_file, png)


def lens_camera(scene, model: str) -> dict:
    """The camera of a render through a lens_camera: lens (as focused), sensor, pitch, focus and the fit of
    `model` to the lens's chief-ray mapping over the film (`optics.calibration.describe_camera`)."""
    from ..optics.calibration import Sensor, describe_camera

    sensor = scene.sensors()[0]
    width, height = (int(v) for v in sensor.film().crop_size())
    wavelength = sensor.response.single_wavelength or sensor.lens.primary_wavelength
    return describe_camera(sensor.lens, Sensor(width, height, float(sensor.pitch_um)), model,
                           wavelength_nm=float(wavelength))


def _focus(text: str | None) -> float | str | None:
    """--focus-distance: world units (a positive number, inf) or "auto"."""
    if text is None or text == "auto":
        return text
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not value > 0:
        raise SolasError(f"--focus-distance {text!r} must be a positive distance in world units, inf, or auto")
    return value


def _write(result, data_file, png) -> int:
    from ..outputs import written_together

    with written_together(data_file, png) as (tmp_data, tmp_png):
        result.write(tmp_data, tmp_png)
    print(f"wrote {data_file} and {png} ({result.seconds:.1f} s, {result.samples_per_second / 1e6:.2f} M samples/s)")
    return 0


def _render_image(args) -> int:
    from ..optics.commands import load_lens
    from ..outputs import data_and_preview
    from .image import render_image

    data_file, png = data_and_preview(args.output, args.png, inputs=[args.image])
    spec = RenderSpec.from_args(args, IMAGE_SETTINGS)
    rows, cols = spec.sensor
    check_render(cols, rows, spec.spp, args.force)
    lens = load_lens(args)
    with _progress(spec.spp) as bar:
        result = render_image(lens, args.image, spec, progress=bar, calibration_model=args.calibration_model)
    result.meta["image"] = str(args.image)
    return _write(result, data_file, png)


def _add_output_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--force", action="store_true", help="run even when the estimated memory exceeds what is free")
    p.add_argument("-o", "--output", required=True, help="output OpenEXR file (linear)")
    add_png_option(p)


def register(sub) -> None:
    from ..optics.commands import add_environment_options, add_lens_argument
    from ..optics.formats import lens_help

    scene = sub.add_parser("scene", help="write a Mitsuba scene (XML + cap meshes) for a lens")
    add_lens_argument(scene)
    scene.add_argument("-o", "--output", required=True, help="output directory")
    scene.add_argument("--image", help="input image (copied beside the scene; default: the bundled photograph)")
    RenderSpec.add_flags(scene, SCENE_SETTINGS)
    scene.set_defaults(run=_scene)

    render = sub.add_parser(
        "render", help="render a Mitsuba scene XML to OpenEXR + PNG, through a real lens with --lens",
        description="Render a scene with its own integrator (stock path where it has none): a scene from "
                    "`solas-mi scene`, any scene holding a lens_sensor or lens_camera, or, with --lens, any "
                    "Mitsuba scene whose perspective camera is replaced by a lens_camera at the same pose.")
    render.add_argument("scene", help="scene XML")
    from ..labelkinds import FLARE_LAYERS
    from ..optics.calibration.command import add_calibration_option

    add_calibration_option(render)
    add_set_option(render)
    render.add_argument("--lens", help=f"replace the scene's perspective camera by this lens: {lens_help()}")
    add_environment_options(render)
    render.add_argument("--pitch-um", type=float, help="with --lens: pixel pitch in µm (default: the lens's field "
                                                       "matches the perspective camera's fov)")
    render.add_argument("--focus-distance", help="with --lens: focus distance in world units, or auto (the depth "
                                                 "at the image centre); default: a thinlens camera's, else the "
                                                 "lens file's image plane")
    render.add_argument("--world-unit-mm", type=float, help="with --lens: one world unit of the scene in mm "
                                                            "(default 1000: metres)")
    render.add_argument("--response", help="with --lens: camera response (srgb, lines, mono:<nm>, table:<file.csv>)")
    render.add_argument("--integrator", choices=INTEGRATORS, default=INTEGRATORS[0],
                        help="auto (default): solas-mi's stratified loop for scenes of `solas-mi scene`, the "
                             "scene's own integrator for any other; scene: the scene's own (path where it has "
                             "none); solas: the loop (lens_sensor + image_object scenes)")
    render.add_argument("--ghosts", action="store_true",
                        help="add the stray light of the lens's ghosts (every two-reflection path, its coatings' "
                             "or Fresnel's reflectance; traced from the scene's area emitters, delta lights and "
                             "environment map's sun to the film, and added) and the flare label layers "
                             f"{', '.join(FLARE_LAYERS)}; the lens camera's surfaces then weigh by their "
                             "transmittance (its fresnel 'transmit')")
    render.add_argument("--spp", type=int, help="samples per pixel (default: the scene's)")
    RenderSpec.add_flags(render, SCENE_FILE_SETTINGS)
    _add_output_options(render)
    render.set_defaults(run=_render)

    image = sub.add_parser("render-image", help="render an input image through the lens geometry")
    add_lens_argument(image)
    image.add_argument("image", help="input image (PNG/JPEG: sRGB; EXR: linear)")
    RenderSpec.add_flags(image, IMAGE_SETTINGS)
    add_calibration_option(image)
    _add_output_options(image)
    image.set_defaults(run=_render_image)
