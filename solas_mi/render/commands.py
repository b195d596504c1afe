"""Command-line front ends of the direct render: `scene`, `render`, `render-image`."""
from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

from ..errors import SolasError
from ..options import parse_wxh

DEFAULT_IMAGE = "images/rocket.png"  # under the shipped scenes directory


def _progress(done: int, total: int) -> None:
    print(f"\rrender: {done}/{total} spp ({100.0 * done / total:.0f} %)", end="", file=sys.stderr, flush=True)
    if done == total:
        print(file=sys.stderr)


def _default_image() -> str:
    from ..resources import resource_dir

    return str(resource_dir("scenes") / DEFAULT_IMAGE)


def _scene(args) -> int:
    from ..optics.camera import camera_for
    from ..optics.lens import Lens
    from .scene import write_scene

    lens = Lens.load(args.lens)
    camera = camera_for(lens, parse_wxh(args.sensor, "--sensor"), args.fov_deg, args.pitch_um)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    image = Path(args.image or _default_image())
    if not image.is_file():
        raise SolasError(f"no such image file: {image}")
    if not (out / image.name).exists() or not (out / image.name).samefile(image):
        shutil.copyfile(image, out / image.name)
    xml = write_scene(lens, out, image.name, camera, args.rings, args.spp, args.response, args.boundary, args.fresnel)
    print(f"wrote {xml} (meshes in {out / 'meshes'}); render it with: solas-mi render {xml} -o out.exr")
    return 0


def _render(args) -> int:
    from .loop import render
    from .mitsuba import load_scene

    params = {}
    for item in args.set or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SolasError(f"--set {item!r} must look like name=value (a <default> of the scene)")
        params[key] = value
    if args.spp is not None:
        params["spp"] = args.spp
    scene = load_scene(args.scene, args.variant, **params)
    spp = args.spp or int(scene.sensors()[0].sampler().sample_count())
    result = render(scene, spp, seed=args.seed, progress=_progress)
    result.meta["scene"] = str(args.scene)
    png = result.write(args.output, args.png)
    print(f"wrote {args.output} and {png} ({result.seconds:.1f} s, {result.samples_per_second / 1e6:.2f} M samples/s)")
    return 0


def _render_image(args) -> int:
    from ..optics.lens import Lens
    from .image import render_image

    lens = Lens.load(args.lens)
    result = render_image(lens, args.image, parse_wxh(args.sensor, "--sensor"), args.pitch_um, args.spp,
                          args.response, args.fov_deg, args.boundary, args.fresnel, args.rings, args.variant,
                          args.seed, progress=_progress)
    result.meta["image"] = str(args.image)
    png = result.write(args.output, args.png)
    print(f"wrote {args.output} and {png} ({result.seconds:.1f} s, {result.samples_per_second / 1e6:.2f} M samples/s)")
    return 0


def _add_render_options(p: argparse.ArgumentParser, spp_default: int | None) -> None:
    from .mitsuba import VARIANTS

    p.add_argument("--spp", type=int, default=spp_default, help="samples per pixel")
    p.add_argument("--variant", choices=VARIANTS, help="Mitsuba variant (default: cuda_ad_spectral with a GPU, "
                                                       "else llvm_ad_spectral)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("-o", "--output", required=True, help="output OpenEXR file (linear)")
    p.add_argument("--png", help="sRGB PNG for viewing (default: beside the EXR)")


def _add_camera_options(p: argparse.ArgumentParser) -> None:
    from .scene import BOUNDARIES, DEFAULT_RINGS

    p.add_argument("--sensor", default="1280x960", help="sensor pixels, columns x rows")
    p.add_argument("--pitch-um", type=float, help="pixel pitch (µm; default: the sensor's width spans the field)")
    p.add_argument("--fov-deg", type=float, help="half the horizontal field the image spans (default: the lens's)")
    p.add_argument("--response", default="srgb", help="camera response: srgb, lines, mono:<nm>, table:<file.csv>")
    p.add_argument("--boundary", choices=BOUNDARIES, default="edge", help="the object outside the image: "
                   "edge (repeat the border), reflect, zero (black)")
    p.add_argument("--fresnel", choices=("transmit", "sample", "off"), default="transmit",
                   help="Fresnel losses: transmit (weight by transmittance), sample (ghost paths too), off")
    p.add_argument("--rings", type=int, default=DEFAULT_RINGS, help="rings of each cap mesh")


def register(sub) -> None:
    scene = sub.add_parser("scene", help="write a Mitsuba scene (XML + cap meshes) for a lens")
    scene.add_argument("lens", help="shipped lens name (solas-doublet) or a .toml lens file")
    scene.add_argument("-o", "--output", required=True, help="output directory")
    scene.add_argument("--image", help="input image (copied beside the scene; default: the bundled photograph)")
    scene.add_argument("--spp", type=int, default=64, help="samples per pixel written into the scene")
    _add_camera_options(scene)
    scene.set_defaults(run=_scene)

    render = sub.add_parser("render", help="render a solas-mi scene XML to OpenEXR + PNG")
    render.add_argument("scene", help="scene XML (from `solas-mi scene`)")
    render.add_argument("--set", action="append", metavar="NAME=VALUE",
                        help="override a <default> of the scene (e.g. --set image=other.png); repeatable")
    _add_render_options(render, None)
    render.set_defaults(run=_render)

    image = sub.add_parser("render-image", help="render an input image through the lens geometry")
    image.add_argument("lens", help="shipped lens name (solas-doublet) or a .toml lens file")
    image.add_argument("image", help="input image (PNG/JPEG: sRGB; EXR: linear)")
    _add_camera_options(image)
    _add_render_options(image, 64)
    image.set_defaults(run=_render_image)
