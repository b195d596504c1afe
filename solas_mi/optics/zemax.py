"""Zemax OpticStudio sequential lens files (.zmx, text): read into our lens-file dictionary (what
`Lens.from_dict` takes) and written from a `Lens`, registered (by `solas_mi.optics`) as the `.zmx`
entries of `formats.READERS` and `WRITERS`.

Read as the author meant it:
- Encodings as OpticStudio writes them: UTF-16 with or without a byte-order mark, UTF-8, else Latin-1
  (`formats.decode_text`); written as UTF-8 text, names and labels on one line each (control characters become
  spaces: a name cannot add a line).
- Surfaces: TYPE STANDARD, EVENASPH (PARM 2… = A4, A6, …; PARM 1, the r² term, must be 0), ODDASPH (PARM
  k the r^k coefficient: the even ones from r⁴ up are kept; r² and odd terms are refused naming the
  surface), QED_TYPE (OpticStudio's Q-type asphere: XDAT 1 the type, 0 Qbfs or 1 Qcon, XDAT 2 the number
  of terms, XDAT 3 the normalisation radius, XDAT 4… a0, a1, …; Qbfs kept as such, Qcon rewritten exactly
  as even-asphere terms, `forbes`), COORDBRK (a pure axial shift: its DISZ added to the gap; undone by the
  next break: gone; one that decentres or tilts: the next surface's placement), TOROIDAL and BICONICX
  (`zemax_asbuilt`, which writes them and the breaks back); PARAXIAL, the ideal thin lens (`ideal`: PARM 1 the focal length,
  PARM 2 the OPD mode); flat air surfaces without a clear aperture of their own (no DIAM, or DIAM's solve
  type 0, automatic: it cuts no ray) (dummies) are dropped, their thickness added to the gap. STOP (none:
  surface 1, as in OpticStudio's new lens, said in the description), COMM (the label), CONI, CURV, DISZ;
  COAT: the ideal coatings I.xx (`coating.zemax_coating`), a coating file's named ones refused by name.
- Clear apertures: DIAM (the semi-diameter); where absent or 0, Zemax's automatic semi-diameter:
  the largest height of the real chief and marginal (stop-rim) rays of every field and wavelength.
- Glass: GLAS names through our catalogue; a name several vendors use is taken from the vendors GCAT
  lists, or from SCHOTT, Zemax's default, when the file lists none (the description says so; the
  lens's `catalogues` holds them); model glass `GLAS ___BLANK 1 0 n_d V_d …` (V_d 0 or absent: a
  constant index); on SURF 0 the object's medium.
- System aperture, which sets the stop's size as in Zemax (the stop's DIAM only with FLOA): ENPD
  (entrance-pupil diameter), FNUM x 0 (image-space F/# = EFL / EPD), FNUM x 1 (paraxial working F/#),
  OBNA x 0 (object-space NA, finite objects), FLOA (float by stop size; also where none is named).
- Fields (XFLN/YFLN, FTYP's first number): 0 angle, 1 object height, 2 paraxial image height, 3 real
  image height (the field whose real chief ray lands there); field_deg is the widest as an angle.
  Vignetting factors VDXN/VCXN/VDYN/VCYN shape the beam automatic semi-diameters follow.
- ENVD (°C, atm; older TEMP, PRES): the lens's `temperature_c`, `pressure_kpa` (`thermal`); written back so.
- UNIT (MM, CM, IN, METER) scales every length to mm; WAVM (or WAVL) the wavelengths (µm in the file),
  PWAV the one the aperture and field solves use; surface 0's DISZ the object distance. The last SURF
  is the image plane (its DIAM the image semi-diameter). Mirrors, gratings, a tilted sensor and other
  surface types are refused naming the surface and the feature.
"""
from __future__ import annotations

import math

from ..errors import SolasError
from . import forbes, ideal, zemax_asbuilt, zemax_solves
from . import glass as glass_mod
from .coating import to_zemax, zemax_coating
from .formats import MAX_FIELDS, check_count, one_line
from .formats import floats as _floats

UNITS = {"MM": 1.0, "CM": 10.0, "IN": 25.4, "METER": 1000.0, "M": 1000.0}
SURFACE_TYPES = ("STANDARD", "EVENASPH", "ODDASPH", "QED_TYPE", "COORDBRK", "PARAXIAL", *zemax_asbuilt.SHAPE_TYPES)
FIELD_TYPES = {"0": "angle", "1": "object height", "2": "paraxial image height", "3": "real image height"}
# GCAT catalogue names → our vendors (Zemax's NIKON catalogue is Hikari's glass).
GCAT_VENDORS = {**{v: v for v in glass_mod.VENDORS}, "NIKON": "HIKARI", "NIKON-HIKARI": "HIKARI"}
DEFAULT_CATALOGUE = "SCHOTT"  # what OpticStudio uses for a file that names no catalogue


def _blocks(text: str, where: str) -> tuple[dict, list[dict]]:
    """Top-level keyword lines (keyword → list of token lists) and one dict per SURF block."""
    top: dict[str, list[list[str]]] = {}
    surfaces: list[dict] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        tokens = raw.split()
        if not tokens:
            continue
        key = tokens[0].upper()
        if key == "SURF":
            surfaces.append({"line": number})
        elif raw[:1].isspace() and surfaces:
            surfaces[-1].setdefault(key, []).append(tokens[1:])
        else:
            top.setdefault(key, []).append(tokens[1:])
    if not surfaces:
        raise SolasError(f"{where}: no SURF blocks; not a sequential Zemax lens file")
    return top, surfaces


def _material(glas: list[str], ident: str, gcat: tuple[str, ...]) -> str:
    """Our material name for a GLAS line's tokens; `gcat`: our vendors that the file's GCAT line lists
    (or the default), which pick among catalogue entries of the same name."""
    name = glas[0] if glas else ""
    if name.upper() == "MIRROR":
        raise SolasError(f"{ident}: GLAS MIRROR: mirrors are not supported (refracting surfaces only)")
    if name.upper() == "___BLANK":
        if len(glas) < 4:
            raise SolasError(f"{ident}: model glass GLAS ___BLANK needs n_d (and V_d): "
                             f"'___BLANK 1 0 n_d V_d', got {' '.join(glas)!r}")
        nd, *vd = _floats(glas[3:5], f"{ident}: model glass GLAS ___BLANK n_d V_d")
        try:
            return glass_mod.model_name(nd, vd[0] if vd else None)
        except SolasError as exc:
            raise SolasError(f"{ident}: {exc} (V_d 0: no dispersion)") from None
    keys = glass_mod.candidates(name) if name and name.upper() != "AIR" else []
    for vendor in gcat:  # the catalogues in the order the file lists them
        listed = [k for k in keys if k.split(":", 1)[0] == vendor]
        if len(keys) > 1 and len(listed) == 1:
            return listed[0]
    return name


def _catalogues(top: dict) -> tuple[tuple[str, ...], bool]:
    """Our vendors of the GCAT line, in its order (Zemax's default when none), and whether defaulted."""
    named = [c.upper() for line in top.get("GCAT", []) for c in line]
    gcat = tuple(dict.fromkeys(GCAT_VENDORS[c] for c in named if c in GCAT_VENDORS))
    return (gcat, False) if named else ((DEFAULT_CATALOGUE,), True)


def read_spec(text: str, where: str) -> dict:
    """The lens-file dictionary of a .zmx text; `where` names it in messages."""
    top, blocks = _blocks(text, where)
    unit = (top.get("UNIT") or [["MM"]])[0][:1] or ["MM"]
    scale = UNITS.get(unit[0].upper())
    if scale is None:
        raise SolasError(f"{where}: UNIT {unit[0]!r} is not supported; allowed: {', '.join(UNITS)}")
    if len(blocks) < 3:
        raise SolasError(f"{where}: {len(blocks)} SURF blocks; a lens needs the object, a surface and the image")
    name = one_line(" ".join((top.get("NAME") or [[]])[0])).strip()
    gcat, defaulted = _catalogues(top)
    spec: dict = {**({"name": name} if name else {}), "catalogues": list(gcat)}
    notes = [f"glass names resolved in {DEFAULT_CATALOGUE}'s catalogue first, OpticStudio's default (the file "
             "names no GCAT)"] if defaulted else []
    spec["object"] = _object(blocks[0], scale, gcat, where)
    rows = [_surface(b, i, scale, gcat, where) for i, b in enumerate(blocks[1:-1], start=1)]
    if "STOP" in blocks[0] or "STOP" in blocks[-1]:
        raise SolasError(f"{where}: STOP on the object or the image surface; the aperture stop lies between them")
    notes.append(zemax_solves.default_stop(rows, "STOP", "as in OpticStudio's new lens (OBJ, STO, IMA)"))
    spec.update({"description": "; ".join(filter(None, notes))} if any(notes) else {})
    spec.update(ideal.zemax_notes(rows, spec.get("description")))
    spec["surface"], image = zemax_asbuilt.fold(rows, where)
    if "DIAM" in blocks[-1]:
        semi = _floats(blocks[-1]["DIAM"][0][:1], f"{where}: image DIAM")[0] * scale
        image.update({"diameter": 2.0 * semi} if semi > 0 else {})
    spec.update({"image": image} if image else {})
    spec.update(_wavelengths(top, where))
    spec.update(_environment(top, where))
    fields = _fields(top, scale, where)
    return zemax_solves.solve(spec, _aperture(top, scale, where), fields, _primary(top, spec), where,
                              zemax_solves.vignetting_factors(top, len(fields[1]), where))


def _environment(top: dict, where: str) -> dict:
    """temperature_c and pressure_kpa of the ENVD line (°C, atmospheres), or of older files' TEMP and PRES lines."""
    envd = (top.get("ENVD") or [[]])[0][:2]
    given = {"temperature_c": envd[:1] or (top.get("TEMP") or [[]])[0][:1],
             "pressure_kpa": envd[1:2] or (top.get("PRES") or [[]])[0][:1]}
    return {key: _floats(v, f"{where}: ENVD/TEMP/PRES")[0] * (101.325 if key == "pressure_kpa" else 1.0)
            for key, v in given.items() if v}


def _object(block: dict, scale: float, gcat: tuple[str, ...], where: str) -> dict:
    """The [object] table of SURF 0: its distance (mm, or "infinity") and material."""
    obj_z = (block.get("DISZ") or [["INFINITY"]])[0][0]
    obj: dict = {"distance": "infinity" if obj_z.upper().startswith("INF")
                 else _floats([obj_z], f"{where}: object DISZ")[0] * scale}
    if "GLAS" in block:
        obj["material"] = _material(block["GLAS"][0], f"{where}: SURF 0 (object)", gcat)
    return obj


def _surface(b: dict, i: int, scale: float, gcat: tuple[str, ...], where: str) -> dict:
    """The [[surface]] table of SURF block `i` (lengths scaled to mm); "diameter" None where Zemax
    computes it (no DIAM, or 0); a coordinate break's parameters under "break"."""
    ident = f"{where}: SURF {i} (line {b['line']})"
    kind = (b.get("TYPE") or [["STANDARD"]])[0][0].upper()
    if kind not in SURFACE_TYPES:
        raise SolasError(f"{ident}: surface TYPE {kind} is not supported; allowed: {', '.join(SURFACE_TYPES)} "
                         "(refracting surfaces)")
    curv = _floats((b.get("CURV") or [["0"]])[0][:1], f"{ident}: CURV")[0] / scale
    thickness = (b.get("DISZ") or [["0"]])[0][0]
    if thickness.upper().startswith("INF"):
        raise SolasError(f"{ident}: DISZ INFINITY inside the lens; only the object may be at infinity")
    semi = _floats(b["DIAM"][0][:1], f"{ident}: DIAM")[0] * scale if "DIAM" in b else 0.0
    hard = _circular_aperture(b, ident) * scale
    semi = hard or semi
    row = {"label": one_line(" ".join((b.get("COMM") or [[]])[0])).strip() or f"SURF {i}",
           "radius": 0.0 if curv == 0 else 1.0 / curv,
           "thickness": _floats([thickness], f"{ident}: DISZ")[0] * scale,
           "diameter": 2.0 * semi if semi > 0 else None,
           "material": _material(b["GLAS"][0], ident, gcat) if "GLAS" in b else "AIR", "ident": ident,
           "auto": not hard and (semi <= 0 or b["DIAM"][0][1:2] == ["0"])}  # DIAM's solve type 0: Zemax's automatic aperture
    conic = _floats((b.get("CONI") or [["0"]])[0][:1], f"{ident}: CONI")[0]
    if conic:
        row["conic"] = conic
    if kind == "COORDBRK":
        row["break"] = _numbered(b, "PARM", ident)
    elif kind in ("EVENASPH", "ODDASPH"):
        terms = _aspheric(b, scale, ident) if kind == "EVENASPH" else _odd_aspheric(b, scale, ident)
        if terms:
            row["aspheric"] = terms
    elif kind == "QED_TYPE":
        row.update(_q_type(b, scale, ident))
    elif kind == "PARAXIAL":
        row.update(ideal.from_zemax(_numbered(b, "PARM", ident), scale, ident))
    elif kind in zemax_asbuilt.SHAPE_TYPES:
        row.update(zemax_asbuilt.form_row(kind, _numbered(b, "PARM", ident), _numbered(b, "XDAT", ident), scale, ident), conic=conic)
    row.update({"stop": True} if "STOP" in b else {})
    row.update({"coating": zemax_coating(b["COAT"][0][0], ident)} if b.get("COAT", [[]])[0] else {})
    return row


# a surface's apertures other than a circle about the axis: refused, as reading DIAM instead would trace rays the
# lens stops (rectangle, ellipse, obscurations, a user-defined shape; an aperture decentred by OBDC)
OTHER_APERTURES = {"SQAP": "rectangular aperture", "ELAP": "elliptical aperture", "OBSC": "circular obscuration",
                   "OBSQ": "rectangular obscuration", "OBEL": "elliptical obscuration", "UDAD": "user-defined aperture",
                   "UDAP": "user-defined aperture"}


def _circular_aperture(b: dict, ident: str) -> float:
    """The radius of a CLAP line (Zemax's circular aperture, `CLAP min max …`; 0 without one) in file units: the
    hard aperture rays beyond are stopped at, which replaces DIAM's. An annulus (min > 0), any other aperture kind
    and a decentred aperture are refused by name."""
    other = sorted(set(b) & set(OTHER_APERTURES))
    if other:
        raise SolasError(f"{ident}: {other[0]} ({OTHER_APERTURES[other[0]]}) is not supported; a surface's aperture "
                         "may be its DIAM or a circular CLAP about the axis")
    shift = [v for v in (b.get("OBDC") or [[]])[0][:2] if _floats([v], f"{ident}: OBDC")[0]]
    if shift:
        raise SolasError(f"{ident}: OBDC {' '.join(b['OBDC'][0][:2])} decentres the aperture; only apertures "
                         "centred on the axis are supported")
    if "CLAP" not in b:
        return 0.0
    radii = _floats(b["CLAP"][0][:2], f"{ident}: CLAP")
    if len(radii) < 2 or radii[0] != 0.0 or not radii[1] > 0.0:
        raise SolasError(f"{ident}: CLAP {' '.join(b['CLAP'][0][:2])}: a circular aperture must run from radius 0 to "
                         "a positive radius (an annulus is not supported)")
    return radii[1]


def _numbered(b: dict, key: str, ident: str) -> dict[int, float]:
    """{n: value} of a block's lines `key` n value (PARM, XDAT); SolasError naming one without its n or value."""
    out: dict[int, float] = {}
    for p in b.get(key, []):
        if len(p) < 2 or not p[0].isdigit():
            why = "has no value" if p[:1] and p[0].isdigit() else "has no whole number n"
            raise SolasError(f"{ident}: {' '.join([key, *p])} {why}; a {key} line is '{key} <n> <value>'")
        out[int(p[0])] = _floats(p[1:2], f"{ident}: {key} {p[0]}")[0]
    return out


def _aspheric(b: dict, scale: float, ident: str) -> list[float]:
    """[A4, A6, …] (mm^(1−2i)) of an EVENASPH block's PARM lines, trailing zeros dropped."""
    parm = _numbered(b, "PARM", ident)
    if parm.get(1, 0.0):
        raise SolasError(f"{ident}: PARM 1 (the r² term) = {parm[1]:g}; only A4 and higher are modelled "
                         "(fold the r² term into CURV)")
    return _trim([parm.get(k, 0.0) * scale ** (1 - 2 * k) for k in range(2, 9)])


def _odd_aspheric(b: dict, scale: float, ident: str) -> list[float]:
    """[A4, A6, A8] of an ODDASPH block (PARM k: the r^k coefficient); r² and odd terms refused."""
    parm = _numbered(b, "PARM", ident)
    other = {k: v for k, v in parm.items() if v and (k % 2 or k == 2)}
    if other:
        k = min(other)
        raise SolasError(f"{ident}: ODDASPH PARM {k} (the r^{k} term) = {other[k]:g}; only even terms from r⁴ "
                         "up are modelled (odd and r² terms are not)")
    return _trim([parm.get(k, 0.0) * scale ** (1 - k) for k in range(4, 9, 2)])


def _q_type(b: dict, scale: float, ident: str) -> dict:
    """The row entries of a QED_TYPE block: {"qbfs", "norm_radius"} (type 0) or {"aspheric"} (type 1,
    Qcon, an even asphere exactly); {} when every coefficient is 0."""
    xdat = _numbered(b, "XDAT", ident)
    kind, count, radius = xdat.get(1, 0.0), xdat.get(2, 0.0), xdat.get(3, 0.0) * scale
    if kind not in (0.0, 1.0) or count != int(count) or not 0 <= count <= 12:
        raise SolasError(f"{ident}: QED_TYPE with type (XDAT 1) {kind:g} and {count:g} terms (XDAT 2); allowed: "
                         "type 0 (Qbfs) or 1 (Qcon), 0 to 12 terms")
    terms = _trim([xdat.get(4 + m, 0.0) * scale for m in range(int(count))])
    if terms and not radius > 0:
        raise SolasError(f"{ident}: QED_TYPE normalisation radius (XDAT 3) {radius:g} must be positive")
    if not terms or kind == 1.0:
        return {"aspheric": _trim(forbes.qcon_to_even(tuple(terms), radius))} if terms else {}
    return {"qbfs": terms, "norm_radius": radius}


def _trim(terms: list[float]) -> list[float]:
    while terms and terms[-1] == 0.0:
        terms.pop()
    return terms


def _wavelengths(top: dict, where: str) -> dict:
    """wavelengths_nm (WAVM, else WAVL) of the header."""
    waves = [w[1] for w in top.get("WAVM", []) if len(w) > 1] or [w for line in top.get("WAVL", []) for w in line]
    waves = list(dict.fromkeys(_floats(waves, f"{where}: WAVM/WAVL")))
    return {"wavelengths_nm": [w * 1000.0 for w in waves]} if waves else {}


def _primary(top: dict, spec: dict) -> float | None:
    """The primary wavelength (nm): PWAV's entry of WAVM, else None (the lens's middle one)."""
    index = {int(w[0]): float(w[1]) * 1000.0 for w in top.get("WAVM", []) if len(w) > 1}
    pwav = (top.get("PWAV") or [["1"]])[0][:1] or ["1"]
    try:
        return index.get(int(pwav[0])) if spec.get("wavelengths_nm") else None
    except ValueError:
        return None


def _aperture(top: dict, scale: float, where: str) -> tuple[str, float]:
    """The system aperture: ("float", 0), ("epd", mm), ("fnum", F/#), ("working fnum", F/#) or ("na", NA)."""
    if "FLOA" in top:
        return "float", 0.0
    for key, kinds, unit in (("ENPD", ("epd",), scale), ("FNUM", ("fnum", "working fnum"), 1.0), ("OBNA", ("na",), 1.0)):
        if key in top:
            value, *mode = _floats(top[key][0][:2], f"{where}: {key}") or [0.0]
            kind = dict(enumerate(kinds)).get(mode[0] if mode else 0)
            if kind is None:
                raise SolasError(f"{where}: {key} {' '.join(top[key][0][:2])}: system aperture type not supported; "
                                 "allowed: entrance pupil diameter (ENPD), image-space F/# (FNUM x 0), paraxial "
                                 "working F/# (FNUM x 1), object-space NA (OBNA x 0), float by stop size (FLOA)")
            if not value > 0:
                raise SolasError(f"{where}: {key} {value:g} must be positive")
            return kind, value * unit
    return "float", 0.0


def _fields(top: dict, scale: float, where: str) -> tuple[str, list[float]]:
    """The field type (FIELD_TYPES' values) and the radial size of each field (degrees or mm)."""
    ftype = (top.get("FTYP") or [["0"]])[0][:1] or ["0"]
    if ftype[0] not in FIELD_TYPES:
        raise SolasError(f"{where}: FTYP {ftype[0]}: field type not supported; allowed: "
                         + ", ".join(f"{k} ({v})" for k, v in FIELD_TYPES.items()))
    kind = FIELD_TYPES[ftype[0]]
    count = _floats((top.get("FTYP") or [["0", "0", "0"]])[0][2:3] or ["0"], f"{where}: FTYP")[0]
    xs = _floats((top.get("XFLN") or [[]])[0], f"{where}: XFLN")
    ys = _floats((top.get("YFLN") or [[]])[0], f"{where}: YFLN")
    n = int(count) if count > 0 else max(len(xs), len(ys))
    check_count(n, "fields", MAX_FIELDS, where)
    xs, ys = (v + [0.0] * (n - len(v)) for v in (xs[:n], ys[:n]))
    unit = 1.0 if kind == "angle" else scale
    return kind, [math.hypot(x, y) * unit for x, y in zip(xs, ys)]


def dumps(lens) -> str:
    """The .zmx text of `lens` (a `solas_mi.optics.lens.Lens`): UNIT MM, the aperture floating on the
    stop's DIAM, angle fields 0 and the half field, the lens's wavelengths; GCAT lists the vendors of
    its catalogue glasses and GLAS their names in those catalogues (the full VENDOR:NAME where two
    of the listed vendors use the same name). Names and labels are written on one line each."""
    def number(v: float) -> str:
        return repr(float(v))

    def glas(g) -> list[str]:
        if g.kind == "air":
            return []
        if g in lens.materials:
            raise SolasError(f"lens {lens.name}: material {g.name!r} is the lens file's own ([materials]); .zmx "
                             "names catalogue or model glass only; save it as .toml")
        nd, vd = (g.coefficients[0][0], 0.0) if g.kind == "model" and g.coefficients[1][0] == 0 else g.abbe()
        nd, vd = float(f"{nd:.12g}"), float(f"{vd:.12g}")  # the formula's rounding noise is no digit of n_d
        if g.kind == "model":
            return [f"  GLAS ___BLANK 1 0 {number(nd)} {number(vd)} 0 0 0 0 0 0"]
        bare = g.name.split(":", 1)[-1]
        same = [k for k in glass_mod.candidates(bare) if k.split(":", 1)[0] in vendors]
        name = bare if same == [g.name] else g.name
        return [f"  GLAS {name} 0 0 {number(nd)} {number(vd)} 0 0 0 0 0 0"]

    glasses = [lens.object_glass, *(s.glass for s in lens.surfaces)]
    vendors = list(dict.fromkeys(g.name.split(":", 1)[0] for g in glasses if g.kind not in ("air", "model")))

    out = ["VERS 190513 80 123457 L123457", "MODE SEQ", f"NAME {lens.name}", "PFIL 0 0 0",
           "UNIT MM X W X CM MR CPMM", f"ENVD {number(lens.temperature_c)} {number(lens.pressure_kpa / 101.325)} 0",
           *([f"GCAT {' '.join(vendors)}"] if vendors else []),
           "FLOA", f"FTYP 0 0 2 {len(lens.wavelengths_nm)} 0 0 0",
           "XFLN 0 0", f"YFLN 0 {number(lens.field_deg)}"]
    out += [f"WAVM {i} {number(w / 1000.0)} 1" for i, w in enumerate(lens.wavelengths_nm, start=1)]
    out += [f"PWAV {lens.wavelengths_nm.index(lens.primary_wavelength) + 1}"]
    distance = "INFINITY" if lens.at_infinity else number(lens.object_distance)
    out += ["SURF 0", "  TYPE STANDARD", "  CURV 0.0", f"  DISZ {distance}", *glas(lens.object_glass)]
    i = 0
    for k, s in enumerate(lens.surfaces, start=1):
        if s.placement is not None:
            i += 1
            out += [f"SURF {i}", *zemax_asbuilt.break_lines(s.placement, number)]
        i += 1
        kind, parm = zemax_asbuilt.surface_lines(s, number)
        shape = s.form or s
        out += [f"SURF {i}", f"  TYPE {kind or _surface_type(s, k)}", f"  COMM {s.label}", *parm,
                f"  CURV {number(0.0 if shape.radius == 0 else 1.0 / shape.radius)}"]
        out += [f"  PARM {k} {number(a)}" for k, a in enumerate(s.aspheric, start=2)] + ideal.to_zemax(s.focal_length)
        if any(s.qbfs):
            out += [f"  XDAT {k} {number(v)}" for k, v in
                    enumerate((0.0, float(len(s.qbfs)), s.norm_radius, *s.qbfs), start=1)]
        out += (["  STOP"] if s.stop else []) + to_zemax(s.coating, f"lens {lens.name}: surface {s.label}")
        out += [f"  DISZ {number(s.thickness)}", *glas(s.glass), f"  DIAM {number(s.semi_diameter)} 1 0 0 1 \"\""]
        out += [f"  CONI {number(shape.conic)}"] if shape.conic else []
    if lens.image_placement is not None:  # the sensor decentred or tilted
        i += 1
        out += [f"SURF {i}", *zemax_asbuilt.break_lines(lens.image_placement, number)]
    out += [f"SURF {i + 1}", "  TYPE STANDARD", "  CURV 0.0", "  DISZ 0",
            f"  DIAM {number(lens.image_diameter / 2.0)} 1 0 0 1 \"\""]
    return "\n".join(out) + "\n"


def _surface_type(s, i: int) -> str:
    """The TYPE of surface `i` in a .zmx file; SolasError for Qbfs and even-asphere terms together."""
    if any(s.qbfs) and any(s.aspheric):
        raise SolasError(f"surface {i} ({s.label}): Qbfs and even-asphere terms together have no .zmx surface "
                         "type; save it as .toml")
    return "PARAXIAL" if s.ideal else "QED_TYPE" if any(s.qbfs) else "EVENASPH" if any(s.aspheric) else "STANDARD"

