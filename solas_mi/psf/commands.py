"""`solas-mi psf` (one PSF) and `solas-mi psf-grid` (PSFs over the field), as OpenEXR + PNG."""
from __future__ import annotations

import sys
from typing import Any

from ..errors import SolasError
from ..options import add_lens_argument, floats, parse_wxh
from ..outputs import data_and_preview, written_together
from .base import (
    DEFAULT_GEOMETRIC_RAYS,
    DEFAULT_PITCH_UM,
    DEFAULT_PUPIL_SAMPLES,
    DEFAULT_SIZE,
    NORMALIZATIONS,
    WINDOW_ENERGY_LIMIT,
)
from .methods import DEFAULT_METHOD, METHODS


def _field(text: str) -> tuple[float, float]:
    values = floats(text, "--field-deg")
    if len(values) == 1:
        values = [0.0, values[0]]
    if len(values) != 2:
        raise SolasError(f"--field-deg {text!r} must be X,Y in degrees (or one value, taken as Y)")
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
    from ..optics.lens import Lens
    from .methods import psf

    data_file, png = data_and_preview(args.output, args.png)
    lens = Lens.load(args.lens)
    wavelengths = floats(args.wavelength_nm, "--wavelength-nm")
    weights = floats(args.weights, "--weights") if args.weights else None
    p = psf(lens, _field(args.field_deg), wavelengths, weights=weights, pitch_um=args.pitch_um, size=args.size,
            method=args.method, normalization=args.normalize, pupil_samples=args.pupil_samples, rays=args.rays,
            auto_window=args.auto_window)
    _finish("psf", p, data_file, png, "")
    return 0


def run_psf_grid(args) -> int:
    from ..budget import check_memory
    from ..optics.lens import Lens
    from .grid import psf_grid

    # the mosaic preview only when asked: a 32×32 grid's costs about 0.9 s (block means + a 2048² PNG)
    data_file, png = data_and_preview(args.output, args.png or None)
    png = png if args.png is not None else None
    lens = Lens.load(args.lens)
    grid = parse_wxh(args.grid, "--grid")
    wavelengths = floats(args.wavelengths, "--wavelengths") if args.wavelengths else None
    count = (len(wavelengths) if wavelengths else len(lens.wavelengths_nm)) * grid[0] * grid[1]
    # the float32 PSFs, their mosaics and the PNG when written, and a batch of complex fields
    need = 3 * 4 * count * args.size ** 2 + 64 * 64 * (args.size + 1) ** 2
    check_memory(f"psf-grid of {count} PSFs of {args.size}x{args.size}", need, args.force,
                 "fewer nodes or a smaller --size")
    rng = floats(args.field_range_deg, "--field-range-deg") if args.field_range_deg else None
    if rng is not None and len(rng) not in (1, 2):
        raise SolasError(f"--field-range-deg {args.field_range_deg!r} must be one value or X,Y")

    def progress(done: int, total: int) -> None:
        print(f"\r{done}/{total} PSFs", end="", file=sys.stderr, flush=True)

    g = psf_grid(lens, grid=grid, wavelengths_nm=wavelengths,
                 field_range_deg=None if rng is None else (rng[0], rng[-1]), pitch_um=args.pitch_um,
                 size=args.size, method=args.method, normalization=args.normalize,
                 pupil_samples=args.pupil_samples, rays=args.rays, field_sampling=args.field_sampling,
                 progress=progress, auto_window=args.auto_window, layout=args.layout,
                 sensor_mm=parse_sensor_mm(args.sensor_mm))
    print(file=sys.stderr)
    _finish("psf-grid", g, data_file, png, f" ({g.meta['seconds']:.1f} s)")
    return 0


def parse_sensor_mm(text: str | None) -> tuple[float, float] | None:
    """--sensor-mm "23.6x15.8" (mm) → (width, height); None when absent."""
    if text is None:
        return None
    parts = str(text).lower().split("x")
    try:
        if len(parts) != 2:
            raise ValueError
        return float(parts[0]), float(parts[1])
    except ValueError:
        raise SolasError(f"--sensor-mm {text!r} must look like 23.6x15.8 (width x height in mm)") from None


def add_sampling_options(p, method_flag: str = "--method") -> None:
    """How PSFs are computed and sampled: pitch, size, method (`method_flag`: a command whose --method
    means something else names it --psf-method), normalisation, pupil samples, rays, auto window."""
    p.add_argument("--pitch-um", type=float, default=DEFAULT_PITCH_UM, help="image-plane pixel pitch (µm)")
    p.add_argument("--size", type=int, default=DEFAULT_SIZE, help="PSF width and height (pixels)")
    p.add_argument(method_flag, choices=list(METHODS), default=DEFAULT_METHOD, help="PSF method")
    p.add_argument("--normalize", choices=NORMALIZATIONS, default="sum")
    p.add_argument("--pupil-samples", type=int, default=DEFAULT_PUPIL_SAMPLES, help="Fraunhofer pupil grid N×N")
    p.add_argument("--rays", type=int, default=DEFAULT_GEOMETRIC_RAYS, help="geometric: rays×rays per PSF")
    p.add_argument("--auto-window", action="store_true",
                   help=f"double --size until each window holds {100 * WINDOW_ENERGY_LIMIT:g} %% of the light")


def add_grid_options(p, method_flag: str = "--method") -> None:
    """The options that define a PSF grid (`psf-grid`, and batch jobs that compute one)."""
    from .grid import FIELD_SAMPLINGS, LAYOUTS

    p.add_argument("--grid", default="8x8", help="columns x rows of field nodes")
    p.add_argument("--wavelengths", help="nm, comma-separated (default: the lens file's)")
    p.add_argument("--field-range-deg", help="half range X[,Y] in degrees (default: the lens file's field)")
    p.add_argument("--field-sampling", choices=FIELD_SAMPLINGS, default=FIELD_SAMPLINGS[0])
    p.add_argument("--layout", choices=LAYOUTS, default=LAYOUTS[0],
                   help="field: nodes on field angles; sensor: nodes on sensor positions (wide and fisheye lenses)")
    p.add_argument("--sensor-mm", help="sensor WxH in mm for --layout sensor (default: the square in the image circle)")
    add_sampling_options(p, method_flag)


def _add_outputs(p) -> None:
    p.add_argument("-o", "--output", required=True, help="output OpenEXR file")
    p.add_argument("--png", help="PNG for viewing (default: beside the EXR)")


def register(sub: Any) -> None:
    """Add `psf` and `psf-grid`."""
    psf = sub.add_parser("psf", help="one PSF (Fraunhofer or geometric) as OpenEXR + PNG")
    add_lens_argument(psf)
    psf.add_argument("--field-deg", required=True, help="X,Y field angle in degrees")
    psf.add_argument("--wavelength-nm", required=True, help="one wavelength, or several for a polychromatic PSF")
    psf.add_argument("--weights", help="weights of the wavelengths (default: equal)")
    add_sampling_options(psf)
    _add_outputs(psf)
    psf.set_defaults(run=run_psf)

    grid = sub.add_parser("psf-grid", help="PSFs on a field grid, one stack per wavelength, as OpenEXR (+ PNG mosaic with --png)")
    add_lens_argument(grid)
    add_grid_options(grid)
    grid.add_argument("--force", action="store_true", help="run even when the estimated memory exceeds what is free")
    grid.add_argument("-o", "--output", required=True, help="output OpenEXR file")
    grid.add_argument("--png", nargs="?", const="", metavar="PNG",
                      help="also write a PNG mosaic for viewing (beside the EXR, or at PNG); default: none")
    grid.set_defaults(run=run_psf_grid)
