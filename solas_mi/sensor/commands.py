"""Command line of the sensor: `camera`, an irradiance (or radiance) image → the sensor's RAW frame;
`sensors`, the shipped sensor presets.

NumPy, OpenEXR and the sensor modules are imported when the command runs."""
from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from ..errors import SolasError


def read_rgb(path):
    """The R, G, B channels (H, W, 3, float64) of an EXR file, finite; SolasError naming what is missing."""
    import numpy as np

    from ..imageio import check_finite, read_exr

    if Path(path).suffix.lower() != ".exr":
        raise SolasError(f"{path}: the sensor reads an OpenEXR image of linear irradiance (R, G, B), not a "
                         f"{Path(path).suffix or 'suffix-less'} file; give the EXR of a render, render-image or "
                         "degrade (a photograph: through a lens first, e.g. render-image LENS PHOTO -o OUT.exr)")
    channels, _ = read_exr(path)
    missing = [c for c in "RGB" if c not in channels]
    if missing:
        raise SolasError(f"{path}: channels {', '.join(missing)} missing; the sensor needs R, G and B "
                         f"(found {', '.join(sorted(channels))})")
    return check_finite(np.stack([channels[c] for c in "RGB"], axis=-1).astype(np.float64), str(path))


def _irradiance(args: argparse.Namespace):
    """The input image as image-plane irradiance (H, W, 3) in W/m²: its R, G, B channels times --scale
    (negative values read as no light, `exposure.negatives_as_no_light`, counted in `args.negative`),
    through the camera equation when --f-number is given (the image is then radiance, W/m²/sr)."""
    from .exposure import image_irradiance, negatives_as_no_light

    if not 0 < args.scale < math.inf:
        raise SolasError(f"--scale {args.scale} must be > 0 and finite")
    image, args.negative = negatives_as_no_light(read_rgb(args.image) * args.scale, str(args.image))
    if args.f_number is None:
        if args.transmission != 1.0:
            raise SolasError("--transmission applies with --f-number (the image is then radiance); give both")
        return image
    return image_irradiance(image, args.f_number, args.transmission)


def raw_frame(args: argparse.Namespace):
    """The RAW frame (H, W, uint16 DN) of the command's image, its `SensorModel` and its metadata."""
    from .capture import capture
    from .files import describe, load_sensor

    model = load_sensor(args.sensor_model)
    if not 0 < args.exposure_ms < math.inf:
        raise SolasError(f"--exposure-ms {args.exposure_ms} must be > 0 and finite")
    raw = capture(model, _irradiance(args), args.exposure_ms * 1e-3, args.seed)
    meta = {"kind": "sensor RAW", "unit": "DN", "sensor_model": str(args.sensor_model), "sensor": describe(model),
            "seed": args.seed,
            "exposure_ms": args.exposure_ms, "scale": args.scale, "f_number": args.f_number,
            "transmission": args.transmission, "input": str(args.image),
            "negative_values_taken_as_zero": args.negative}
    return raw, model, meta


def report(args: argparse.Namespace, raw, model) -> None:
    print(f"{args.output}: {raw.shape[1]}x{raw.shape[0]} RAW ({model.cfa}, {model.bit_depth} bit), "
          f"mean {raw.mean():.1f} DN, {int(model.saturated(raw).sum())} pixels saturated (full well or white level)")


def run_camera(args: argparse.Namespace) -> int:
    """Write the RAW frame (one channel "RAW", DN) with the model, seed and exposure in the metadata."""
    from ..imageio import write_exr
    from ..outputs import data_and_preview

    data_and_preview(args.output, None, [args.image, args.sensor_model])  # OUT.exr, as with --isp
    raw, model, meta = raw_frame(args)
    write_exr(args.output, {"RAW": raw.astype("float32")}, meta)
    report(args, raw, model)
    return 0


def run_sensors(args: argparse.Namespace) -> int:
    """List the presets: name, then the sensor and where its values come from (the file's first line)."""
    from .files import PRESETS, preset_names, preset_title

    for name in preset_names():
        print(f"{name:12s} {preset_title(name)}")
    print(f"(each file in {PRESETS} cites its sources; use a name with camera --sensor-model)")
    return 0


def register(subparsers: Any) -> None:
    """Add the `camera` and `sensors` subcommands."""
    p = subparsers.add_parser(
        "camera", help="sensor RAW of an irradiance image (EMVA 1288 noise model, CFA, ADC)",
        description="The RAW frame a sensor gives for an image-plane irradiance image: photons through the "
                    "CFA's quantum efficiencies, shot/dark/read noise, PRNU/DSNU, full well, conversion gain, "
                    "ADC. Written as one EXR channel RAW (DN) with the sensor model and seed in its metadata.")
    p.add_argument("image", help="EXR with R, G, B channels: irradiance in W/m² (times --scale), or radiance "
                                 "in W/m²/sr with --f-number")
    p.add_argument("--sensor-model", required=True, metavar="PRESET|FILE.toml",
                   help="a sensor preset's name (solas-mi sensors lists them) or a TOML file with a [sensor] table")
    p.add_argument("--exposure-ms", type=float, required=True, help="exposure time in ms")
    p.add_argument("--seed", type=int, default=0, help="seed of the noise and fixed pattern (default 0)")
    p.add_argument("--scale", type=float, default=1.0, help="W/m² (or W/m²/sr) per unit of the image (default 1)")
    p.add_argument("--f-number", type=float, default=None,
                   help="the image is radiance: image irradiance E = π T L / (4 N²) (default: none, the image is irradiance)")
    p.add_argument("--transmission", type=float, default=1.0, help="lens transmission T with --f-number (default 1)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.exr", help="RAW frame to write")
    p.set_defaults(run=run_camera)
    p = subparsers.add_parser("sensors", help="list the sensor presets (camera --sensor-model NAME)",
                              description="The sensor presets shipped with solas-mi, from public data sheets; each "
                                          "preset's file cites its sources and names the values that are assumptions.")
    p.set_defaults(run=run_sensors)
