"""`solas-mi lens info`: paraxial data, real chief rays, and the distortion and relative illumination
table (image height vs field, closest projection) of a lens, as a table or JSON;
`solas-mi lens convert`: a lens file in another format (`formats.writable()`); `solas-mi lens calibrate`
(`calibration.command`); `add_lens_argument`, the LENS of every command that takes one."""
from __future__ import annotations

import sys
from typing import Any

import numpy as np

from .. import jsonio
from ..options import floats
from . import notes, typical_ar
from .formats import lens_help, writable

_ROWS = [("efl_mm", "EFL (mm)"), ("bfd_mm", "BFD (mm)"), ("entrance_pupil_diameter_mm", "EPD (mm)"),
         ("entrance_pupil_z_mm", "entrance pupil z (mm)"), ("exit_pupil_diameter_mm", "exit pupil D (mm)"),
         ("exit_pupil_z_mm", "exit pupil z (mm)"), ("f_number", "f/# (EFL/EPD)"),
         ("working_f_number", "working f/#"), ("exit_pupil_f_number", "f/# (exit pupil → image)"),
         ("image_offset_mm", "image plane − paraxial focus (mm)")]


def add_lens_argument(p) -> None:
    """The positional LENS argument of every command that takes a lens, and where the lens is
    (`add_environment_options`)."""
    p.add_argument("lens", help=lens_help())
    add_environment_options(p)


def add_environment_options(p) -> None:
    """--temperature-c, --pressure-kpa and --mount: the lens at another temperature and pressure (`Lens.at`)."""
    from . import thermal  # light: no NumPy

    p.add_argument("--temperature-c", type=float, metavar="C", help="the lens, its mount and the air at this "
                   "temperature (°C; default: the lens file's, 20 unless it states one)")
    p.add_argument("--pressure-kpa", type=float, metavar="KPA", help="the air's pressure (kPa; default: the lens "
                   "file's, 101.325 unless it states one)")
    p.add_argument("--mount", help="what holds every air gap, which grows with the temperature: "
                   f"{', '.join(thermal.MOUNTS)}, or a CTE in 1/K (default: each surface's mount in the lens file, "
                   f"{thermal.DEFAULT_MOUNT} where it names none)")


def load_lens(args):
    """The lens of a command (`args.lens`, at `args.temperature_c` and `args.pressure_kpa` where given:
    `Lens.at`), stating on stderr what of it overlaps (`Lens.overlaps`)."""
    from . import thermal
    from .lens import Lens

    lens = Lens.load(args.lens)
    temperature, pressure, mount = (args.temperature_c, args.pressure_kpa, args.mount)
    if mount is not None:
        thermal.mount_cte(mount)  # checked even where nothing moves (the lens at its own temperature)
    if temperature is not None or pressure is not None:
        lens = lens.at(lens.temperature_c if temperature is None else temperature,
                       lens.pressure_kpa if pressure is None else pressure, mount)
    for note in lens.overlaps:
        print(f"solas-mi: warning: lens {lens.name}: {note}", file=sys.stderr)
    return lens


def _print_distortion(table) -> None:
    """`lens info`'s table of image height, distortion and relative illumination against field."""
    print(f"\nimage height vs field at {table.wavelength_nm:g} nm (real chief ray); closest projection: "
          f"{table.projection}")
    print(f"{'field (deg)':>12s}{'height (mm)':>14s}{'f tan(θ) (mm)':>16s}{'distortion %':>14s}{'rel. illum.':>13s}")
    for row in zip(table.field_deg, table.image_height_mm, table.rectilinear_height_mm, table.distortion_percent,
                   table.relative_illumination):
        rect, percent = ("-", "-") if row[2] is None else (f"{row[2]:.6f}", f"{row[3]:.4f}")
        print(f"{row[0]:12.3f}{row[1]:14.6f}{rect:>16s}{percent:>14s}{'-' if row[4] is None else f'{row[4]:.4f}':>13s}")
    if table.illumination_note:
        print(f"rel. illum. '-': {table.illumination_note}")
    print("projection fits (focal mm, RMS residual mm): " + ", ".join(
        f"{k} {f:.4f} / {r:.2e}" if f is not None else f"{k} undefined beyond 90 deg"
        for k, (f, r) in table.projection_fits.items()))


def _real_chief_y(lens, fields: list[float], wavelength_nm: float) -> list[float]:
    """Image y (mm) of the real chief rays of fields (0, f) degrees: the Dr.Jit tracer's aim, or for a lens as
    built (`lens_checks.as_built`) the NumPy tracer's (`local_aim`, on the sensor in its own frame)."""
    from .lens_checks import as_built

    field_deg = np.array([[0.0, f] for f in fields]).reshape(-1, 2)
    if not as_built(lens):
        from .pupil import chief_rays  # loads Dr.Jit

        return chief_rays(lens, field_deg, np.full(len(fields), wavelength_nm)).image_xy[:, 1].tolist()
    from ..errors import SolasError
    from .local_aim import chief_rays as aimed

    chief = aimed(lens, field_deg, wavelength_nm)
    if not chief.found.all():
        bad = field_deg[~chief.found][0]
        raise SolasError(f"lens {lens.name}: no real chief ray of {wavelength_nm:g} nm through the stop's centre "
                         f"found for field ({bad[0]:g}, {bad[1]:g}) deg")
    return chief.image_xy[:, 1].tolist()


def run_lens_info(args) -> int:
    from .distortion import distortion
    from .lens_checks import as_built
    from .paraxial import paraxial

    lens = load_lens(args)
    wavelengths = (floats(args.wavelengths_nm, "--wavelengths-nm") if args.wavelengths_nm is not None
                   else list(lens.wavelengths_nm))
    half = [lens.field_deg, -lens.field_deg] if lens.field_deg else []  # none for a lens that states no field
    fields = floats(args.fields, "--fields") if args.fields is not None else [0.0, *half]
    rows = []
    for w in wavelengths:
        p = paraxial(lens, w, fields).as_dict()
        p["real_chief_ray_image_height_mm"] = _real_chief_y(lens, fields, w)
        rows.append(p)
    info = {"lens": lens.name, "hash": lens.hash, "source": lens.source, "stop_surface": lens.stop_index + 1,
            "image_z_mm": lens.image_z, "image_diameter_mm": lens.image_diameter, "field_type": lens.field_type.name,
            "dispersion": lens.dispersive, **notes.metadata(lens), **typical_ar.note(lens), "per_wavelength": rows}
    table = None
    if (args.fields or lens.field_deg > 0) and not as_built(lens):  # the given fields, else 0 … the half field
        table = distortion(lens, sorted({abs(f) for f in fields} | {0.0}) if args.fields else None)
    info["distortion"] = table.as_dict() if table else None
    if args.json:
        print(jsonio.dumps(info, indent=2))
        return 0
    print(f"{lens.name}  ({lens.description})  hash {lens.hash}")
    print(f"stop: surface {lens.stop_index + 1}; image plane z = {lens.image_z:.6f} mm, diameter {lens.image_diameter:g} mm")
    print(f"fields: {lens.field_type.description}")
    if "temperature_c" in info:
        print(f"at {lens.temperature_c:g} °C in air of {lens.pressure_kpa:g} kPa (glass indices relative to it)")
    if not lens.dispersive:
        print("glass: no dispersion data (every medium a constant index): the columns of every wavelength agree")
    for key, label in (("virtual_object", "object: virtual, "), ("ideal_lens_path", "ideal lens: "),
                       ("coatings", "coatings: "), ("iris", "iris: "), ("paraxial_axis", "note: ")):
        if key in info:
            print(label + info[key])
    for note in info.get("overlaps", []):
        print(f"overlap: {note}")
    print(f"{'quantity':36s}" + "".join(f"{w:>12g} nm" for w in wavelengths))
    image_space = [("efl_image_space_mm", "EFL in image space, n'·EFL (mm)")] * any(
        r["efl_image_space_mm"] != r["efl_mm"] for r in rows)  # only where the image medium is not air
    for key, label in _ROWS[:1] + image_space + _ROWS[1:]:
        print(f"{label:36s}" + "".join(f"{r[key]:15.6f}" for r in rows))
    for i, f in enumerate(f + 0.0 for f in fields):  # + 0.0: −0 reads 0
        print(f"{f'chief ray y at {f:g} deg, paraxial (mm)':36s}" + "".join(f"{r['chief_ray_image_height_mm'][i]:15.6f}" for r in rows))
        print(f"{f'chief ray y at {f:g} deg, real (mm)':36s}" + "".join(f"{r['real_chief_ray_image_height_mm'][i]:15.6f}" for r in rows))
    if table:
        _print_distortion(table)
    elif as_built(lens):
        print("\nno distortion table: it is computed for lenses on one axis only (this one is as built)")
    return 0


def run_lens_list(args) -> int:
    """The shipped lenses: name, source (the file's description), EFL and f/# at the primary wavelength,
    half field."""
    from .lens import Lens, shipped_lenses
    from .paraxial import paraxial

    rows = []
    for name in shipped_lenses():
        lens = Lens.load(name)
        p = paraxial(lens, lens.primary_wavelength)
        rows.append({"name": name, "source": lens.description, "efl_mm": p.efl_mm, "f_number": p.f_number,
                     "field_deg": lens.field_deg, "wavelength_nm": lens.primary_wavelength})
    if args.json:
        print(jsonio.dumps(rows, indent=2))
        return 0
    print(f"{'name':20s}{'EFL (mm)':>10s}{'f/#':>7s}{'field (deg)':>13s}  source")
    for r in rows:
        print(f"{r['name']:20s}{r['efl_mm']:10.2f}{r['f_number']:7.2f}{r['field_deg']:13g}  {r['source']}")
    return 0


def run_lens_convert(args) -> int:
    from ..outputs import check_target
    from .lens import Lens

    lens = load_lens(args)
    target = check_target(args.output, [lens.source] if lens.source else [])
    out = (typical_ar.with_typical_ar(lens) if args.typical_ar else lens).save(target)
    lens = Lens.load(out) if args.typical_ar else lens
    print(f"wrote {out} ({lens.name}: {len(lens.surfaces)} surfaces, hash {lens.hash})")
    return 0


def register(sub: Any) -> None:
    """Add `lens list`, `lens info`, `lens convert` and `lens calibrate`."""
    lens = sub.add_parser("lens", help="lens data").add_subparsers(dest="lens_command", metavar="COMMAND", required=True)
    shipped = lens.add_parser("list", help="the shipped lenses: name, EFL, f/# (primary wavelength), half field, source")
    shipped.add_argument("--json", action="store_true", help="as JSON")
    shipped.set_defaults(run=run_lens_list)
    info = lens.add_parser("info", help="paraxial data: EFL, BFD, pupils, f/#, chief rays, distortion and "
                           "relative illumination")
    add_lens_argument(info)
    info.add_argument("--wavelengths-nm", help="nm, comma-separated (default: the lens file's)")
    info.add_argument("--fields", help="y field angles in degrees, comma-separated")
    info.add_argument("--json", action="store_true", help="as JSON instead of the table: every value at full precision, each key naming its unit")
    info.set_defaults(run=run_lens_info)
    convert = lens.add_parser("convert", help=f"write a lens file in another format ({writable()}, by extension)")
    add_lens_argument(convert)
    convert.add_argument("-o", "--output", required=True, help=f"the new lens file, its format by its extension: "
                                                                f"{writable()}")
    ar = typical_ar.TYPICAL_AR
    convert.add_argument("--typical-ar", action="store_true", help=f"state the typical AR coating on every air-glass "
                         f"surface that states none: {ar['material']} a quarter wave at {ar['design_nm']:g} nm")
    convert.set_defaults(run=run_lens_convert)
    from .calibration.command import register as register_calibrate

    register_calibrate(lens, add_lens_argument, load_lens)
