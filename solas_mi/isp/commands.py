"""Command line of the image processor: `--isp` on the sensor's `camera` command, which then writes the
developed 8-bit sRGB frame as a PNG beside the RAW EXR (OUT.exr → OUT.png), every stage named in the
EXR's metadata. The command is the sensor's (`sensor.commands`); this stage, later in the import order,
adds its option to it.

NumPy, OpenEXR and the processor's modules are imported when the command runs."""
from __future__ import annotations

import argparse
from typing import Any


def run_camera(args: argparse.Namespace) -> int:
    """The sensor's RAW, and with --isp the developed frame beside it, written together."""
    from ..sensor import commands as sensor

    if args.isp is None:
        return sensor.run_camera(args)
    from ..outputs import data_and_preview
    from .camera import write_frame
    from .pipeline import develop, load_isp

    isp = load_isp(args.isp)
    data, png = data_and_preview(args.output, None, [args.image, args.sensor_model, args.isp])
    raw, model, meta = sensor.raw_frame(args)
    frame, developed = develop(raw, model, isp)
    write_frame(data, raw, frame, {**meta, **developed})
    sensor.report(args, raw, model)
    print(f"{png}: developed 8-bit sRGB frame ({', '.join(developed['stages'])})")
    return 0


def register(subparsers: Any) -> None:
    """Add --isp to the sensor's `camera` command."""
    p = subparsers.choices["camera"]
    p.add_argument("--isp", default=None, metavar="default|FILE.toml",
                   help="develop the RAW through the image processor (black level, white balance, demosaicing, "
                        "colour correction, tone curve): 'default' or a TOML file with an [isp] table; the 8-bit "
                        "sRGB frame is written beside OUT.exr as OUT.png (default: RAW only)")
    p.set_defaults(run=run_camera)


def add_camera_options(p: argparse.ArgumentParser, seed: bool) -> None:
    """A batch's camera options: --sensor-model, --exposure-ms, --isp (and --seed where `seed`)."""
    g = p.add_argument_group("the camera: each frame (its values read as W/m² of image irradiance) through a sensor "
                             "and image processor, its RAW written as <name>_raw.exr and, with --isp, the developed "
                             "frame as <name>_raw.png")
    g.add_argument("--sensor-model", metavar="PRESET|FILE.toml",
                   help="the sensor: a preset's name (solas-mi sensors lists them) or a TOML file with a [sensor] table")
    g.add_argument("--exposure-ms", type=float, help="exposure time in ms (with --sensor-model)")
    g.add_argument("--isp", metavar="default|FILE.toml",
                   help="develop each RAW: 'default' or a TOML file with an [isp] table (with --sensor-model)")
    if seed:
        g.add_argument("--seed", type=int, default=0,
                       help="the sensor's seed: its fixed pattern, and with each frame's name its noise (default 0)")


def camera_from_args(args: argparse.Namespace, seed: int):
    """The `isp.camera.Camera` of the options, or None without --sensor-model."""
    from ..errors import SolasError

    if args.sensor_model is None:
        given = [flag for flag, value in (("--exposure-ms", args.exposure_ms), ("--isp", args.isp)) if value is not None]
        if given:
            raise SolasError(f"{' and '.join(given)} go(es) with --sensor-model; give the sensor too")
        return None
    if args.exposure_ms is None:
        raise SolasError("--sensor-model needs --exposure-ms (the exposure time in ms)")
    from .camera import load_camera

    return load_camera(args.sensor_model, args.exposure_ms, args.isp, seed)
