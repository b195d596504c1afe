"""`solas-mi psf` (one PSF) and `solas-mi psf-grid` (PSFs over the field), as OpenEXR + PNG."""

from __future__ import annotations

import sys
from typing import Any

from ..errors import SolasError
from ..optics.commands import add_lens_argument
from ..optics.ghost_paths import DEFAULT_RAYS as DEFAULT_GHOST_RAYS
from ..options import floats
from ..outputs import add_png_option, check_target, data_and_preview, written_together
from ..progress import Progress
from .spec import PSF_OPTIONS, GridSpec

# what --field-deg takes: its help and its message (one value is a field on the y axis, as `lens info --fields`
# and a lens file's field_deg)
FIELD_FORM = "X,Y in degrees, or one value Y (x = 0)"
GHOST_PITCH_UM, GHOST_SIZE = 10.0, 512  # `ghosts`: its stray-light PSF's grid


def _field(text: str) -> tuple[float, float]:
    values = floats(text, "--field-deg")
    if len(values) == 1:
        values = [0.0, values[0]]
    if len(values) != 2:
        raise SolasError(f"--field-deg {text!r} must be {FIELD_FORM}")
    return values[0], values[1]


def _finish(command: str, result, data_file, png, note: str) -> None:
    """Each warning of `result` (a PSF or PSFGrid) once on stderr — stdout stays for results, and the
    warnings are in its metadata too — then its EXR and PNG, written together."""
    for text in result.meta["warnings"]:
        print(f"solas-mi {command}: warning: {text}", file=sys.stderr)
    if png is None:
        with written_together(data_file) as (tmp_data,):
            result.write(tmp_data)
        print(f"wrote {data_file}{note}")
        return
    with written_together(data_file, png) as (tmp_data, tmp_png):
        result.write(tmp_data)
        result.write_png(tmp_png)
    print(f"wrote {data_file} and {png}{note}")


def run_psf(args) -> int:
    from ..optics.commands import load_lens
    from .methods import psf

    data_file, png = data_and_preview(args.output, args.png)
    lens = load_lens(args)
    wavelengths = floats(args.wavelengths_nm, "--wavelengths-nm")
    weights = floats(args.weights, "--weights") if args.weights else None
    p = psf(lens, _field(args.field_deg), wavelengths, weights=weights, **GridSpec.given(args, PSF_OPTIONS))
    _finish("psf", p, data_file, png, "")
    return 0


def run_psf_grid(args) -> int:
    from ..budget import check_memory
    from ..optics.commands import load_lens
    from .depth import make_grid

    # the mosaic only when asked: a 32×32 grid's costs about 0.9 s (block means + a 2048² PNG)
    data_file, png = data_and_preview(args.output, args.mosaic or None)
    png = png if args.mosaic is not None else None
    lens = load_lens(args)
    spec = GridSpec.from_args(args)
    count = len(spec.wavelengths_nm or lens.wavelengths_nm) * spec.grid[0] * spec.grid[1] * len(spec.distances_m or [0])
    # the float32 PSFs, their mosaics and the PNG when written, and a batch of complex fields
    need = 3 * 4 * count * spec.size**2 + 64 * 64 * (spec.size + 1) ** 2
    check_memory(
        f"psf-grid of {count} PSFs of {spec.size}x{spec.size}", need, args.force, "fewer nodes or a smaller --size"
    )

    with Progress("psf-grid", count, "PSFs") as bar:  # nodes × wavelengths × distances, mirrored ones included
        g = make_grid(lens, spec, progress=bar)
    _finish("psf-grid", g, data_file, png, f" ({g.meta['seconds']:.1f} s)")
    return 0


def run_ghosts(args) -> int:
    from ..optics.commands import load_lens
    from . import stray_light, stray_psf
    from .base import check_grid

    data_file, png = data_and_preview(args.output, args.png)
    check_grid(args.pitch_um, args.size)  # before the work
    lens = load_lens(args)
    wavelengths = floats(args.wavelengths_nm, "--wavelengths-nm") if args.wavelengths_nm else None
    report = stray_light.ghosts(lens, _field(args.field_deg), wavelengths, rays=args.rays)
    print(report.table())
    data, centre, warnings = stray_psf.stray_psf(lens, report, args.pitch_um, args.size)
    for text in [*report.warnings, *warnings]:
        print(f"solas-mi ghosts: warning: {text}", file=sys.stderr)
    stray_psf.write(report, data, centre, args.pitch_um, data_file, png)
    print(f"wrote {data_file} and {png}")
    return 0


def run_ghost_grid(args) -> int:
    from ..budget import check_memory
    from ..optics import ghost_paths
    from ..optics.commands import load_lens
    from .ghost_nodes import ghost_grid, grid_options

    exr = check_target(args.output)
    json_path = check_target(args.json or exr.with_suffix(".json"))
    lens = load_lens(args)
    wavelengths = floats(args.wavelengths_nm, "--wavelengths-nm") if args.wavelengths_nm else None
    chosen = (args.radii, args.field_deg, wavelengths, args.rays, args.kernel, args.azimuths)
    options = grid_options(lens, *chosen)  # checked before the work
    nodes = options["radii"] * options["azimuths"]
    kernels = len(options["wavelengths_nm"]) * nodes * len(ghost_paths.paths(lens))
    check_memory(  # the float32 kernels, their mosaics in the file, and a node's work
        f"ghost-grid of {kernels} kernels of {args.kernel}x{args.kernel}", 3 * 4 * kernels * args.kernel**2 + (1 << 28),
        args.force, "fewer --radii or a smaller --kernel",
    )  # fmt: skip
    with Progress("ghost-grid", nodes, "nodes") as bar:
        grid = ghost_grid(lens, *chosen, progress=bar)
    grid.write(exr, json_path)
    print(f"wrote {exr} and {json_path} ({len(grid.paths)} ghosts on {nodes} nodes)")
    return 0


def _add_outputs(p) -> None:
    p.add_argument("-o", "--output", required=True, help="output OpenEXR file")
    add_png_option(p)


def register(sub: Any) -> None:
    """Add `psf` and `psf-grid`."""
    psf = sub.add_parser("psf", help="one PSF (Fraunhofer or geometric) as OpenEXR + PNG")
    add_lens_argument(psf)
    psf.add_argument("--field-deg", required=True, help=f"field angle: {FIELD_FORM}")
    psf.add_argument("--wavelengths-nm", required=True, help="one wavelength, or several for a polychromatic PSF")
    psf.add_argument("--weights", help="weights of the wavelengths (default: equal)")
    GridSpec.add_flags(psf, PSF_OPTIONS)
    _add_outputs(psf)
    psf.set_defaults(run=run_psf)

    ghost = sub.add_parser(
        "ghosts",
        help="every two-reflection ghost of a point source: the table, and the "
        "stray-light PSF (ghosts + direct image) as OpenEXR + log-scale PNG",
    )
    add_lens_argument(ghost)
    ghost.add_argument("--field-deg", required=True, help=f"field angle: {FIELD_FORM}")
    ghost.add_argument("--wavelengths-nm", help="wavelengths, summed with equal weights (default: the lens's)")
    ghost.add_argument(
        "--rays",
        type=int,
        default=DEFAULT_GHOST_RAYS,
        help="rays per side of the grid over the first surface's clear aperture, per path and wavelength",
    )
    ghost.add_argument("--pitch-um", type=float, default=GHOST_PITCH_UM, help="pixel pitch of the stray-light PSF (um)")
    ghost.add_argument("--size", type=int, default=GHOST_SIZE, help="pixels per side of the stray-light PSF")
    _add_outputs(ghost)
    ghost.set_defaults(run=run_ghosts)

    _register_ghost_grid(sub)
    grid = sub.add_parser(
        "psf-grid", help="PSFs on a field grid, one stack per wavelength, as OpenEXR (+ PNG mosaic with --mosaic)"
    )
    add_lens_argument(grid)
    GridSpec.add_flags(grid)
    grid.add_argument("--force", action="store_true", help="run even when the estimated memory exceeds what is free")
    grid.add_argument("-o", "--output", required=True, help="output OpenEXR file")
    grid.add_argument(
        "--mosaic",
        nargs="?",
        const="",
        metavar="PNG",
        help="also write the grid as a PNG mosaic for viewing, axes in field degrees (beside the EXR, "
        "of the same name, or at PNG); default: none (a 32x32 grid's takes about a second)",
    )
    grid.set_defaults(run=run_psf_grid)


def _register_ghost_grid(sub: Any) -> None:
    from .ghost_grid_file import DEFAULT_IRIS_AZIMUTHS, DEFAULT_KERNEL, DEFAULT_RADII

    p = sub.add_parser(
        "ghost-grid",
        help="every ghost on nodes along the field's radius (per node and wavelength: energy, centroid, kernel) "
        "as OpenEXR + JSON, for stray light over the image",
    )
    add_lens_argument(p)
    p.add_argument("--radii", type=int, default=DEFAULT_RADII, help="nodes along the field's radius, from the axis")
    p.add_argument(
        "--field-deg", type=float, help="the largest polar field angle (degrees; default the lens's field_deg)"
    )
    p.add_argument("--wavelengths-nm", help="wavelengths, a channel each (default: the lens's)")
    p.add_argument("--rays", type=int, default=DEFAULT_GHOST_RAYS, help="rays per side of each node's launch grid")
    p.add_argument("--kernel", type=int, default=DEFAULT_KERNEL, help="pixels per side of each ghost's kernel (odd)")
    p.add_argument(
        "--azimuths",
        type=int,
        help=f"an iris's nodes per blade sector (default {DEFAULT_IRIS_AZIMUTHS}; a round stop: 1, its ghosts turn)",
    )
    p.add_argument("--force", action="store_true", help="run even when the estimated memory exceeds what is free")
    p.add_argument("-o", "--output", required=True, help="output OpenEXR file")
    p.add_argument("--json", help="the metadata as JSON (default: beside the EXR, of the same name)")
    p.set_defaults(run=run_ghost_grid)
