"""Command line of the sensor: `camera`, an irradiance (or radiance) image → the sensor's RAW frame;
`sensors`, the shipped sensor presets.

NumPy, OpenEXR and the sensor modules are imported when the command runs."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from ..errors import SolasError

CLIPPED_WARNING = 0.01  # the fraction of a RAW's pixels at saturation past which a camera warns
# the camera's peak memory (bytes), measured as the peak RSS of `solas-mi camera` on 2000×1500 frames of 3
# and 10 channels against 8×8 ones: the modules (48 MB; 146 MB with the image processor's), the EXR read
# (float32 per value of every channel in the file, then the float64 R, G, B and their copy) and the
# sensor's chain per pixel (float64 R, G, B scaled, clipped, photons; mosaic, fixed pattern, noise:
# 102 B measured); the image processor's peak per pixel is its own (`isp.commands.DEVELOP_BYTES_PER_PIXEL`)
FIXED_BYTES = 150e6
READ_BYTES_PER_VALUE, READ_BYTES_PER_PIXEL = 4.0, 48.0
RAW_BYTES_PER_PIXEL = 110.0
# an HDR sensor's chain beyond one readout (traced with tracemalloc on 1000×500 frames: +15 B for two readouts,
# +25 B for four, +17 B for three exposures), rounded up: the merge's float64 estimate and weight, and each
# further readout's frame and electrons
MERGE_BYTES_PER_PIXEL, READOUT_BYTES_PER_PIXEL = 16.0, 8.0
# a scene in time (--flicker, --image-motion): two images of it (its static image and light, or one instant
# and its weighted share) and the rows' average (float64 R, G, B each)
TIMED_SCENE_BYTES_PER_PIXEL = 72.0


def read_input(path):
    """The R, G, B channels (H, W, 3, float64, finite) of an EXR file and its metadata; SolasError
    naming what is missing."""
    import numpy as np

    from ..imageio import check_finite, read_exr

    if Path(path).suffix.lower() != ".exr":
        raise SolasError(
            f"{path}: the sensor reads an OpenEXR image of linear irradiance (R, G, B), not a "
            f"{Path(path).suffix or 'suffix-less'} file; give the EXR of a render, render-image or "
            "degrade (a photograph: through a lens first, e.g. render-image LENS PHOTO -o OUT.exr)"
        )
    channels, meta = read_exr(path)
    missing = [c for c in "RGB" if c not in channels]
    if missing:
        raise SolasError(
            f"{path}: channels {', '.join(missing)} missing; the sensor needs R, G and B "
            f"(found {', '.join(sorted(channels))})"
        )
    image = check_finite(np.stack([channels[c] for c in "RGB"], axis=-1).astype(np.float64), str(path))
    return image, meta


def read_rgb(path):
    """The R, G, B channels (H, W, 3, float64) of an EXR file, finite (`read_input`)."""
    return read_input(path)[0]


def radiance_f_number(given: float | None, meta: dict, what: str) -> tuple[float | None, dict, str | None]:
    """The f-number an image is read through as radiance (None: it is irradiance), where it came from (for
    the RAW's metadata) and a notice: the user's `given`, else the image's own, the `f_number` its metadata
    states (a render through a lens writes its lens's: its values are radiance). A given value that differs
    from the image's own is named in the notice."""
    from .exposure import check_f_number

    own = meta.get("f_number") if isinstance(meta, dict) else None
    if given is not None:
        given = check_f_number(given, "--f-number")
        shown = f"f/{own:.4g}" if isinstance(own, (int, float)) and not isinstance(own, bool) else f"f_number {own!r}"
        notice = (
            (
                f"{what}: --f-number {given:g} differs from the image's own {shown} (its lens's, from its "
                "metadata); --f-number used"
            )
            if own is not None and own != given
            else None
        )
        return given, {"f_number": given, "f_number_source": "--f-number", "f_number_of_input": own}, notice
    if own is None:
        return None, {"f_number": None, "f_number_source": None}, None
    own = check_f_number(own, f"{what}: the f_number in its metadata")
    source = f"input metadata (lens {meta.get('lens', 'unnamed')})"
    notice = (
        f"{what}: read as radiance through the camera equation at f/{own:.4g}, its lens's f-number from its "
        "metadata (--f-number sets another)"
    )
    return own, {"f_number": own, "f_number_source": source}, notice


def clipping_warning(model, raw, exposure_ms: float, what: str) -> tuple[float, str | None]:
    """The fraction of the RAW's pixels at saturation (`SensorModel.saturated`), and a warning naming it and
    what to change where it passes CLIPPED_WARNING."""
    fraction = float(model.saturated(raw).mean()) if raw.size else 0.0
    if fraction <= CLIPPED_WARNING:
        return fraction, None
    return fraction, (
        f"{what}: {100 * fraction:.1f} % of the RAW's pixels are saturated (full well or white level) "
        f"at {exposure_ms:.4g} ms; give a shorter --exposure-ms or a smaller --scale, or --exposure-ms "
        "auto (an exposure chosen from the light)"
    )


def check_camera_memory(args: argparse.Namespace, develop_bytes_per_pixel: float = 0.0, readouts: int = 1) -> None:
    """Refuse a frame whose read, sensor chain (of `readouts` readouts) or image processor (its peak bytes per
    pixel, 0 without) cannot fit in the free memory (unless --force); announce a large one
    (`budget.check_memory`)."""
    from ..budget import check_memory
    from ..imageio import image_size

    rows, cols, channels = image_size(args.image)
    timed = bool(args.flicker or args.image_motion)
    need = FIXED_BYTES + frame_bytes(rows, cols, channels, develop_bytes_per_pixel, readouts, timed)
    check_memory(f"camera {cols}x{rows}", need, args.force, "a smaller image")


def frame_bytes(
    rows: int,
    cols: int,
    channels: int = 3,
    develop_bytes_per_pixel: float = 0.0,
    readouts: int = 1,
    timed: bool = False,
) -> float:
    """The camera's peak memory for a frame beyond its modules (bytes): the largest of the EXR read (of
    `channels` channels), the sensor's chain (of `readouts` readouts) and the image processor's (0: none),
    plus a scene in time's images (`timed`: a flickering box or the image's motion) and the sensor's fixed
    pattern, held from frame to frame (`readout.PATTERN_VALUES_PER_READOUT`)."""
    from .readout import PATTERN_VALUES_PER_READOUT

    read = READ_BYTES_PER_VALUE * channels + READ_BYTES_PER_PIXEL
    chain = RAW_BYTES_PER_PIXEL + (
        MERGE_BYTES_PER_PIXEL + READOUT_BYTES_PER_PIXEL * (readouts - 1) if readouts > 1 else 0.0
    )
    scene = TIMED_SCENE_BYTES_PER_PIXEL if timed else 0.0
    held = 8.0 * PATTERN_VALUES_PER_READOUT * readouts
    return rows * cols * (max(read, chain, develop_bytes_per_pixel) + scene + held)


def as_irradiance(
    image, meta: dict, what: str, scale: float = 1.0, f_number: float | None = None, transmission: float = 1.0
):
    """An input image (H, W, 3) with its metadata as image-plane irradiance in W/m², how it was read (for
    the RAW's metadata) and a notice (None: nothing to say): its R, G, B times `scale` (negative values
    read as no light, `exposure.negatives_as_no_light`), through the camera equation when it is radiance
    (`radiance_f_number`: `f_number`, or the render's own). The one rule of `camera` and a batch's camera."""
    import numpy as np

    from .exposure import image_irradiance, negatives_as_no_light

    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not 0 < scale < math.inf:
        raise SolasError(f"--scale {scale} must be > 0 and finite")
    with np.errstate(over="ignore"):
        scaled = image * scale
    if not np.all(np.isfinite(scaled)):
        raise SolasError(
            f"--scale {scale:g} times the image's largest value {np.abs(image).max():.3g} passes the "
            "largest float64 (1.8e308); give a smaller --scale"
        )
    image, negative = negatives_as_no_light(scaled, what)
    f_number, reading, notice = radiance_f_number(f_number, meta, what)
    reading.update(scale=scale, transmission=transmission, negative_values_taken_as_zero=negative)
    if f_number is None:
        if transmission != 1.0:
            raise SolasError(
                "--transmission applies with --f-number (or a render that states its f-number): to "
                "radiance; give --f-number too"
            )
        return image, reading, notice
    return image_irradiance(image, f_number, transmission), reading, notice


def camera_input(args: argparse.Namespace, model, exposure, develop_bytes_per_pixel: float):
    """The command's input (H, W, 3, float64) and its metadata, its memory checked first: an EXR image read
    (`read_input`), or a scene file rendered over the sensor's exposure windows (`scene_input.rendered_input`)."""
    from .capture import as_chain
    from .scene_input import is_scene, rendered_input

    readouts = len(as_chain(model).readouts)
    if not is_scene(args.image):
        check_camera_memory(args, develop_bytes_per_pixel, readouts)
        return read_input(args.image)
    exposure_s = exposure / 1e3 if isinstance(exposure, (int, float)) else None  # None: auto, refused there
    return rendered_input(
        args,
        as_chain(model).shutter,
        exposure_s,
        lambda rows, cols: FIXED_BYTES + frame_bytes(rows, cols, 3, develop_bytes_per_pixel, readouts),
    )


def raw_frame(args: argparse.Namespace, develop_bytes_per_pixel: float = 0.0):
    """The RAW frame (H, W, uint16 DN) of the command's image, its `SensorModel` and its metadata."""
    from .auto_exposure import exposure_seconds, parse_exposure
    from .capture import capture, check_frame, check_seed
    from .files import describe, load_sensor
    from .scene_input import check_scene_options, is_scene
    from .time_options import timed_scene

    model = load_sensor(args.sensor_model)
    exposure = parse_exposure(args.exposure_ms)
    check_seed(args.seed)
    check_frame(args.frame)
    check_scene_options(args)
    timed = timed_scene(args)
    image, meta_in = camera_input(args, model, exposure, develop_bytes_per_pixel)
    irradiance, reading, notice = as_irradiance(
        image, meta_in, str(args.image), args.scale, args.f_number, args.transmission
    )
    if notice:
        print(f"notice: {notice}", file=sys.stderr)
    seconds, chosen = exposure_seconds(exposure, model, irradiance)
    exposure_ms = exposure if not chosen else seconds * 1e3
    raw = capture(model, irradiance if timed is None else timed.of(irradiance), seconds, args.seed, args.frame)
    fraction, warning = clipping_warning(model, raw, exposure_ms, str(args.output))
    if warning:
        print(f"solas-mi camera: warning: {warning}", file=sys.stderr)
    meta = {
        "kind": "sensor RAW",
        "unit": "DN",
        "sensor_model": str(args.sensor_model),
        "sensor": describe(model),
        "seed": args.seed,
        "frame": args.frame,
        "exposure_ms": exposure_ms,
        **({"auto_exposure": chosen} if chosen else {}),
        **(timed.describe() if timed else {}),
        **reading,
        "input": str(args.image),
        **({"rendered": meta_in} if is_scene(args.image) else {}),
        "saturated_fraction": fraction,
    }
    return raw, model, meta


def report(args: argparse.Namespace, raw, model, meta: dict) -> None:
    auto = meta.get("auto_exposure")
    chosen = (
        (
            f", exposure {meta['exposure_ms']:.4g} ms (auto: the {auto['percentile']:g}th percentile at "
            f"{100 * auto['fraction']:g} % of saturation)"
        )
        if auto
        else ""
    )
    print(
        f"{args.output}: {raw.shape[1]}x{raw.shape[0]} RAW ({model.cfa}, {model.bit_depth} bit), "
        f"mean {raw.mean():.1f} DN, {int(model.saturated(raw).sum())} pixels saturated (full well or white level)"
        f"{chosen}"
    )


def run_camera(args: argparse.Namespace) -> int:
    """Write the RAW frame (one channel "RAW", DN) with the model, seed and exposure in the metadata."""
    from ..imageio import write_exr
    from ..outputs import data_and_preview

    data_and_preview(args.output, None, [args.image, args.sensor_model])  # OUT.exr, as with --isp
    raw, model, meta = raw_frame(args)
    write_exr(args.output, {"RAW": raw.astype("float32")}, meta)
    report(args, raw, model, meta)
    return 0


def run_sensors(args: argparse.Namespace) -> int:
    """List the presets: name, then the sensor and where its values come from (the file's first line);
    with --json, every preset's name, title and values."""
    from .files import PRESETS, describe, load_sensor, preset_names, preset_title

    if args.json:
        from .. import jsonio

        print(
            jsonio.dumps(
                [
                    {"name": name, "title": preset_title(name), "sensor": describe(load_sensor(name))}
                    for name in preset_names()
                ],
                indent=2,
            )
        )
        return 0
    for name in preset_names():
        print(f"{name:12s} {preset_title(name)}")
    print(f"(each file in {PRESETS} cites its sources; use a name with camera --sensor-model)")
    return 0


def add_exposure_option(p: Any, required: bool) -> None:
    """--exposure-ms: a time in ms, or auto[:P,F] (`auto_exposure`)."""
    p.add_argument(
        "--exposure-ms",
        required=required,
        metavar="MS|auto[:P,F]",
        help="exposure time in ms, or auto: chosen from the light so that the P-th percentile of the "
        "pixels sits at the fraction F of saturation (auto = auto:99,0.8), the choice in the metadata",
    )


def register(subparsers: Any) -> None:
    """Add the `camera` and `sensors` subcommands."""
    from ..render.mitsuba import SCENE_SUFFIXES
    from .scene_input import add_scene_options
    from .time_options import add_time_options

    p = subparsers.add_parser(
        "camera",
        help="sensor RAW of an irradiance image (EMVA 1288 noise model, CFA, ADC)",
        description="The RAW frame a sensor gives for an image-plane irradiance image (or a Mitsuba scene file "
        "rendered over the sensor's exposure windows: PWM-driven emitters, a moving camera): photons through the "
        "CFA's quantum efficiencies, shot/dark/read noise, PRNU/DSNU, full well, conversion gain, "
        "ADC; an HDR sensor's readouts (split pixels, dual conversion gain, multiple exposures) merged "
        "into one linear signal and companded. Written as one EXR channel RAW (DN) with the sensor's "
        "stages and seed in its metadata.",
    )
    p.add_argument(
        "image",
        help="EXR with R, G, B channels: irradiance in W/m² (times --scale), or radiance "
        "in W/m²/sr with --f-number (a render through a lens states its own f-number); or a Mitsuba scene "
        f"file ({', '.join('*' + s for s in SCENE_SUFFIXES)}) rendered with its own camera over the exposure's windows (--pwm-emitter, "
        "--camera-motion, --spp), its R, G, B read as the EXR's",
    )
    p.add_argument(
        "--sensor-model",
        required=True,
        metavar="PRESET|FILE.toml",
        help="a sensor preset's name (solas-mi sensors lists them) or a TOML file with a [sensor] table "
        "(an HDR sensor's naming its stages in tables of their own, e.g. imx490-hdr)",
    )
    add_exposure_option(p, required=True)
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="the sensor's seed: its fixed pattern (PRNU, DSNU) and, with --frame, its temporal noise (default 0)",
    )
    p.add_argument(
        "--frame",
        type=int,
        default=0,
        help="frame number: another frame of the same sensor (same seed: same fixed pattern, new "
        "temporal noise), e.g. for photon transfer or video (default 0)",
    )
    p.add_argument("--scale", type=float, default=1.0, help="W/m² (or W/m²/sr) per unit of the image (default 1)")
    p.add_argument(
        "--f-number",
        type=float,
        default=None,
        help="the image is radiance: image irradiance E = π T L / (4 N²) (default: the f-number a render "
        "through a lens states in its metadata, else none: the image is irradiance)",
    )
    p.add_argument("--transmission", type=float, default=1.0, help="lens transmission T of radiance (default 1)")
    add_time_options(p)
    add_scene_options(p)
    p.add_argument("--force", action="store_true", help="run even when the estimated memory exceeds what is free")
    p.add_argument("-o", "--output", required=True, metavar="OUT.exr", help="RAW frame to write")
    p.set_defaults(run=run_camera)
    add_sensors_command(subparsers)


def add_sensors_command(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "sensors",
        help="list the sensor presets (camera --sensor-model NAME)",
        description="The sensor presets shipped with solas-mi, from public data sheets; each "
        "preset's file cites its sources and names the values that are assumptions.",
    )
    p.add_argument("--json", action="store_true", help="as JSON: each preset's name, title and every value")
    p.set_defaults(run=run_sensors)
