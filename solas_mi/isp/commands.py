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
    from ..imageio import write_exr, write_png
    from ..outputs import data_and_preview, written_together
    from .pipeline import develop, load_isp

    isp = load_isp(args.isp)
    data, png = data_and_preview(args.output, None, [args.image, args.sensor_model, args.isp])
    raw, model, meta = sensor.raw_frame(args)
    frame, developed = develop(raw, model, isp)
    meta.update(developed, developed_frame=png.name)
    with written_together(data, png) as (tmp_data, tmp_png):
        write_exr(tmp_data, {"RAW": raw.astype("float32")}, meta)
        write_png(tmp_png, frame / 255.0, encoded=True)
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
