"""Command line of the image processor: `--isp` on the sensor's `camera` command, which then writes the
developed 8-bit sRGB frame as a PNG beside the RAW EXR (OUT.exr → OUT.png), every stage named in the
EXR's metadata. The command is the sensor's (`sensor.commands`); this stage, later in the import order,
adds its option to it.

NumPy, OpenEXR and the processor's modules are imported when the command runs."""

from __future__ import annotations

import argparse
from typing import Any

# the camera's peak memory per pixel while it develops (bytes; `sensor.commands.check_camera_memory`):
# measured on 2000×1500 frames, 162 (bilinear), 167 (Malvar2004), 209 (Menon2007): the RAW, the signal's
# float64 copies, the demosaicer's planes and masks, the colour-corrected and encoded images
DEVELOP_BYTES_PER_PIXEL = 220.0


def run_camera(args: argparse.Namespace) -> int:
    """The sensor's RAW, and with --isp the developed frame beside it, written together."""
    from ..sensor import commands as sensor

    if args.isp is None:
        return sensor.run_camera(args)
    from ..outputs import data_and_preview
    from ..sensor.capture import as_chain
    from ..sensor.files import load_sensor
    from .camera import write_frame
    from .pipeline import check_sensor, develop, load_isp

    isp = load_isp(args.isp)
    check_sensor(isp, load_sensor(args.sensor_model))  # before the frame is taken
    data, png = data_and_preview(args.output, None, [args.image, args.sensor_model, args.isp])
    raw, model, meta = sensor.raw_frame(args, DEVELOP_BYTES_PER_PIXEL)
    frame, developed = develop(raw, model, isp, as_chain(model).defective_pixels(raw.shape, args.seed))
    write_frame(data, raw, frame, {**meta, **developed})
    sensor.report(args, raw, model, meta)
    print(f"{png}: developed 8-bit sRGB frame ({', '.join(developed['stages'])})")
    return 0


def stage_choices() -> str:
    """What the method fields of an [isp] table take (their registries), for help texts."""
    from . import demosaic, tone, white

    return (
        f"white_balance: {', '.join(white.named())} or a table of gains; demosaic: {', '.join(demosaic.METHODS)} "
        f"or none; tone: {', '.join(tone.CURVES)}"
    )


def register(subparsers: Any) -> None:
    """Add --isp to the sensor's `camera` command."""
    p = subparsers.choices["camera"]
    p.add_argument(
        "--isp",
        default=None,
        metavar="default|FILE.toml",
        help="develop the RAW through the image processor (black level, white balance, demosaicing, "
        f"colour correction, tone curve): 'default' or a TOML file with an [isp] table "
        f"({stage_choices()}); the 8-bit sRGB frame is written beside OUT.exr as OUT.png "
        "(default: RAW only)",
    )
    p.set_defaults(run=run_camera)


def add_camera_options(p: argparse.ArgumentParser, seed: bool, scenes: bool = False) -> None:
    """A batch's camera options: --sensor-model, --exposure-ms, --scale, --isp, --flicker, --image-motion (and
    --seed where `seed`; --pwm-emitter and --camera-motion where its items include `scenes` files)."""
    from ..sensor.commands import add_exposure_option
    from ..sensor.scene_input import add_timing_options
    from ..sensor.time_options import add_time_options

    g = p.add_argument_group(
        "the camera: each frame through a sensor and image processor (its values times --scale "
        "read as W/m² of image irradiance, or as radiance through the f-number a render states), "
        "its RAW written as <name>_raw.exr and, with --isp, the developed frame as <name>_raw.png"
    )
    g.add_argument(
        "--sensor-model",
        metavar="PRESET|FILE.toml",
        help="the sensor: a preset's name (solas-mi sensors lists them) or a TOML file with a [sensor] table",
    )
    add_exposure_option(g, required=False)
    g.add_argument(
        "--scale", type=float, help="W/m² (or W/m²/sr) per unit of each frame (with --sensor-model; default 1)"
    )
    g.add_argument(
        "--isp",
        metavar="default|FILE.toml",
        help=f"develop each RAW: 'default' or a TOML file with an [isp] table ({stage_choices()}; with --sensor-model)",
    )
    add_time_options(g)
    if scenes:
        add_timing_options(g, "with --sensor-model, a scene file's")
    if seed:
        g.add_argument(
            "--seed",
            type=int,
            default=0,
            help="the sensor's seed: its fixed pattern, and with each frame's name its noise (default 0)",
        )


def camera_from_args(args: argparse.Namespace, seed: int):
    """The `isp.camera.Camera` of the options, or None without --sensor-model."""
    from ..errors import SolasError

    options = (
        ("--exposure-ms", args.exposure_ms),
        ("--scale", args.scale),
        ("--isp", args.isp),
        ("--flicker", args.flicker),
        ("--image-motion", args.image_motion),
        ("--pwm-emitter", getattr(args, "pwm_emitter", None)),
        ("--camera-motion", getattr(args, "camera_motion", None)),
    )
    if args.sensor_model is None:
        given = [flag for flag, value in options if value is not None]
        if given:
            raise SolasError(f"{' and '.join(given)} go(es) with --sensor-model; give the sensor too")
        return None
    if args.exposure_ms is None:
        raise SolasError("--sensor-model needs --exposure-ms (the exposure time in ms, or auto)")
    from ..sensor.auto_exposure import parse_exposure
    from ..sensor.scene_input import scene_timing
    from ..sensor.time_options import timed_scene
    from .camera import load_camera

    return load_camera(
        args.sensor_model,
        parse_exposure(args.exposure_ms),
        args.isp,
        seed,
        1.0 if args.scale is None else args.scale,
        timed_scene(args),
        scene_timing(getattr(args, "pwm_emitter", None), getattr(args, "camera_motion", None)),
    )
