"""Zemax OpticStudio sequential lens files (.zmx, text): read into our lens-file dictionary (what
`Lens.from_dict` takes) and written from a `Lens`.

Read: SURF blocks of TYPE STANDARD and EVENASPH (CURV in 1/unit, DISZ, CONI, PARM 2… = A4, A6, … of
the even asphere; PARM 1, the r² term, must be 0), STOP, DIAM (the semi-diameter), COMM (the label),
GLAS names resolved through our catalogue (unknown names fail naming the glass; a name that several
vendors use is taken from the vendor that GCAT lists, else it fails listing them; on SURF 0 the
object's medium) and model glass (`GLAS ___BLANK 1 0 n_d V_d …`, V_d 0 for a constant index); UNIT (MM, CM, IN, METER) scales every
length to mm; angle fields (YFLN/XFLN with FTYP 0) give the half field; WAVM (or WAVL) the
wavelengths (µm in the file, nm here); surface 0's DISZ the object distance (INFINITY). Surface 0 is
the object, the last SURF the image plane (its DIAM the image semi-diameter). Other surface types,
mirrors and other field types are refused, naming them.
"""
from __future__ import annotations

from ..errors import SolasError
from . import glass as glass_mod

UNITS = {"MM": 1.0, "CM": 10.0, "IN": 25.4, "METER": 1000.0, "M": 1000.0}
SURFACE_TYPES = ("STANDARD", "EVENASPH")
# GCAT catalogue names → our vendors (Zemax's NIKON catalogue is Hikari's glass).
GCAT_VENDORS = {**{v: v for v in glass_mod.VENDORS}, "NIKON": "HIKARI", "NIKON-HIKARI": "HIKARI"}


def _floats(tokens: list[str], where: str) -> list[float]:
    try:
        return [float(t) for t in tokens]
    except ValueError:
        raise SolasError(f"{where}: expected numbers, got {' '.join(tokens)!r}") from None


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


def _material(glas: list[str], ident: str, gcat: tuple[str, ...] = ()) -> str:
    """Our material name for a GLAS line's tokens; `gcat`: our vendors that the file's GCAT line lists,
    which pick among catalogue entries of the same name."""
    name = glas[0] if glas else ""
    if name.upper() == "MIRROR":
        raise SolasError(f"{ident}: GLAS MIRROR: mirrors are not supported (refracting surfaces only)")
    if name.upper() == "___BLANK":
        nd, vd = _floats(glas[3:5], f"{ident}: model glass GLAS ___BLANK")
        return f"model:{nd!r}" if vd == 0 else f"model:{nd!r}/{vd!r}"
    keys = glass_mod.candidates(name) if name and name.upper() != "AIR" else []
    listed = [k for k in keys if k.split(":", 1)[0] in gcat]
    return listed[0] if len(keys) > 1 and len(listed) == 1 else name


def read_spec(text: str, where: str) -> dict:
    """The lens-file dictionary of a .zmx text; `where` names it in messages."""
    top, blocks = _blocks(text, where)
    unit = (top.get("UNIT") or [["MM"]])[0][:1] or ["MM"]
    scale = UNITS.get(unit[0].upper())
    if scale is None:
        raise SolasError(f"{where}: UNIT {unit[0]!r} is not supported; allowed: {', '.join(UNITS)}")
    if len(blocks) < 3:
        raise SolasError(f"{where}: {len(blocks)} SURF blocks; a lens needs the object, a surface and the image")
    spec: dict = {}
    name = " ".join((top.get("NAME") or [[]])[0])
    if name:
        spec["name"] = name
    gcat = tuple(GCAT_VENDORS[c.upper()] for line in top.get("GCAT", []) for c in line if c.upper() in GCAT_VENDORS)
    spec["object"] = _object(blocks[0], scale, gcat, where)
    spec["surface"] = [_surface(b, i, scale, gcat, where) for i, b in enumerate(blocks[1:-1], start=1)]
    if "DIAM" in blocks[-1]:
        spec["image"] = {"diameter": 2.0 * _floats(blocks[-1]["DIAM"][0][:1], f"{where}: image DIAM")[0] * scale}
    spec.update(_wavelengths_and_field(top, where))
    return spec


def _object(block: dict, scale: float, gcat: tuple[str, ...], where: str) -> dict:
    """The [object] table of SURF 0: its distance (mm, or "infinity") and material."""
    obj_z = (block.get("DISZ") or [["INFINITY"]])[0][0]
    obj: dict = {"distance": "infinity" if obj_z.upper().startswith("INF")
                 else _floats([obj_z], f"{where}: object DISZ")[0] * scale}
    if "GLAS" in block:
        obj["material"] = _material(block["GLAS"][0], f"{where}: SURF 0 (object)", gcat)
    return obj


def _surface(b: dict, i: int, scale: float, gcat: tuple[str, ...], where: str) -> dict:
    """The [[surface]] table of SURF block `i` (lengths scaled to mm)."""
    ident = f"{where}: SURF {i} (line {b['line']})"
    kind = (b.get("TYPE") or [["STANDARD"]])[0][0].upper()
    if kind not in SURFACE_TYPES:
        raise SolasError(f"{ident}: surface TYPE {kind} is not supported; allowed: {', '.join(SURFACE_TYPES)}")
    curv = _floats((b.get("CURV") or [["0"]])[0][:1], f"{ident}: CURV")[0] / scale
    thickness = (b.get("DISZ") or [["0"]])[0][0]
    if thickness.upper().startswith("INF"):
        raise SolasError(f"{ident}: DISZ INFINITY inside the lens; only the object may be at infinity")
    if "DIAM" not in b:
        raise SolasError(f"{ident}: no DIAM (semi-diameter); every surface needs its clear aperture")
    row = {"label": " ".join((b.get("COMM") or [[f"SURF {i}"]])[0]) or f"SURF {i}",
           "radius": 0.0 if curv == 0 else 1.0 / curv,
           "thickness": _floats([thickness], f"{ident}: DISZ")[0] * scale,
           "diameter": 2.0 * _floats(b["DIAM"][0][:1], f"{ident}: DIAM")[0] * scale,
           "material": _material(b["GLAS"][0], ident, gcat) if "GLAS" in b else "AIR"}
    conic = _floats((b.get("CONI") or [["0"]])[0][:1], f"{ident}: CONI")[0]
    if conic:
        row["conic"] = conic
    if kind == "EVENASPH":
        terms = _aspheric(b, scale, ident)
        if terms:
            row["aspheric"] = terms
    if "STOP" in b:
        row["stop"] = True
    return row


def _aspheric(b: dict, scale: float, ident: str) -> list[float]:
    """[A4, A6, …] (mm^(1−2i)) of an EVENASPH block's PARM lines, trailing zeros dropped."""
    parm = {int(p[0]): _floats(p[1:2], f"{ident}: PARM")[0] for p in b.get("PARM", []) if p}
    if parm.get(1, 0.0):
        raise SolasError(f"{ident}: PARM 1 (the r² term) = {parm[1]:g}; only A4 and higher are modelled "
                         "(fold the r² term into CURV)")
    terms = [parm.get(k, 0.0) * scale ** (1 - 2 * k) for k in range(2, 9)]
    while terms and terms[-1] == 0.0:
        terms.pop()
    return terms


def _wavelengths_and_field(top: dict, where: str) -> dict:
    """wavelengths_nm (WAVM, else WAVL) and field_deg (the largest angle field) of the header."""
    spec: dict = {}
    waves = [w[1] for w in top.get("WAVM", []) if len(w) > 1] or [w for line in top.get("WAVL", []) for w in line]
    waves = list(dict.fromkeys(_floats(waves, f"{where}: WAVM/WAVL")))
    if waves:
        spec["wavelengths_nm"] = [w * 1000.0 for w in waves]
    ftype = (top.get("FTYP") or [["0"]])[0][:1] or ["0"]
    fields = [_floats(t, f"{where}: {k}") for k in ("XFLN", "YFLN") for t in top.get(k, [])]
    if fields and ftype[0] == "0":
        xs, ys = (fields[0], fields[1]) if len(fields) == 2 else ([0.0] * len(fields[0]), fields[0])
        spec["field_deg"] = max((x * x + y * y) ** 0.5 for x, y in zip(xs, ys))
    elif fields and any(v for f in fields for v in f):
        raise SolasError(f"{where}: FTYP {ftype[0]}: only angle fields (FTYP 0) are supported")
    return spec


def dumps(lens) -> str:
    """The .zmx text of `lens` (a `solas_mi.optics.lens.Lens`): UNIT MM, the aperture floating on the
    stop's DIAM, angle fields 0 and the half field, the lens's wavelengths; GCAT lists the vendors of
    its catalogue glasses and GLAS their names in those catalogues (the full VENDOR:NAME where two
    of the listed vendors use the same name)."""
    def number(v: float) -> str:
        return repr(float(v))

    def glas(g) -> list[str]:
        if g.kind == "air":
            return []
        if g.kind == "model":
            nd, vd = (g.coefficients[0][0], 0.0) if g.coefficients[1][0] == 0 else g.abbe()
            return [f"  GLAS ___BLANK 1 0 {number(nd)} {number(vd)} 0 0 0 0 0 0"]
        bare = g.name.split(":", 1)[-1]
        same = [k for k in glass_mod.candidates(bare) if k.split(":", 1)[0] in vendors]
        name = bare if same == [g.name] else g.name
        return [f"  GLAS {name} 0 0 {number(g.abbe()[0])} {number(g.abbe()[1])} 0 0 0 0 0 0"]

    glasses = [lens.object_glass, *(s.glass for s in lens.surfaces)]
    vendors = list(dict.fromkeys(g.name.split(":", 1)[0] for g in glasses if g.kind not in ("air", "model")))

    out = ["VERS 190513 80 123457 L123457", "MODE SEQ", f"NAME {lens.name}", "PFIL 0 0 0",
           "UNIT MM X W X CM MR CPMM", *([f"GCAT {' '.join(vendors)}"] if vendors else []),
           "FLOA", "FTYP 0 0 2 %d 0 0 0" % len(lens.wavelengths_nm),
           "XFLN 0 0", f"YFLN 0 {number(lens.field_deg)}"]
    out += [f"WAVM {i} {number(w / 1000.0)} 1" for i, w in enumerate(lens.wavelengths_nm, start=1)]
    out += [f"PWAV {lens.wavelengths_nm.index(lens.primary_wavelength) + 1}"]
    distance = "INFINITY" if lens.at_infinity else number(lens.object_distance)
    out += ["SURF 0", "  TYPE STANDARD", "  CURV 0.0", f"  DISZ {distance}", *glas(lens.object_glass)]
    for i, s in enumerate(lens.surfaces, start=1):
        out += [f"SURF {i}", f"  TYPE {'STANDARD' if not any(s.aspheric) else 'EVENASPH'}", f"  COMM {s.label}",
                f"  CURV {number(s.curvature)}"]
        out += [f"  PARM {k} {number(a)}" for k, a in enumerate(s.aspheric, start=2)]
        out += ["  STOP"] if s.stop else []
        out += [f"  DISZ {number(s.thickness)}", *glas(s.glass), f"  DIAM {number(s.semi_diameter)} 1 0 0 1 \"\""]
        out += [f"  CONI {number(s.conic)}"] if s.conic else []
    out += [f"SURF {len(lens.surfaces) + 1}", "  TYPE STANDARD", "  CURV 0.0", "  DISZ 0",
            f"  DIAM {number(lens.image_diameter / 2.0)} 1 0 0 1 \"\""]
    return "\n".join(out) + "\n"
