"""`solas-mi experiment street` (the natural-scene SFR experiment on the shipped street scene) and
`solas-mi experiment street-scene` (write the scene again). The work is done by
`street.run.run` and `street.scene.write_street`."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..options import parse_wxh, positive_ints
from ..outputs import output_folder, safe_name


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def run_street(args: argparse.Namespace) -> int:
    from ..optics.commands import load_lens
    from ..render.commands import check_render
    from .street.run import Settings, run

    lens = load_lens(args)
    height, width = parse_wxh(args.size, "--size")
    for spp in (args.spp_ideal, args.spp):  # its renders: refused when absurd or too large, announced when long
        check_render(width, height, spp, args.force)
    layers = () if args.depth_layers.strip().lower() == "none" else positive_ints(args.depth_layers, "--depth-layers")
    out = output_folder(args.output)  # made once the settings are known to be sound
    settings = Settings(
        width=width,
        height=height,
        spp_ideal=args.spp_ideal,
        spp_lens=args.spp,
        near_focus_m=args.near_focus,
        variant=args.variant,
        depth_layers=layers,
    )
    outcome = run(lens, out, settings, log=_say)
    print((out / "street.md").read_text())
    print(
        f"wrote {out}/street.md, street.csv, street.json, fig5_*.png, error_*.png and the images "
        f"({', '.join(safe_name(n) for n in outcome.images)}, depth) as .exr and .png"
    )
    return 0


def run_street_scene(args: argparse.Namespace) -> int:
    from .street.scene import write_street

    files = write_street(output_folder(args.output))
    print(f"wrote {len(files)} files to {args.output} (street.xml and textures/)")
    return 0


def register(sub: Any) -> None:
    """Add the `experiment` subcommands."""
    from ..optics.commands import add_environment_options
    from ..optics.formats import lens_help
    from ..render.mitsuba import VARIANTS
    from ..resources import resource_dir

    exp = sub.add_parser("experiment", help="experiments on shipped scenes").add_subparsers(
        dest="experiment_command", required=True
    )
    p = exp.add_parser(
        "street",
        help="the SOLAS paper's natural-scene SFR experiment on the procedural street scene",
        description="Render the street scene through an ideal camera with the lens's field, degrade it by the "
        "lens's PSF grid (interp and the paper's patch 8x6 and 32x24), render it through the lens "
        "camera focused at infinity and near, measure the natural-scene SFR of each against the ideal "
        "image per annulus beside the PSF grid's predicted MTF50, and map the convolution's error "
        "against the renders on near and far objects. Writes street.md/.csv/.json, figure-5 plots, "
        "error maps and every image; step times on stderr and in the table.",
    )
    p.add_argument("--lens", default="solas-doublet", help=f"{lens_help()} (default solas-doublet)")
    add_environment_options(p)
    p.add_argument("-o", "--output", required=True, help="output folder")
    p.add_argument("--size", default="1280x960", help="image WIDTHxHEIGHT in px (default 1280x960)")
    p.add_argument("--spp", type=int, default=64, help="lens render samples per pixel (default 64)")
    p.add_argument("--spp-ideal", type=int, default=64, help="ideal image samples per pixel (default 64)")
    p.add_argument("--force", action="store_true", help="render even when the estimated memory exceeds what is free")
    p.add_argument("--near-focus", type=float, help="near focus distance in m (default: the lens's framing)")
    p.add_argument(
        "--depth-layers",
        default="1,2,4,8,16",
        help="step (g), the depth-aware convolution: intervals between depth nodes, each dividing the "
        "largest (default 1,2,4,8,16); none: skip it",
    )
    p.add_argument(
        "--variant",
        choices=VARIANTS,
        help="Mitsuba variant (default: CUDA where it works, else LLVM, spectral; the grey scene renders "
        "alike in a mono one)",
    )
    p.set_defaults(run=run_street)
    p = exp.add_parser(
        "street-scene",
        help="write the procedural street scene (Mitsuba XML and textures)",
        description="Write street.xml and textures/ (the same bytes every time).",
    )
    p.add_argument(
        "-o",
        "--output",
        default="street",
        help="output folder; the shipped copy is %s" % (resource_dir("scenes") / "street"),
    )
    p.set_defaults(run=run_street_scene)
