"""`solas-mi crossval`, `solas-mi report error-vs-time` and `solas-mi check-stability`: the validation
package's command line.
The work is done by `crossval.crossval` and `error_vs_time.error_vs_time`; the options both take
come from `options.add_image_input_options`, after the LENS of `optics.commands.add_lens_argument`."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from .. import jsonio
from ..convolution.kernels import BOUNDARIES
from ..errors import SolasError
from ..optics.commands import add_lens_argument, load_lens
from ..options import add_image_input_options, parse_wxh, positive_ints
from ..outputs import output_folder
from ..psf.methods import METHODS as PSF_METHODS
from ..render.mitsuba import VARIANTS
from ..userfiles import read_text
from .crossval import DEFAULT_CASES, crossval
from .engines import Case, parse_blocks
from .error_vs_time import DEFAULT_INTERP_GRIDS, DEFAULT_PATCH_GRIDS, DEFAULT_RENDER_SPP, error_vs_time
from .inputs import load_input
from .tables import crossval_markdown, error_vs_time_markdown

FISHEYE_MARGIN_DEG = 5.0  # the environment reaches this far beyond a fisheye's field by default


def block_grids(text: str, what: str) -> tuple[tuple[int, int], ...]:
    """Comma-separated COLSxROWS → ((columns, rows), ...)."""
    return tuple(parse_blocks(item, what) for item in text.split(",") if item.strip())


def case_list(text: str | None) -> tuple[str, ...]:
    """The cases `--cases` selects (None: DEFAULT_CASES), each checked (`engines.Case.parse`); SolasError
    for a selection of no case or an empty entry (an empty selection ran every case)."""
    if text is None:
        return DEFAULT_CASES
    cases = tuple(item.strip() for item in text.split(","))
    if not all(cases):
        raise SolasError(f"--cases {text!r} {'selects no case' if not any(cases) else 'has an empty entry'}; give "
                         f"comma-separated METHOD:PSF:COLSxROWS (default: {','.join(DEFAULT_CASES)})")
    return tuple(Case.parse(case).name for case in cases)


def _grids_text(grids) -> str:
    return ",".join(f"{cols}x{rows}" for cols, rows in grids)


def _lens_and_image(args: argparse.Namespace):
    output_folder(args.output)
    lens = load_lens(args)
    sensor = parse_wxh(args.sensor, "--sensor") if args.sensor else None
    return lens, load_input(args.image, sensor, args.scale, args.linear)


def _say(text: str) -> None:
    """A step of a long run, on stderr: stdout holds the results (the tables), as for every command."""
    print(text, file=sys.stderr, flush=True)


def run_crossval(args: argparse.Namespace) -> int:
    lens = load_lens(args)
    if not lens.field_type.pinhole:
        return _crossval_fisheye(args, lens)
    given = [name for name, value in (("--size", args.size), ("--pitch-um", args.pitch_um), ("--grid", args.grid))
             if value is not None] + ["--defocus-mm"] * (args.defocus_mm != 0.0)
    if given:
        raise SolasError(f"{', '.join(given)}: only for a lens of polar fields (a fisheye); {lens.name} has tangent "
                         "fields: give its sensor with --sensor or --scale and its grids with --cases")
    cases = case_list(args.cases)
    lens, image = _lens_and_image(args)
    res = crossval(lens, image, args.output, 1024 if args.spp is None else args.spp, args.seeds, cases, args.fov_deg, args.boundary,
                   args.variant, reuse=args.reuse_reference, log=_say)
    print(crossval_markdown(res.rows))
    print(f"wrote {args.output}/table.md, table.csv, crossval.json, reference.exr and per case: .exr, _error.exr, "
          "_error.png")
    return 0


def _crossval_fisheye(args: argparse.Namespace, lens) -> int:
    """crossval of a lens of polar fields: the input is an equidistant environment (`validation.fisheye`)."""
    from .fisheye import crossval_fisheye, defocused, fisheye_markdown

    given = [name for name, value in (("--sensor", args.sensor), ("--scale", args.scale), ("--cases", args.cases),
                                      ("--variant", args.variant)) if value is not None]
    given += ["--reuse-reference"] * args.reuse_reference + ["--seeds"] * (args.seeds != 2) + \
        ["--boundary"] * (args.boundary != "edge")
    if given:
        raise SolasError(f"{', '.join(given)}: not for a lens of polar fields ({lens.name}); its cross-validation "
                         "takes --size, --pitch-um, --grid, --fov-deg, --spp and --linear")
    fov = lens.field_deg + FISHEYE_MARGIN_DEG if args.fov_deg is None else args.fov_deg
    if not 0 < fov < 180:
        raise SolasError(f"--fov-deg {fov:g} must lie in (0, 180): half the width of the equidistant environment")
    size = 64 if args.size is None else args.size
    if size < 8:
        raise SolasError(f"--size {size} must be at least 8 (pixels per side of the square sensor)")
    if args.pitch_um is not None and not args.pitch_um > 0:
        raise SolasError(f"--pitch-um {args.pitch_um:g} must be positive (um)")
    grid = parse_wxh(args.grid, "--grid", minimum=2) if args.grid else (5, 5)
    if args.defocus_mm:
        defocused(lens, args.defocus_mm)  # checked before anything is written
    output_folder(args.output)
    env = load_input(args.image, linear=args.linear).mean(axis=-1)
    spp = 256 if args.spp is None else args.spp
    crossval_fisheye(lens, env, args.output, fov, size, args.pitch_um, grid, spp, args.defocus_mm, log=_say)
    print(fisheye_markdown(jsonio.loads(read_text(Path(args.output) / "crossval.json", "record"))))
    print(f"wrote {args.output}/table.md, crossval.json, direct.exr, convolved.exr, ideal.exr, error.exr, error.png")
    return 0


def run_error_vs_time(args: argparse.Namespace) -> int:
    lens, image = _lens_and_image(args)
    render_spp = DEFAULT_RENDER_SPP if args.spp is None else positive_ints(args.spp, "--spp")
    interp = DEFAULT_INTERP_GRIDS if args.interp_grids is None else block_grids(args.interp_grids, "--interp-grids")
    patch = DEFAULT_PATCH_GRIDS if args.patch_grids is None else block_grids(args.patch_grids, "--patch-grids")
    rows = error_vs_time(lens, image, args.output, args.ref_spp, args.seeds, render_spp, interp, patch, args.psf,
                         args.fov_deg, args.boundary, args.repeats, args.variant, log=_say)
    print(error_vs_time_markdown(rows))
    print(f"wrote {args.output}/table.md, table.csv, error_vs_time.png, report.json")
    return 0


def run_check_stability(args: argparse.Namespace) -> int:
    from .stability import check_stability, markdown

    lens = load_lens(args)
    cases = check_stability(lens, progress=lambda name: print(f"check-stability: {name}", file=sys.stderr, flush=True))
    if args.json:
        print(jsonio.dumps({"lens": lens.name, "lens_hash": lens.hash, "passed": all(c.passed for c in cases),
                          "cases": [c.to_dict() for c in cases]}, indent=1))
    else:
        print(markdown(lens, cases))
    failed = [c.name for c in cases if not c.passed]
    if failed:
        print(f"solas-mi check-stability: {len(failed)} case(s) failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


def _add_image_inputs(p) -> None:
    """LENS, then the options of a command that degrades an image both ways (`options.add_image_input_options`)."""
    add_lens_argument(p)
    add_image_input_options(p, BOUNDARIES, VARIANTS)


def register(sub: Any) -> None:
    """Add the `crossval`, `report` (`report error-vs-time`) and `check-stability` subcommands."""
    p = sub.add_parser(
        "crossval", help="cross-validate the PSF-grid convolution against the direct render",
        description="Degrade one image by the direct spectral render (the reference: lines response, no Fresnel, "
                    "several seeds so that its noise is known) and by each convolution case (convolution method × "
                    "PSF method × grid), in the same units; write the images, per-pixel error "
                    "maps and a table of relative RMSE (whole image and centre/middle/edge annuli), PSNR, SSIM "
                    "and run times (PSF grid and convolution apart).")
    _add_image_inputs(p)
    p.add_argument("--spp", type=int, help="reference samples per pixel, all seeds together (default 1024; "
                                            "1280x960 takes ~13 min on 2 cores); a fisheye: per seed (default 256)")
    fisheye = p.add_argument_group(
        "a lens of polar fields (a fisheye)", "IMAGE is then an equidistant environment spanning ±--fov-deg across "
        "its width (default: the lens's field + 5 deg), rendered through the lens onto a square sensor and, as its "
        "ideal sensor image, degraded by the lens's sensor-space PSF grid")
    fisheye.add_argument("--size", type=int, help="sensor pixels per side (default 64)")
    fisheye.add_argument("--pitch-um", type=float, help="pixel pitch in um (default: the sensor's corners reach "
                                                        "the lens's field)")
    fisheye.add_argument("--grid", help="PSF grid on the sensor, COLSxROWS (default 5x5)")
    fisheye.add_argument("--defocus-mm", type=float, default=0.0,
                         help="move the film this far behind the image plane in both engines (mm, default 0): in "
                              "focus the PSFs are far below a pixel; a few mm spread them over pixels")
    p.add_argument("--cases", help="comma-separated METHOD:PSF:COLSxROWS (default: "
                                   + ",".join(DEFAULT_CASES) + ")")
    p.add_argument("--reuse-reference", action="store_true",
                   help="reuse DIR/reference.exr when it was rendered with the same lens, size, field, boundary, "
                        "spp and seeds (e.g. to add cases without rendering again)")
    p.set_defaults(run=run_crossval)

    report = sub.add_parser("report", help="reports: error against run time").add_subparsers(
        dest="report_command", metavar="COMMAND", required=True)
    p = report.add_parser(
        "error-vs-time", help="error of the patch and the interp convolution and of the direct render against run time",
        description="Relative RMSE against a converged direct render (noise removed) and run time of the paper's "
                    "patch convolution, the interp convolution on grids of increasing size and the direct render "
                    "at increasing spp; writes table.md, table.csv, error_vs_time.png (log x) and report.json.")
    _add_image_inputs(p)
    p.add_argument("--ref-spp", type=int, default=1536, help="reference spp, all seeds together (default 1536)")
    p.add_argument("--spp", help="render spp to time, comma-separated (default "
                                 + ",".join(map(str, DEFAULT_RENDER_SPP)) + ")")
    p.add_argument("--interp-grids", help="interp grids COLSxROWS, comma-separated (default "
                                          + _grids_text(DEFAULT_INTERP_GRIDS) + ")")
    p.add_argument("--patch-grids", help="patch grids COLSxROWS, comma-separated (default "
                                         + _grids_text(DEFAULT_PATCH_GRIDS) + ")")
    p.add_argument("--psf", choices=list(PSF_METHODS), default="geometric",
                   help="PSF kind (default geometric: the render is a ray render, without diffraction)")
    p.add_argument("--repeats", type=int, default=3, help="convolution runs to take the median time of")
    p.set_defaults(run=run_error_vs_time)

    p = sub.add_parser(
        "check-stability", help="stiff and extreme cases of a lens: accurate, or a warning, never silently wrong",
        description="Run the stability cases for LENS (pupil sampling, window energy, wave vs ray transmission, "
                    "centring, chief rays, fields beyond the design, object distances 100 mm to 1e12 mm, the "
                    "glasses' wavelength limits, near-flat and monocentric surfaces, float64 OPD, the render's "
                    "exit-pupil bound) and print a table: case, expected, observed, verdict. Exit status 1 when "
                    "any case fails.")
    add_lens_argument(p)
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    p.set_defaults(run=run_check_stability)
