"""Command line of the sharpness metrics: `sfr`, `ss-sfr` and `sfr-target`.

The metric modules (NumPy, SciPy, scikit-image) are imported when a command runs, so that building
the parser costs the other commands nothing; they validate --mode, --annuli and --contrast.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import jsonio
from ..errors import SolasError
from ..options import parse_wxh

if TYPE_CHECKING:
    from .nssfr import NsSfrReport

CHANNELS = {"R": 0, "G": 1, "B": 2}


def _fmt(value: float | None, digits: int = 4) -> str:
    return "—" if value is None else f"{value:.{digits}f}"


def _full_scale(args: argparse.Namespace) -> float | None:
    """Saturation level: --full-scale, else 1 for integer formats and none for EXR."""
    if args.full_scale is not None:
        if not args.full_scale > 0:
            raise SolasError(f"--full-scale {args.full_scale} must be > 0")
        return args.full_scale
    return None if Path(args.image).suffix.lower() == ".exr" else 1.0


def _image_parser(subparsers: Any, name: str, help_: str, description: str) -> argparse.ArgumentParser:
    """Subcommand parser whose first argument is the image to measure."""
    p = subparsers.add_parser(name, help=help_, description=description)
    p.add_argument("image", help="PNG/JPEG/TIFF (sRGB, decoded unless --linear) or EXR (linear)")
    return p


def _add_input_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--mode", default="2023",
                   help="2023 (default): 5th-order edge fit, Tukey window (sfrmat5); 2017: linear fit, Hamming")
    p.add_argument("--linear", action="store_true",
                   help="PNG/JPEG/TIFF values are already linear: do not decode sRGB")
    p.add_argument("--full-scale", type=float, default=None,
                   help="saturation level of the linear values (default 1; none for EXR)")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")


def run_sfr(args: argparse.Namespace) -> int:
    """e-SFR of the given ROIs, or of every edge found in a slanted-edge/square chart."""
    from ..imageio import read_image
    from .esfr import check_mode, esfr
    from .nssfr import CHART_MARGINS, find_edge_rois
    from .roi import crop, is_grey, luminance, parse_roi

    check_mode(args.mode)
    image = read_image(args.image, linearize=not args.linear)
    if args.channel is not None and is_grey(image):
        raise SolasError(f"--channel {args.channel}: {args.image} is a grey image (one channel), it has no colour "
                         "channels; measure it without --channel")
    full_scale = _full_scale(args)
    if args.roi:
        rois = [parse_roi(text) for text in args.roi]
    else:
        rois = find_edge_rois(luminance(image), margins=CHART_MARGINS, max_rows=None)
    channel = None if args.channel is None else CHANNELS[args.channel]
    results = [(roi, esfr(crop(image, roi), mode=args.mode, full_scale=full_scale, channel=channel))
               for roi in rois]
    if args.json:
        print(jsonio.dumps({
            "image": args.image, "mode": args.mode, "rois_from": "user" if args.roi else "auto",
            "results": [{"roi": list(roi), **res.to_dict()} for roi, res in results],
        }, indent=1))
    elif not results:
        print(f"{args.image}: no slanted edge found; give ROIs with --roi x,y,w,h")
    else:
        print(f"{args.image}: e-SFR ({args.mode} mode), frequencies in cy/px along the edge normal")
        print("| ROI x,y,w,h | edge | angle (°) | MTF50 | MTF10 | contrast | status |")
        print("|---|---|---|---|---|---|---|")
        for roi, res in results:
            status = "ok" if res.valid else f"invalid: {res.reason}"
            if res.valid and res.mtf50 is None:
                status = "MTF50 not found"
            print(f"| {','.join(map(str, roi))} | {res.orientation} | {_fmt(res.angle_deg, 2)} | "
                  f"{_fmt(res.mtf50)} | {_fmt(res.mtf10)} | {_fmt(res.contrast, 2)} | {status} |")
        for roi, res in results:
            for w in res.warnings:
                print(f"warning (ROI {','.join(map(str, roi))}): {w}")
    if not any(res.valid for _, res in results):
        print(f"solas-mi sfr: no valid edge measured in {args.image} (exit status 1)", file=sys.stderr)
        return 1
    return 0


def _annulus_table(report: NsSfrReport) -> list[str]:
    """Markdown table of the per-annulus MTF50 statistics (cy/px)."""
    head = "| annulus | r/R | count | mean MTF50 | median MTF50 | sharpest 10 % |"
    rule = "|---|---|---|---|---|---|"
    if report.after is not None:
        head += " mean MTF50 compared | mean change |"
        rule += "---|---|"
    lines = [head, rule]
    changes = report.mean_change() if report.after is not None else [None] * len(report.before)
    after = report.after or [None] * len(report.before)
    for s, a, c in zip(report.before, after, changes):
        row = (f"| {s.name} | {s.r_inner:.2f}–{s.r_outer:.2f} | {s.count} | {_fmt(s.mean_mtf50)} | "
               f"{_fmt(s.median_mtf50)} | {_fmt(s.sharpest10_mtf50)} |")
        if a is not None:
            row += f" {_fmt(a.mean_mtf50)} | {'—' if c is None else f'{c:+.4f}'} |"
        lines.append(row)
    return lines


def run_ss_sfr(args: argparse.Namespace) -> int:
    """Natural-scene SFR per annulus, optionally against a degraded image on the same ROIs."""
    from ..imageio import read_image
    from ..outputs import check_target
    from .nssfr import natural_scene_sfr, plot_report

    if args.plot:
        if Path(args.plot).suffix.lower() != ".png":
            raise SolasError(f"--plot {args.plot!r} must end in .png")
        check_target(args.plot, [args.image, args.compare], "plot")
    image = read_image(args.image, linearize=not args.linear)
    other = read_image(args.compare, linearize=not args.linear) if args.compare else None
    report = natural_scene_sfr(image, compare=other, annuli=args.annuli, mode=args.mode,
                               contrast=args.contrast, full_scale=_full_scale(args))
    if args.plot:
        plot_report(report, image, args.plot)
    if args.json:
        print(jsonio.dumps({"image": args.image, "compare": args.compare, **report.to_dict()}, indent=1))
    else:
        what = f"{args.image} vs {args.compare}" if args.compare else args.image
        print(f"{what}: natural-scene SFR, {len(report.rois)} edge ROIs, MTF50 in cy/px "
              f"({args.annuli} annuli, R = {report.radius_px:.1f} px)")
        print("\n".join(_annulus_table(report)))
        if report.rejected:
            print("rejected: " + ", ".join(f"{k}: {v}" for k, v in sorted(report.rejected.items())))
        if args.plot:
            print(f"plot written to {args.plot}")
    if not report.rois:
        print(f"solas-mi ss-sfr: no edge passed the filters in {args.image} (exit status 1)", file=sys.stderr)
        return 1
    return 0


def run_sfr_target(args: argparse.Namespace) -> int:
    """Write a synthetic slanted-edge (or slanted-square) target with a known MTF."""
    from ..imageio import write_exr, write_png
    from ..outputs import check_target
    from .targets import Square, analytic_mtf50, slanted_edge, slanted_squares

    out = Path(args.output)
    if out.suffix.lower() not in (".png", ".exr"):
        raise SolasError(f"output {args.output!r} must end in .png (8-bit sRGB) or .exr (linear float)")
    check_target(out)
    if not 0 <= args.sigma_px < math.inf:
        raise SolasError(f"--sigma-px {args.sigma_px} must be a finite number ≥ 0")
    if not math.isfinite(args.angle_deg):
        raise SolasError(f"--angle-deg {args.angle_deg} must be a finite angle (degrees)")
    if not (0 <= args.low <= 1 and 0 <= args.high <= 1):
        raise SolasError(f"--low {args.low} and --high {args.high} must lie in [0, 1] (linear levels)")
    if args.low == args.high:
        raise SolasError(f"--low and --high are both {args.low}: an edge needs two different levels")
    rows, cols = parse_wxh(args.size, "--size", 16)
    if args.shape == "edge":
        img = slanted_edge((rows, cols), args.angle_deg, args.sigma_px, low=args.low, high=args.high,
                           noise=args.noise, seed=args.seed)
    else:
        square = Square((cols - 1) / 2, (rows - 1) / 2, 0.5 * min(rows, cols), args.angle_deg, args.sigma_px,
                        args.low)
        img = slanted_squares((rows, cols), [square], background=args.high,
                              noise=args.noise * abs(args.high - args.low), seed=args.seed)
    mtf50 = analytic_mtf50(args.sigma_px, args.angle_deg)
    meta = {"target": args.shape, "angle_deg": args.angle_deg, "sigma_px": args.sigma_px,
            "low": args.low, "high": args.high, "noise": args.noise, "analytic_mtf50_cy_px": mtf50}
    if out.suffix.lower() == ".exr":
        write_exr(out, {"Y": img}, meta)
    else:
        write_png(out, img, encoded=args.linear)
    encoding = "linear float" if out.suffix.lower() == ".exr" else ("8-bit linear" if args.linear else "8-bit sRGB")
    print(f"wrote {out} ({cols}×{rows} px, {encoding}): slanted {args.shape} at {args.angle_deg}°, "
          f"Gaussian PSF σ = {args.sigma_px} px; analytic MTF50 = {mtf50:.6f} cy/px")
    return 0


def register(subparsers: Any) -> None:
    """Add the `sfr`, `ss-sfr` and `sfr-target` subcommands."""
    p = _image_parser(
        subparsers, "sfr", "ISO 12233 e-SFR, MTF50 and MTF10 of slanted edges",
        "e-SFR of slanted edges (ISO 12233:2023 / 2017). Without --roi, every edge of a "
        "slanted-edge or slanted-square chart is found and measured. Exit 1 if no ROI could be measured.")
    p.add_argument("--roi", action="append", metavar="x,y,w,h",
                   help="ROI in px (top-left corner, width, height) holding one edge; repeatable")
    p.add_argument("--channel", choices=tuple(CHANNELS), default=None,
                   help="measure one colour channel instead of luminance")
    _add_input_options(p)
    p.set_defaults(run=run_sfr)

    p = _image_parser(
        subparsers, "ss-sfr", "natural-scene SFR: MTF50 of edges found in an image, per radial annulus",
        "Natural-scene SFR: slanted edges found in the image, e-SFR of each, MTF50 statistics per "
        "annulus. --compare measures the same ROIs in a second image (e.g. the lens-degraded one). "
        "Exit 1 if no edge could be measured.")
    p.add_argument("--compare", metavar="DEGRADED", help="second image of the same scene and size")
    p.add_argument("--plot", metavar="OUT.png", help="write annuli/ROIs and mean SFR curves")
    p.add_argument("--annuli", default="automotive",
                   help="automotive (default): 0.24/0.6/1.0 of the centre-to-corner radius; "
                        "equal-area: 3 annuli of equal area")
    p.add_argument("--contrast", default="automotive",
                   help="accepted edge contrast band: automotive (default, 0.1–0.9) or chart (0.55–0.65)")
    _add_input_options(p)
    p.set_defaults(run=run_ss_sfr)

    p = subparsers.add_parser(
        "sfr-target", help="write a synthetic slanted-edge target with a known MTF",
        description="Slanted edge (or square) blurred by a Gaussian PSF and integrated over 100 % "
                    "fill-factor pixels; prints the analytic MTF50 to check a measurement setup.")
    p.add_argument("-o", "--output", required=True, help="OUT.png (8-bit sRGB) or OUT.exr (linear float)")
    p.add_argument("--angle-deg", type=float, default=5.0, help="edge tilt from vertical, degrees")
    p.add_argument("--sigma-px", type=float, default=1.0, help="Gaussian PSF sigma, px")
    p.add_argument("--size", default="128x128", help="WxH in px")
    p.add_argument("--shape", choices=("edge", "square"), default="edge",
                   help="one slanted edge (--low left or below it, --high beyond), or a --low square at the centre, its side "
                        "half the image's shorter side, turned by --angle-deg, on --high (four edges)")
    p.add_argument("--low", type=float, default=0.2, help="dark linear level")
    p.add_argument("--high", type=float, default=0.8, help="bright linear level")
    p.add_argument("--noise", type=float, default=0.0, help="Gaussian noise sd, fraction of the step")
    p.add_argument("--seed", type=int, default=None, help="noise seed")
    p.add_argument("--linear", action="store_true", help="PNG: store linear values (no sRGB encoding)")
    p.set_defaults(run=run_sfr_target)
