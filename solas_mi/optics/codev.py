"""CODE V sequence files (.seq, text): read into our lens-file dictionary (what `Lens.from_dict` takes),
registered (by `solas_mi.optics`) as the `.seq` entry of `formats.READERS`. The rotationally symmetric
refracting subset:

- Commands one per line or separated by `;`; `!` starts a comment; quoted strings ('…' or "…") are one
  token. Keywords are case-insensitive and, as in CODE V, known by their first three letters (STOP is
  STO).
- Surfaces: SO (the object: radius, thickness = object distance, ≥ 1e10 or INF is at infinity, glass), S and
  STO (radius or curvature, thickness, glass; STO is the stop), SI (the image); STO alone marks the
  surface before it, STO Sn surface n. Per surface after it:
  RDY (radius), CUY (curvature), THI, GLA, CIR (the clear semi-aperture; on SI the image's), STO (this
  surface is the stop), SLB (its label), SPH (spherical: no aspheric terms), CON or ASP with K (conic)
  and A, B, C, … J (the r⁴, r⁶, … r²⁰ coefficients), PIM (the thickness that puts the image plane at
  the paraxial image). RDM (or RDM Y) / RDM N or CUM: the S lines give radii or curvatures. A file saying
  neither is read in radii, as CODE V shows lens data and as the public hand-written files (and optiland)
  take them; ray-optics reads curvatures. Where the radii form no real image (a negative focal length, a
  virtual image, no field imaged) and curvatures do, curvatures are taken; the description says which.
  Without any STO the stop is surface 1 (CODE V's default; the description says so). CIR EDG (the edge aperture, drawn only) is read past; CIR OBS and HOL refused.
- Glass: catalogue names as CODE V writes them, NAME_VENDOR (SCHOTT, OHARA, HOYA, CDGM, SUMITA, HIKARI
  or NIKON; hyphens may be left out: NBK7_SCHOTT is N-BK7) or a bare name; model glass "n_d:V_d" or the
  code "nnnnnn.vvvvvv" or "nnn.vvv" (n_d = 1.nnnnnn, V_d = vv.vvvv); the object space's on SO.
- TEM (°C) and PRE (atmospheres): the temperature and air pressure the prescription holds at, the lens's
  `temperature_c` and `pressure_kpa` (its glass indices there, `thermal`; radii and thicknesses as given).
- System: TIT (the name), DIM M / C / I (mm, cm, inches), WL (nm) and REF (the reference one), the
  system aperture EPD (entrance-pupil diameter), FNO (the image-space F/#: EFL / EPD for a distant object,
  the paraxial working F/# 1 / (2 n' u') for a near one), NAO (object-space
  NA), none: the stop's CIR; fields YAN/XAN (degrees), YOB/XOB (object heights), YIM/XIM (paraxial
  image heights) or YRI/XRI (real image heights), solved as Zemax's are (`zemax_solves`); surfaces
  without CIR get the automatic semi-diameter.
Vignetting factors VUY/VLY/VUX/VLX shape the beam the automatic semi-diameters follow (`zemax_solves`).
Weights, optimisation codes, surface identifiers (UID), tolerances, DER values and view settings are read
past (`codev_syntax.IGNORED`); a zero CUF (fringe curvature) changes nothing. Decentres and tilts (XDE, YDE,
ZDE, ADE, BDE, CDE; DAR, REV, BEN) become coordinate breaks (`codev_placement`). What
cannot be represented is refused naming the surface and the feature: RET, mirrors,
diffractive, holographic, toric and anamorphic surfaces, rectangular or elliptical apertures,
obscurations, zoom positions, private catalogues; and any command not listed here.
"""

from __future__ import annotations

import math
import re

from ..errors import SolasError
from . import codev_placement, zemax_solves
from .codev_glass import PrivateCatalogue, material, unquote
from .codev_syntax import (
    APERTURES,
    ASPHERIC,
    FIELDS,
    IGNORED,
    REFUSED,
    SYSTEM,
    VIGNETTING,
    ZERO_IS_NOTHING,
    command,
    commands,
)
from .formats import MAX_FIELDS, check_count, one_line
from .formats import floats as _numbers
from .lens import Lens
from .paraxial import paraxial

UNITS = {"M": 1.0, "C": 10.0, "I": 25.4}
RADII_DEFAULT = "as CODE V's lens data shows them and hand-written files give them"
INFINITE_OBJECT = 1e10  # an object distance at least this (in lens units) is at infinity, as CODE V takes it
# TEM and PRE: the lens file's key, the unit CODE V gives it in, and the factor to ours (°C; atmospheres to kPa)
ENVIRONMENT = {"TEM": ("temperature_c", "°C", 1.0), "PRE": ("pressure_kpa", "atmospheres", 101.325)}


class _Reader:
    """The state of a .seq file being read: the system settings and the surfaces so far."""

    def __init__(self, where: str, radius_mode: bool = True):
        self.where = where
        self.system: dict = {}  # a system command's arguments; TEM, PRE: temperature_c, pressure_kpa
        self.rows: list[dict] = []  # SO, the surfaces, SI: raw values in lens units
        self.stop_at: int | None = None  # STO Sn: the stop is surface n
        self.radius_mode = radius_mode  # S lines give radii (RDM Y) or curvatures (RDM N, CUM)
        self.mode_given = False  # whether RDM or CUM said which
        self.s_values = False  # whether an S line gives a nonzero radius or curvature
        self.private: PrivateCatalogue | None = None  # inside PRV … END
        self.materials: dict[str, dict] = {}  # the private glasses, as [materials] tables

    def ident(self, line: int, new: str | None = None) -> str:
        """Where a command stands: its line and the surface it acts on (`new`: the kind of the surface the
        line itself begins, SO, S, STO or SI)."""
        if not self.rows and new is None:
            return f"{self.where}: line {line}"
        kind, i = (new, len(self.rows)) if new else (self.rows[-1]["kind"], len(self.rows) - 1)
        return f"{self.where}: line {line}, surface {'SO' if kind == 'SO' else ('SI' if kind == 'SI' else f'S{i}')}"

    def read(self, text: str) -> None:
        for line, tokens in commands(text):
            key, args = tokens[0].upper(), tokens[1:]
            if self.private is not None:
                if self.private.read(key, tokens, f"{self.where}: line {line}, PRV"):
                    self.materials.update(self.private.glasses)
                    self.private = None
                continue
            if key == "PRV":
                self.private = PrivateCatalogue()
                continue
            key = command(key)
            if key in REFUSED:
                if key in ZERO_IS_NOTHING and args and _numbers(args[:1], self.ident(line)) == [0.0]:
                    continue  # a zero fringe curvature changes nothing
                raise SolasError(
                    f"{self.ident(line)}: {key}: {REFUSED[key]} are not supported "
                    "(rotationally symmetric refracting systems only)"
                )
            self.command(key, args, line)

    def command(self, key: str, args: list[str], line: int) -> None:
        ident = self.ident(line)
        if key == "STO" and args and re.fullmatch(r"[Ss]\d+", args[0]):
            self.stop_at = int(args[0][1:])
        elif key in ("SO", "S", "STO", "SI") and (key != "STO" or args or not self.rows):
            self.surface(key, args, self.ident(line, key))
        elif key in ("RDM", "CUM"):
            self.radius_mode = key == "RDM" and (not args or args[0].upper() not in ("N", "NO"))
            self.mode_given = True
        elif key in IGNORED:
            return
        elif key in ENVIRONMENT:
            self.environment(key, args, ident)
        elif key in SYSTEM:
            self.system[key] = args
        elif not self.rows:
            raise SolasError(f"{ident}: command {key} is not supported (or needs a surface before it)")
        else:
            self.modify(self.rows[-1], key, args, ident)

    def environment(self, key: str, args: list[str], ident: str) -> None:
        """TEM (°C) or PRE (atmospheres): the lens's temperature or air pressure, checked by `thermal`."""
        value = _numbers(args[:1], f"{ident}: {key}")
        if not value:
            raise SolasError(f"{ident}: {key} needs a number ({ENVIRONMENT[key][1]})")
        name, _, scale = ENVIRONMENT[key]
        self.system[name] = value[0] * scale

    def surface(self, key: str, args: list[str], ident: str) -> None:
        row: dict = {"kind": key, "curv": 0.0, "thi": 0.0, "glass": "AIR", "ident": ident}
        if key == "SO" and args[1:2] and args[1].upper() in ("INF", "INFINITY"):
            args = [args[0], repr(INFINITE_OBJECT), *args[2:]]  # an object at infinity, spelt out
        values = _numbers(args[:2], f"{ident}: {key}")
        if values:
            self.modify(row, "RDY" if self.radius_mode else "CUY", args[:1], ident)
            self.s_values = self.s_values or values[0] != 0.0
        if len(values) > 1:
            row["thi"] = values[1]
        if len(args) > 2:
            row["glass"] = material(args[2], ident, self.materials)
        if key == "STO":
            row["stop"] = True
        self.rows.append(row)

    def modify(self, row: dict, key: str, args: list[str], ident: str) -> None:  # long: one branch per command
        if key == "CIR" and args[:1] and args[0].upper() in ("EDG", "OBS", "HOL"):
            if args[0].upper() != "EDG":  # EDG: the edge (mechanical) aperture, drawn only
                raise SolasError(f"{ident}: CIR {args[0].upper()}: obscurations and holes are not supported")
        elif key in ("RDY", "CUY", "THI", "CIR", "K", *ASPHERIC):
            value = _numbers(args[:1], f"{ident}: {key}") if args else []
            if not value:
                raise SolasError(f"{ident}: {key} needs a value")
            v = value[0]
            if key == "RDY":
                row["curv"] = 0.0 if v == 0 else 1.0 / v
            elif key == "CUY":
                row["curv"] = v
            elif key == "THI":
                row["thi"] = v
            elif key == "CIR":
                row["cir"] = v
            elif key == "K":
                row["conic"] = v
            else:
                row.setdefault("asp", {})[ASPHERIC.index(key)] = v
        elif key == "GLA":
            row["glass"] = material(args[0], ident, self.materials) if args else "AIR"
        elif key == "STO":
            row["stop"] = True
        elif key == "SLB":
            row["label"] = one_line(unquote(" ".join(args)))
        elif key == "PIM":
            row["pim"] = True
        elif key == "SPH":
            row.pop("asp", None)
            row.pop("conic", None)
        elif key in codev_placement.MOVES + codev_placement.TYPES:
            codev_placement.note(row, key, args, ident)
        elif key not in ("ASP", "CON"):
            raise SolasError(
                f"{ident}: command {key} is not supported (rotationally symmetric refracting "
                "surfaces: RDY, CUY, THI, GLA, CIR, STO, SLB, SPH, CON, ASP with K and A…J, PIM)"
            )


def read_spec(text: str, where: str) -> dict:
    """The lens-file dictionary of a .seq text; `where` names it in messages. A file that says neither RDM nor
    CUM is read in radii (module docstring); where that lens forms no real image and the same lines read as
    curvatures do, those are taken. The description says which."""
    reader = _read(text, where, radius_mode=True)
    if reader.mode_given or not reader.s_values:
        return _spec(reader, where)
    first: SolasError | None = None
    try:
        spec = _spec(reader, where)
        if _real_image(spec, where):
            return _noted(spec, f"no RDM in the file: its S lines read as radii, {RADII_DEFAULT}")
    except SolasError as exc:
        first = exc
    try:
        other = _spec(_read(text, where, radius_mode=False), where)
        if _real_image(other, where):
            return _noted(
                other,
                "no RDM in the file: its S lines read as radii form no real image, as curvatures "
                "(RDM N) they do: read as curvatures; add RDM or RDM N to say which",
            )
    except SolasError as exc:
        if first is not None and str(exc) == str(first):
            raise first from None  # the same fault either way: not the radii's
    if first is None:  # neither reading forms a real image: the radii stand, as the description says
        return _noted(spec, f"no RDM in the file: its S lines read as radii, {RADII_DEFAULT}")
    raise SolasError(
        f"{first} (the file has no RDM: its S lines were read as radii, {RADII_DEFAULT}; "
        "if they are curvatures, add RDM N)"
    ) from None


def _read(text: str, where: str, radius_mode: bool) -> _Reader:
    """The file's commands read, S lines in radii or curvatures where the file says neither."""
    reader = _Reader(where, radius_mode)
    reader.read(text)
    if reader.private is not None:
        raise SolasError(f"{where}: PRV (a private glass catalogue) has no END")
    return reader


def _real_image(spec: dict, where: str) -> bool:
    """Whether the lens of `spec` has a positive focal length and a paraxial image behind its last surface."""
    lens = Lens.from_dict(spec, source=where)
    p = paraxial(lens, lens.primary_wavelength)
    return bool(p.efl_mm > 0 and p.focus_z_mm > lens.vertex_z[-1])


def _noted(spec: dict, note: str) -> dict:
    spec["description"] = "; ".join(filter(None, (spec.get("description"), note)))
    return spec


def _spec(reader: _Reader, where: str) -> dict:
    """The lens-file dictionary of the commands `reader` read."""
    system, rows = reader.system, reader.rows
    if reader.stop_at is not None:
        if not 1 <= reader.stop_at < len(rows) - 1:
            raise SolasError(f"{where}: STO S{reader.stop_at}: the lens has surfaces S1 to S{len(rows) - 2}")
        for k, row in enumerate(rows):
            row["stop"] = k == reader.stop_at
    if len(rows) < 3 or rows[0]["kind"] != "SO" or rows[-1]["kind"] != "SI":
        raise SolasError(
            f"{where}: a lens needs SO (the object), at least one surface (S or STO) and SI "
            f"(the image), in that order; got {' '.join(r['kind'] for r in rows) or 'no surfaces'}"
        )
    stop_note = zemax_solves.default_stop(rows[1:-1], "STO", "CODE V's default")
    inner = [r for r in rows[1:-1] if r["kind"] in ("SO", "SI")]
    if inner:
        raise SolasError(f"{inner[0]['ident']}: {inner[0]['kind']} inside the lens (SO first, SI last)")
    dim = (system.get("DIM") or ["M"])[0].upper()[:1]
    if dim not in UNITS:
        raise SolasError(f"{where}: DIM {system['DIM'][0]!r} is not supported; allowed: M (mm), C (cm), I (inches)")
    scale = UNITS[dim]
    spec: dict = {
        "object": _object(rows[0], scale),
        **{key: system[key] for key, _, _ in ENVIRONMENT.values() if key in system},
    }
    if reader.materials:
        spec["materials"] = reader.materials
    title = one_line(" ".join(unquote(t) for t in system.get("TIT", system.get("TITLE", [])))).strip()
    if title:
        spec["name"] = title
    if stop_note:
        spec["description"] = stop_note
    spec["surface"] = [_surface(r, i, scale) for i, r in enumerate(rows[1:-1], start=1)]
    if rows[-1].get("cir", 0) > 0:
        spec["image"] = {"diameter": 2.0 * rows[-1]["cir"] * scale}
    codev_placement.place(spec, rows, scale)
    waves = _numbers(system.get("WL", []), f"{where}: WL")
    if waves:
        spec["wavelengths_nm"] = list(dict.fromkeys(waves))
    primary = _primary(system, waves, where)
    pim = [min(i, len(rows) - 3) for i, r in enumerate(rows[1:]) if r.get("pim")]  # on SI: the last gap
    if pim:
        _image_solve(spec, pim[-1], primary, where)
    aperture = _aperture(system, scale, where)
    if aperture[0] == "fnum" and spec["object"]["distance"] != "infinity":
        aperture = ("working fnum", aperture[1])  # CODE V's FNO: the working F/# at the object's conjugate
    fields = _fields(system, scale, where)
    return zemax_solves.solve(spec, aperture, fields, primary, where, _vignetting(system, len(fields[1]), where))


def _vignetting(system: dict, count: int, where: str) -> list[tuple[float, ...]] | None:
    """Per field, the VUX, VLX, VUY, VLY factors (0 where not given); None when the file gives none."""
    given = {k: _numbers(system[k], f"{where}: {k}") for k in VIGNETTING if k in system}
    if not given:
        return None
    for k, values in given.items():
        if len(values) > count or not all(-1.0 < v < 1.0 for v in values):
            raise SolasError(f"{where}: {k} {' '.join(system[k])!r}: one factor in (-1, 1) per field ({count} fields)")
    return [tuple(given.get(k, [])[i] if i < len(given.get(k, [])) else 0.0 for k in VIGNETTING) for i in range(count)]


def _object(row: dict, scale: float) -> dict:
    obj: dict = {"distance": "infinity" if abs(row["thi"]) >= INFINITE_OBJECT else row["thi"] * scale}
    if row["glass"].upper() != "AIR":
        obj["material"] = row["glass"]
    return obj


def _surface(row: dict, i: int, scale: float) -> dict:
    """The [[surface]] table of a surface row, lengths in mm; "diameter" None without CIR (automatic)."""
    curv = row["curv"] / scale
    out = {
        "label": row.get("label") or f"S{i}",
        "radius": 0.0 if curv == 0 else 1.0 / curv,
        "thickness": row["thi"] * scale,
        "material": row["glass"],
        "diameter": 2.0 * row["cir"] * scale if row.get("cir", 0) > 0 else None,
    }
    if row.get("conic"):
        out["conic"] = row["conic"]
    terms = [row.get("asp", {}).get(k, 0.0) * scale ** (-3 - 2 * k) for k in range(len(ASPHERIC))]
    while terms and terms[-1] == 0.0:
        terms.pop()
    if terms:
        out["aspheric"] = terms
    if row.get("stop"):
        out["stop"] = True
    return out


def _primary(system: dict, waves: list[float], where: str) -> float | None:
    """The reference wavelength (nm): REF's entry of WL (1-based), else None (the lens's middle one)."""
    if "REF" not in system or not waves:
        return None
    ref = _numbers(system["REF"][:1], f"{where}: REF")
    if not ref or ref[0] != int(ref[0]) or not 1 <= ref[0] <= len(waves):
        raise SolasError(f"{where}: REF {' '.join(system['REF'])!r} must name one of the {len(waves)} WL entries")
    return waves[int(ref[0]) - 1]


def _image_solve(spec: dict, k: int, primary: float | None, where: str) -> None:
    """PIM on surface k: its thickness set so that the image plane lies at the paraxial image."""
    rows = [{**r, "diameter": r["diameter"] or 1.0} for r in spec["surface"]]
    lens = Lens.from_dict({**spec, "surface": rows}, source=where)
    p = paraxial(lens, primary or lens.primary_wavelength)
    spec["surface"][k]["thickness"] -= p.image_offset_mm


def _aperture(system: dict, scale: float, where: str) -> tuple[str, float]:
    """The system aperture: ("epd", mm), ("fnum", F/#), ("na", NA), or ("float", 0): the stop's CIR."""
    given = [k for k in APERTURES if k in system]
    if len(given) > 1:
        raise SolasError(f"{where}: {' and '.join(given)} both set the system aperture; give one")
    if not given:
        return "float", 0.0
    value = _numbers(system[given[0]][:1], f"{where}: {given[0]}")
    if not value or not value[0] > 0:
        raise SolasError(f"{where}: {given[0]} {' '.join(system[given[0]])!r} must be a positive number")
    return APERTURES[given[0]], value[0] * (scale if given[0] == "EPD" else 1.0)


def _fields(system: dict, scale: float, where: str) -> tuple[str, list[float]]:
    """The field type (`zemax_solves`' kinds) and each field's radial size (degrees or mm)."""
    given = [k for k in FIELDS if k in system or "X" + k[1:] in system]
    if len(given) > 1:
        raise SolasError(f"{where}: fields given as both {' and '.join(given)}; give one kind")
    if not given:
        return "angle", []
    y = _numbers(system.get(given[0], []), f"{where}: {given[0]}")
    x = _numbers(system.get("X" + given[0][1:], []), f"{where}: X{given[0][1:]}")
    n = max(len(x), len(y))
    check_count(n, "fields", MAX_FIELDS, where)
    x, y = x + [0.0] * (n - len(x)), y + [0.0] * (n - len(y))
    unit = 1.0 if given[0] == "YAN" else scale
    return FIELDS[given[0]], [math.hypot(a, b) * unit for a, b in zip(x, y)]
