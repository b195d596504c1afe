"""`solas-mi degrade`: an image degraded by a lens's spatially variant PSF grid.

The input image is the ideal (pinhole) image of the scene spanning the grid's ±x field range; its
pixel grid is the sensor (`kernels.grid_camera`). PNG/JPEG input is sRGB-decoded first (unless
--linear); the output is linear OpenEXR plus an sRGB PNG beside it.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..outputs import add_png_option

LARGE_IMAGE_VALUES = 4096 * 3072 * 3  # beyond 4K (≈ 1.7 s) the command reports each channel
# the DegradeSpec fields `degrade` takes
DEGRADE_OPTIONS = (
    "method",
    "boundary",
    "occlusion",
    "silhouette",
    "linear",
    "calibration_model",
    "ghosts",
    "ghost_threshold",
)


def run_degrade(args: argparse.Namespace) -> int:
    from ..imageio import image_size
    from ..labelkinds import parse_label_files
    from ..outputs import data_and_preview
    from ..progress import Progress
    from ..psf.depth import read_grid
    from .output import degrade_file
    from .spec import DegradeSpec

    labels = dict(parse_label_files(args.labels, "--labels")) if args.labels is not None else {}
    output, png = data_and_preview(
        args.output,
        args.png,
        inputs=[args.image, args.psf_grid, *labels.values()] + ([args.depth] if args.depth else []),
    )
    spec = DegradeSpec.from_args(args, DEGRADE_OPTIONS, frame=frame_from_args(args))
    rows, cols, channels = image_size(args.image)
    large = rows * cols * channels > LARGE_IMAGE_VALUES

    # a large image takes long enough to want a sign of life
    with Progress("degrade", channels, "channels", enabled=large) as bar:
        meta = degrade_file(
            args.image,
            read_grid(args.psf_grid),
            args.psf_grid,
            output,
            png,
            spec,
            force=args.force,
            depth=args.depth,
            progress=bar,
            labels=labels,
            calibration_model=spec.calibration_model,
        )
    if meta["camera"].get("calibration", True) is None:
        print(f"degrade: no calibration in the metadata: {meta['camera']['no_calibration']}", file=sys.stderr)
    height, width = meta["output_shape"][:2]
    print(
        f"wrote {output} and {png} ({spec.method}{', depth-aware' if args.depth else ''}, {width}x{height} px, "
        f"{meta['seconds']:.2f} s)"
    )
    if "ghosts" in meta:
        report_ghosts(meta["ghosts"], meta["labels"]["outputs"]["layers"])
    if labels:
        about = meta["labels"]
        print(
            f"wrote the labels {', '.join(about['kinds'])} warped with it: {', '.join(about['outputs'].values())} "
            f"({100 * about['valid_fraction']:.1f} % of the pixels valid)"
        )
    return 0


def report_ghosts(about: dict, layers: str) -> None:
    """Say what `degrade --ghosts` added (`convolution.ghosts`) and warn of what it assumed."""
    for warning in about["warnings"]:
        print(f"degrade: warning: {warning}", file=sys.stderr)
    print(
        f"added the ghosts of {about['source_pixels']} source pixels ({about['cells']} field cells, {about['paths']} "
        f"ghost paths of {about['lens']}, {about['seconds']:.2f} s); the flare label in {layers}"
    )


def add_frame_options(p) -> None:
    """The frame's camera (`optics.frame`): one of --fov-deg (with --fov-axis), --intrinsics, --fisheye;
    none: the image spans the grid's x field range."""
    from ..optics.frame import FISHEYE, FOV_AXES

    p.add_argument(
        "--fov-deg", type=float, help="the frame's half field of view (deg) across --fov-axis, axis at its centre"
    )
    p.add_argument("--fov-axis", choices=FOV_AXES, default="x", help="what --fov-deg spans (default: x, the width)")
    p.add_argument(
        "--intrinsics",
        metavar="FX,FY,CX,CY",
        help="the frame's pinhole intrinsics (pixels), or an OpenCV calibration file without distortion (.yaml, .json)",
    )
    p.add_argument(
        "--fisheye",
        metavar="MODEL:FX,FY,CX,CY,C1,...",
        help=f"the frame's fisheye calibration, MODEL one of {', '.join(FISHEYE)} (k1..k4; a1..a4[,aspect])"
        ", or an OpenCV fisheye (.yaml, .json) or WoodScape (.json) calibration file (`solas-mi lens "
        "calibrate` writes them): its field is checked against the lens's",
    )


def frame_from_args(args: argparse.Namespace):
    """The frame's camera of the options of `add_frame_options` (`optics.frame.FrameCamera`), or None."""
    from ..optics.frame import parse_frame

    return parse_frame(args.fov_deg, args.fov_axis, args.intrinsics, args.fisheye)


def register(subparsers: Any) -> None:
    """Add the `degrade` subcommand."""
    from ..labelkinds import kinds_help
    from .spec import DegradeSpec

    p = subparsers.add_parser(
        "degrade",
        help="degrade an image with a lens's spatially variant PSF grid (FFT convolution)",
        description="Convolve an image with a PSF grid from `solas-mi psf-grid`. The image is the ideal "
        "(pinhole) image spanning the grid's ±x field range; its pixels are the sensor's. Channels "
        "R, G, B use the grid's wavelengths longest first (656, 531, 486 nm); a one-wavelength grid "
        "serves every channel. PSFs are resampled to the pixel pitch exactly (PSF samples and "
        "pixel areas integrated), centred on each wavelength's real chief ray (distortion and "
        "lateral colour are kept). Writes linear OpenEXR and an sRGB PNG beside it. One frame with its "
        "intrinsics and a lens to scale to them (--scale-lens): `solas-mi batch degrade FRAME --lens "
        "LENS --intrinsics FX,FY,CX,CY --scale-lens PIXEL_UM -o DIR`, a batch of one that computes "
        "the scaled lens's grid.",
    )
    p.add_argument("image", help="PNG/JPEG (sRGB, decoded unless --linear) or EXR (linear)")
    p.add_argument("--psf-grid", required=True, metavar="GRID.exr", help="PSF grid written by `solas-mi psf-grid`")
    p.add_argument(
        "--depth",
        metavar="DEPTH.exr",
        help="the image's depth map (OpenEXR, metres along the optical "
        "axis, inf: sky; one channel or Z/depth/Y) with a grid over object distance (psf-grid "
        "--distances-m): PSFs interpolated in field and in 1/distance",
    )
    p.add_argument(
        "--labels",
        metavar="KIND=FILE[,KIND=FILE...]",
        help=f"the image's label files (KIND one of {kinds_help()}), warped by exactly the mapping the "
        "image goes through and written beside the output: the layers in OUT.labels.exr with "
        "labels.valid (1 where the pixel's source lies inside the frame), the boxes in OUT.boxes.json",
    )
    DegradeSpec.add_flags(p, DEGRADE_OPTIONS)
    add_frame_options(p)
    p.add_argument("-o", "--output", required=True, metavar="OUT.exr", help="output OpenEXR (linear)")
    add_png_option(p)
    p.add_argument("--force", action="store_true", help="run even when the estimated memory exceeds what is free")
    p.set_defaults(run=run_degrade)
