"""The `solas-mi` command line: lens data, PSFs and PSF grids, direct renders, image metrics."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from .arguments import floats, parse_wxh
from .errors import SolasError


def _field(text: str) -> tuple[float, float]:
    values = floats(text, "--field-deg")
    if len(values) == 1:
        values = [0.0, values[0]]
    if len(values) != 2:
        raise SolasError(f"--field-deg {text!r} must be X,Y in degrees (or one value, taken as Y)")
    return values[0], values[1]


def _lens(name: str):
    from .lens import Lens

    return Lens.load(name)


def _lens_info(args) -> int:
    from .pupil import chief_rays  # loads Dr.Jit

    lens = _lens(args.lens)
    wavelengths = floats(args.wavelengths, "--wavelengths") if args.wavelengths else list(lens.wavelengths_nm)
    fields = floats(args.fields, "--fields") if args.fields else [0.0, lens.field_deg, -lens.field_deg]
    rows = []
    for w in wavelengths:
        p = lens.paraxial(w, fields).as_dict()
        real = chief_rays(lens, np.array([[0.0, f] for f in fields]), np.full(len(fields), w))
        p["real_chief_ray_image_height_mm"] = real.image_xy[:, 1].tolist()
        rows.append(p)
    info = {"lens": lens.name, "hash": lens.hash, "source": lens.source, "stop_surface": lens.stop_index + 1,
            "image_z_mm": lens.image_z, "image_diameter_mm": lens.image_diameter, "per_wavelength": rows}
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    print(f"{lens.name}  ({lens.description})  hash {lens.hash}")
    print(f"stop: surface {lens.stop_index + 1}; image plane z = {lens.image_z:.6f} mm, diameter {lens.image_diameter:g} mm")
    keys = [("efl_mm", "EFL (mm)"), ("bfd_mm", "BFD (mm)"), ("entrance_pupil_diameter_mm", "EPD (mm)"),
            ("entrance_pupil_z_mm", "entrance pupil z (mm)"), ("exit_pupil_diameter_mm", "exit pupil D (mm)"),
            ("exit_pupil_z_mm", "exit pupil z (mm)"), ("f_number", "f/# (EFL/EPD)"),
            ("working_f_number", "working f/#"), ("exit_pupil_f_number", "f/# (exit pupil → image)"),
            ("image_offset_mm", "image plane − paraxial focus (mm)")]
    print(f"{'quantity':36s}" + "".join(f"{w:>12g} nm" for w in wavelengths))
    for key, label in keys:
        print(f"{label:36s}" + "".join(f"{r[key]:15.6f}" for r in rows))
    for i, f in enumerate(fields):
        print(f"{f'chief ray y at {f:g} deg, paraxial (mm)':36s}" + "".join(f"{r['chief_ray_image_height_mm'][i]:15.6f}" for r in rows))
        print(f"{f'chief ray y at {f:g} deg, real (mm)':36s}" + "".join(f"{r['real_chief_ray_image_height_mm'][i]:15.6f}" for r in rows))
    return 0


def _psf(args) -> int:
    lens = _lens(args.lens)
    wavelengths = floats(args.wavelength_nm, "--wavelength-nm")
    weights = floats(args.weights, "--weights") if args.weights else None
    p = lens.psf(_field(args.field_deg), wavelengths, weights=weights, pitch_um=args.pitch_um, size=args.size,
                 method=args.method, normalization=args.normalize, pupil_samples=args.pupil_samples, rays=args.rays)
    p.write(args.output)
    png = args.png or str(Path(args.output).with_suffix(".png"))
    p.write_png(png)
    print(f"wrote {args.output} and {png}")
    return 0


def _psf_grid(args) -> int:
    lens = _lens(args.lens)
    grid = parse_wxh(args.grid, "--grid")
    wavelengths = floats(args.wavelengths, "--wavelengths") if args.wavelengths else None
    rng = floats(args.field_range_deg, "--field-range-deg") if args.field_range_deg else None
    if rng is not None and len(rng) not in (1, 2):
        raise SolasError(f"--field-range-deg {args.field_range_deg!r} must be one value or X,Y")

    def progress(done: int, total: int) -> None:
        print(f"\r{done}/{total} PSFs", end="", file=sys.stderr, flush=True)

    g = lens.psf_grid(grid=grid, wavelengths_nm=wavelengths,
                      field_range_deg=None if rng is None else (rng[0], rng[-1]), pitch_um=args.pitch_um,
                      size=args.size, method=args.method, normalization=args.normalize,
                      pupil_samples=args.pupil_samples, rays=args.rays, field_sampling=args.field_sampling,
                      progress=progress)
    print(file=sys.stderr)
    g.write(args.output)
    png = args.png or str(Path(args.output).with_suffix(".png"))
    g.write_png(png)
    print(f"wrote {args.output} and {png} ({g.meta['seconds']:.1f} s)")
    return 0


def _add_psf_options(p: argparse.ArgumentParser) -> None:
    from .psf import (DEFAULT_GEOMETRIC_RAYS, DEFAULT_PITCH_UM, DEFAULT_PUPIL_SAMPLES, DEFAULT_SIZE, METHODS,
                      NORMALIZATIONS)

    p.add_argument("--pitch-um", type=float, default=DEFAULT_PITCH_UM, help="image-plane pixel pitch (µm)")
    p.add_argument("--size", type=int, default=DEFAULT_SIZE, help="PSF width and height (pixels)")
    p.add_argument("--method", choices=METHODS, default="fraunhofer")
    p.add_argument("--normalize", choices=NORMALIZATIONS, default="sum")
    p.add_argument("--pupil-samples", type=int, default=DEFAULT_PUPIL_SAMPLES, help="Fraunhofer pupil grid N×N")
    p.add_argument("--rays", type=int, default=DEFAULT_GEOMETRIC_RAYS, help="geometric: rays×rays per PSF")
    p.add_argument("-o", "--output", required=True, help="output OpenEXR file")
    p.add_argument("--png", help="PNG for viewing (default: beside the EXR)")


def build_parser() -> argparse.ArgumentParser:
    from . import crossval, render_commands, report
    from .convolution import commands as convolution_commands
    from .metrics import commands as metrics_commands

    parser = argparse.ArgumentParser(prog="solas-mi", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    lens = sub.add_parser("lens", help="lens data").add_subparsers(dest="lens_command", required=True)
    info = lens.add_parser("info", help="paraxial data: EFL, BFD, pupils, f/#, chief rays")
    info.add_argument("lens", help="shipped lens name (solas-doublet) or a .toml lens file")
    info.add_argument("--wavelengths", help="nm, comma-separated (default: the lens file's)")
    info.add_argument("--fields", help="y field angles in degrees, comma-separated")
    info.add_argument("--json", action="store_true")
    info.set_defaults(run=_lens_info)

    psf = sub.add_parser("psf", help="one PSF (Fraunhofer or geometric) as OpenEXR + PNG")
    psf.add_argument("lens")
    psf.add_argument("--field-deg", required=True, help="X,Y field angle in degrees")
    psf.add_argument("--wavelength-nm", required=True, help="one wavelength, or several for a polychromatic PSF")
    psf.add_argument("--weights", help="weights of the wavelengths (default: equal)")
    _add_psf_options(psf)
    psf.set_defaults(run=_psf)

    from .psf_grid import FIELD_SAMPLINGS

    grid = sub.add_parser("psf-grid", help="PSFs on a field grid, one stack per wavelength, as OpenEXR + PNG mosaic")
    grid.add_argument("lens")
    grid.add_argument("--grid", default="8x8", help="columns x rows of field nodes")
    grid.add_argument("--wavelengths", help="nm, comma-separated (default: the lens file's)")
    grid.add_argument("--field-range-deg", help="half range X[,Y] in degrees (default: the lens file's field)")
    grid.add_argument("--field-sampling", choices=FIELD_SAMPLINGS, default=FIELD_SAMPLINGS[0])
    _add_psf_options(grid)
    grid.set_defaults(run=_psf_grid)

    metrics_commands.register(sub)
    render_commands.register(sub)
    convolution_commands.register(sub)
    crossval.register(sub)
    report.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except SolasError as exc:
        print(f"solas-mi {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
