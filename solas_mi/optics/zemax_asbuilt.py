"""The lens as built in .zmx files (`zemax` reads and writes through it): TOROIDAL and BICONICX surfaces,
coordinate breaks that decentre or tilt, and the folding of breaks and dummies into our rows.

- TOROIDAL: CURV and CONI the y-z curve's, PARM 1 the radius of rotation (0: none, a cylinder),
  PARM 2…8 α1…α7 on y², y⁴, …, y¹⁴ (`shapes.toroid`); PARM 0, the extrapolation flag, changes nothing
  inside the curve's domain (rays beyond it are lost); its Zernike terms (PARM 13…, or extra data) are
  refused by name (OpticStudio User Guide, "Toroidal").
- BICONICX: CURV and CONI the y-z section's, PARM 1 the x radius (0: flat in x), PARM 2 the x conic
  (`shapes.biconic`; its polynomial terms refused by name).
- COORDBRK: PARM 1, 2 the decentres, PARM 3, 4, 5 the tilts (degrees), PARM 6 the order flag; with DISZ 0
  it becomes the next surface's `placement` (`placement.Placement`, the same convention), or the image
  plane's (a decentred or tilted sensor, `Lens.image_placement`); a break that only
  moves along the axis gives its DISZ to the gap before, and a pair of breaks that undo each other
  vanishes (as before the lens as built was read); a moving break's own thickness is folded exactly into
  the gap before it and its decentres (`_placed`). Two breaks in a row that do not undo each other are
  refused by name.
Lengths scaled to mm by the file's UNIT.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import SolasError
from .placement import KEYS as PLACEMENT_KEYS
from .placement import Placement

SHAPE_TYPES = ("TOROIDAL", "BICONICX")
TERMS = 7  # TOROIDAL's PARM 2…8: α1…α7 (OpticStudio User Guide, "Toroidal")
NORM_RADIUS_XDAT = 2  # TOROIDAL's extra data: XDAT 1 the number of Zernike terms, XDAT 2 their normalisation radius


def form_row(kind: str, parameters: dict[int, float], extra: dict[int, float], scale: float, ident: str) -> dict:
    """The row entries beyond radius and conic (CURV, CONI) of a TOROIDAL or BICONICX block's PARM lines;
    SolasError for a parameter or extra data (XDAT: a toroid's Zernike terms) that is not read."""
    last = 1 + TERMS if kind == "TOROIDAL" else 2
    stray = sorted(k for k, v in parameters.items() if v and not ((k == 0 and kind == "TOROIDAL") or 1 <= k <= last))
    if stray:
        raise SolasError(
            f"{ident}: {kind} PARM {stray[0]} = {parameters[stray[0]]:g} is not read (only PARM 1 to {last})"
        )
    # TOROIDAL's XDAT 1 is its number of Zernike terms, XDAT 2 their normalisation radius (set, at 100, in
    # files with no terms: Thorlabs' cylinder lenses), XDAT 3… the terms: the radius alone changes nothing
    unused = (
        {NORM_RADIUS_XDAT}
        if kind == "TOROIDAL" and not any(v for k, v in extra.items() if k != NORM_RADIUS_XDAT)
        else set()
    )
    extra_set = sorted(k for k, v in extra.items() if v and k not in unused)
    if extra_set:
        raise SolasError(
            f"{ident}: {kind} extra data XDAT {extra_set[0]} = {extra[extra_set[0]]:g} is not read "
            "(its Zernike or polynomial terms)"
        )
    if kind == "BICONICX":
        return {"kind": "biconic", "radius_x": parameters.get(1, 0.0) * scale, "conic_x": parameters.get(2, 0.0)}
    terms = [parameters.get(k, 0.0) * scale ** (1 - 2 * (k - 1)) for k in range(2, 2 + TERMS)]
    while terms and terms[-1] == 0.0:
        terms.pop()
    rotation = parameters.get(1, 0.0) * scale
    if not terms and not rotation:
        return {"kind": "cylinder"}
    return {"kind": "toroid", "terms_y": terms, "radius_rotation": rotation}


def fold(rows: list[dict], where: str) -> tuple[list[dict], dict]:
    """Rows without coordinate breaks and dummies, and the [image] table's placement entries: a pure axial
    break, a pair of breaks that undo each other, and a flat air surface with no clear aperture of its own
    give their thickness to the row before (or to the object's gap: refused, as the object distance would
    change); a break that decentres or tilts becomes the next row's placement, or the image plane's."""
    out: list[dict] = []
    image: dict = {}
    i = 0
    while i < len(rows):
        row = rows[i]
        if "break" in row:
            shift = _break_shift(rows, i)
            if shift == "placed":
                (rows[i + 1] if i + 1 < len(rows) else image).update(_placed(row, out))
                i += 1
                continue
            span = 2 if shift is None else 1
            moved = row["thickness"] + (rows[i + 1]["thickness"] if shift is None else 0.0)
            if not out:
                raise SolasError(f"{row['ident']}: a coordinate break before the first surface is not supported")
            out[-1]["thickness"] += moved
            i += span
            continue
        air_before = not out or out[-1]["material"].upper() == "AIR"
        plain = not any(row.get(k) for k in ("stop", "aspheric", "qbfs", "kind", *PLACEMENT_KEYS))
        dummy = (
            row["radius"] == 0
            and plain
            and "focal_length" not in row
            and (row["diameter"] is None or row["auto"])
            and row["material"].upper() == "AIR"
            and air_before
            and out
        )
        if dummy:
            out[-1]["thickness"] += row["thickness"]
        else:
            out.append(row)
        i += 1
    return [{k: v for k, v in row.items() if k not in ("ident", "auto", "opd_mode")} for row in out], image


def _break_shift(rows: list[dict], i: int) -> float | str | None:
    """0.0 for a coordinate break that only moves along the axis; None when the next row is a break
    that undoes it (no thickness between them); "placed" for one that places the next surface (or the image plane);
    else SolasError naming the break."""
    row = rows[i]
    p = row["break"]
    moves = [p.get(k, 0.0) for k in range(1, 6)]
    if not any(moves):
        return 0.0
    nxt = rows[i + 1] if i + 1 < len(rows) else {}
    q = nxt.get("break")
    if q is not None and row["thickness"] == 0:
        back = [q.get(k, 0.0) for k in range(1, 6)]
        reordered = p.get(6, 0.0) != q.get(6, 0.0)
        several = sum(1 for v in moves if v) > 1
        if back == [-v for v in moves] and (reordered or not several):
            return None
    if q is None:
        return "placed"  # on the next surface, or the image plane (the sensor) where none follows
    why = "followed by another break that does not undo it"
    raise SolasError(
        f"{row['ident']}: COORDBRK decentres or tilts the axis (decenter x, y {moves[0]:g}, "
        f"{moves[1]:g}; tilt x, y, z {moves[2]:g}, {moves[3]:g}, {moves[4]:g}) {why}"
    )


def _placed(row: dict, out: list[dict]) -> dict:
    """The placement entries of a break `row` (PARM 1…6: `placement.KEYS`, the order flag 0 or 1) for the row
    after it. A break's own thickness t (along its new z) is folded into the row before (`out[-1]`), exactly:
    order 0 decentres before it tilts by R, so R (0, 0, t) = (a, b, c) adds (a, b) to the decentres and c to
    that thickness; order 1 decentres along the tilted axes, so the thickness grows by δ = t / R_zz and the
    decentres lose δ (R_zx, R_zy) (refused where R_zz = 0, a tilt of 90°)."""
    p = row["break"]
    values = [p.get(k, 0.0) for k in range(1, 6)] + [1 if p.get(6, 0.0) else 0]
    placement = Placement(*values)
    t = row["thickness"]
    if t:
        if not out:
            raise SolasError(
                f"{row['ident']}: a coordinate break with a thickness (DISZ {t:g}) before the first "
                "surface is not supported"
            )
        r = placement.rotation()
        if placement.order == 0:
            a, b, c = r @ np.array([0.0, 0.0, t])
        else:
            if abs(r[2, 2]) < 1e-12:
                raise SolasError(
                    f"{row['ident']}: a coordinate break of order 1 tilted by 90° with a thickness "
                    f"(DISZ {t:g}) is not supported"
                )
            c = t / r[2, 2]
            a, b = -c * r[2, :2]
        out[-1]["thickness"] += c
        placement = replace(placement, decentre_x=placement.decentre_x + a, decentre_y=placement.decentre_y + b)
    return placement.table()


def surface_lines(s, number) -> tuple[str, list[str]]:
    """(TYPE, the PARM lines) of a surface without rotational symmetry; ("", []) for the others."""
    table = s.form.table() if s.form is not None else {}
    if s.kind == "biconic":
        return "BICONICX", [f"  PARM 1 {number(table['radius_x'])}", f"  PARM 2 {number(table['conic_x'])}"]
    if s.form is None:
        return "", []
    terms = table.get("terms_y", [])
    if len(terms) > TERMS:
        raise SolasError(
            f"surface {s.label}: a toroid of {len(terms)} terms_y has no .zmx form (TOROIDAL holds "
            f"{TERMS}); save it as .toml"
        )
    return "TOROIDAL", [f"  PARM 1 {number(table.get('radius_rotation', 0.0))}"] + [
        f"  PARM {k} {number(a)}" for k, a in enumerate(terms, start=2)
    ]


def break_lines(placement, number) -> list[str]:
    """The lines of a COORDBRK block (after its SURF line) that places the next surface."""
    values = (placement.decentre_x, placement.decentre_y, placement.tilt_x, placement.tilt_y, placement.tilt_z)
    return (
        ["  TYPE COORDBRK", "  CURV 0.0", "  DISZ 0"]
        + [f"  PARM {k} {number(v)}" for k, v in enumerate(values, start=1)]
        + [f"  PARM 6 {placement.order}"]
    )
