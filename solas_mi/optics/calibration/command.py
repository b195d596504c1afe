"""`solas-mi lens calibrate`: a camera model fitted to a lens's chief-ray mapping over a sensor, written in
its ecosystem's file (one per wavelength: lateral colour as one calibration each), with its residual."""

from __future__ import annotations

import math
from pathlib import Path

from ...errors import SolasError
from .models import MODELS


def focus_mm(text: str | None) -> float | None:
    """--focus-distance: mm in front of surface 1, or inf; None: the lens file's own."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not value > 0:
        raise SolasError(f"--focus-distance {text!r} must be a positive distance in mm in front of surface 1, or inf")
    return value


def targets(output: str, wavelengths: list[float] | None) -> list[Path]:
    """The file of each wavelength: `output` itself for one, `<stem>_<λ>nm<suffix>` beside it for several."""
    out = Path(output)
    if wavelengths is None or len(wavelengths) == 1:
        return [out]
    if len(set(wavelengths)) != len(wavelengths):
        raise SolasError(f"--wavelength-nm {','.join(f'{w:g}' for w in wavelengths)}: each wavelength once")
    return [out.with_name(f"{out.stem}_{w:g}nm{out.suffix}") for w in wavelengths]


def report(cal, path: Path) -> str:
    m = cal.mapping
    circle = m["image_circle_radius_px"]
    lines = [
        f"wrote {path}: {cal.model} of lens {m['lens']} at {m['wavelength_nm']:g} nm, sensor "
        f"{m['sensor_px'][0]}x{m['sensor_px'][1]} px of {m['pitch_um']:g} um",
        f"  residual over {cal.pixels} imaged pixels: RMS {cal.rms_px:.3g} px, max {cal.max_px:.3g} px at pixel "
        f"({cal.max_at_px[0]:g}, {cal.max_at_px[1]:g}), {cal.max_at_deg:.4g} deg from the axis",
        f"  fitted: {', '.join(cal.fitted)}",
    ]
    lines += [f"  {n} = 0: {why}" for n, why in cal.fixed.items()]
    if circle is not None:
        lines.append(f"  image circle: radius {circle:.6g} px; pixels outside it left out")
    if "note" in cal.extra:
        lines.append(f"  note: {cal.extra['note']}")
    return "\n".join(lines)


def run_calibrate(args) -> int:
    from ...imageio import write_text
    from ...options import floats, parse_wxh
    from ...outputs import check_target, written_together
    from . import Sensor, calibrate
    from .files import check_suffix
    from .files import write_text as calibration_text

    rows, cols = parse_wxh(args.sensor, "--sensor")
    sensor = Sensor(cols, rows, args.pitch_um)
    waves = floats(args.wavelength_nm, "--wavelength-nm") if args.wavelength_nm is not None else None
    paths = targets(args.output, waves)
    suffix = check_suffix(args.model, args.output)
    lens = args.load_lens(args)
    for p in paths:
        check_target(p, [lens.source] if lens.source else [], "calibration file")
    cals = calibrate(lens, args.model, sensor, waves, focus_mm(args.focus_distance))
    texts = [calibration_text(c, suffix) for c in cals]  # every file made before any is written
    with written_together(*paths) as tmps:
        for tmp, text in zip(tmps, texts):
            write_text(tmp, text)
    for cal, path in zip(cals, paths):
        print(report(cal, path))
    return 0


def calibration_help() -> str:
    """What --calibration-model does, for every command that takes it (`add_calibration_option`,
    `convolution.spec.DegradeSpec`)."""
    return "the camera model whose fit to the lens the output's metadata records; see `solas-mi lens calibrate`"


def add_calibration_option(p) -> None:
    """--calibration-model of the commands whose outputs record their camera (`describe_camera`)."""
    p.add_argument(
        "--calibration-model",
        choices=MODELS.names(),
        default=MODELS.default,
        help=f"{calibration_help()} (default: {MODELS.default})",
    )


def register(lens_commands, add_lens_argument, load_lens) -> None:
    """Add `lens calibrate` to the `lens` subcommands (`optics.commands` gives its LENS argument and loader)."""
    p = lens_commands.add_parser(
        "calibrate",
        help="fit a camera model to the lens's real chief-ray mapping over a sensor and write it in "
        "the model's own file (OpenCV, OCamCalib, WoodScape, Kalibr)",
        description="Fits MODEL to where the lens's real chief rays land on every pixel of the sensor (pixels "
        "outside a fisheye's image circle left out) and reports the residual: RMS, maximum and where "
        "it lies. Pixel (0, 0) is the top-left pixel's centre; directions are in the camera frame x "
        "right, y down, z forward, from the lens's entrance pupil.",
    )
    add_lens_argument(p)
    p.add_argument("--model", required=True, choices=MODELS.names(), help=MODELS.help())
    p.add_argument(
        "--sensor",
        required=True,
        metavar="WxH",
        help="sensor size in pixels (columns x rows), centred on the lens's axis",
    )
    p.add_argument("--pitch-um", required=True, type=float, help="pixel pitch (um)")
    p.add_argument(
        "--wavelength-nm",
        metavar="NM[,NM...]",
        help="wavelength(s) in nm (default: the lens's primary); "
        "several: one calibration each (lateral colour), written as OUT's stem + _<nm>nm",
    )
    p.add_argument(
        "--focus-distance",
        metavar="MM",
        help="focus on an object this far in front of surface 1 (mm, or inf; default: the lens file's object distance)",
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="FILE",
        help="the calibration file, its format by MODEL and extension: "
        + "; ".join(f"{n}: {', '.join(e.extra['formats'])}" for n, e in MODELS.items()),
    )
    p.set_defaults(run=run_calibrate, load_lens=load_lens)
