"""CODE V's decentres and tilts in a .seq file, read into the lens's coordinate breaks (`placement`).

On a surface (S, STO) or the image (SI): XDE, YDE, ZDE (lens units) and ADE, BDE, CDE (degrees) decentre it
and then tilt it by α about x, β about the new y, γ about the newest z; CODE V's α and β turn by the
left-hand rule and γ by the right-hand rule (as ray-optics reads them: its `DecenterData.convertl2r`), so a
break of Zemax's order 0 with tilts (−α, −β, γ) is the same move. The decentre's type: none, a basic
decentre (this surface and those after it on the new axis); DAR, decentre and return (after this surface the
axis is the one before its decentre, its thickness measured from the vertex it had before it); REV, a
reverse decentre (none before this surface; after it the inverse move, tilts γ, β, α undone, then the
decentre: it returns from a basic decentre of the same values); BEN, bend (the move before the surface and
its tilts again after it, as at a fold mirror). Each surface's break and the gap before it are then
found from the move between its frame and the one before (`place`): the gap is the move along the earlier
surface's axis, the rest a break of order 0 (decentres, tilts about x, y, z). Lengths in mm after `scale`.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import SolasError
from .formats import floats as _numbers
from .placement import KEYS, Placement

MOVES = ("XDE", "YDE", "ZDE", "ADE", "BDE", "CDE")  # a decentre's values, in Placement's order
TYPES = ("DAR", "REV", "BEN")  # the decentre's type; none: a basic decentre


def note(row: dict, key: str, args: list[str], ident: str) -> None:
    """Record on `row` a decentre command `key` (`MOVES` or `TYPES`) and its value."""
    if key in TYPES:
        row["decentre_type"] = key
        return
    value = _numbers(args[:1], f"{ident}: {key}") if args else []
    if not value:
        raise SolasError(f"{ident}: {key} needs a value")
    row.setdefault("moves", dict.fromkeys(MOVES, 0.0))[key] = value[0]


def _move(row: dict, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The decentre (mm, 3) and rotation (3×3: the new axes in the old frame) of a row's decentre."""
    m = row.get("moves", dict.fromkeys(MOVES, 0.0))
    rotation = Placement(tilt_x=-m["ADE"], tilt_y=-m["BDE"], tilt_z=m["CDE"]).rotation()
    return np.array([m["XDE"], m["YDE"], m["ZDE"]]) * scale, rotation


def _relative(before: dict, after: dict, gap: float, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The shift (3, in the frame of the surface of row `before`) and rotation from that surface's frame to
    the frame of the surface of row `after`, `gap` mm apart along the axis between them."""
    shift, turn = np.zeros(3), np.eye(3)
    if before.get("decentre_type") in ("DAR", "REV"):  # back to the axis before the move (REV: its inverse)
        d, r = _move(before, scale)
        shift, turn = -r.T @ d, r.T
    elif before.get("decentre_type") == "BEN":
        turn = _move(before, scale)[1]
    shift = shift + turn[:, 2] * gap
    if "moves" in after and after.get("decentre_type") != "REV":
        d, r = _move(after, scale)
        shift, turn = shift + turn @ d, turn @ r
    return shift, turn


def _tilts(turn: np.ndarray) -> tuple[float, float, float]:
    """(tilt_x, tilt_y, tilt_z) degrees of a break of order 0 whose rotation is `turn` (|tilt_y| ≤ 90)."""
    return (
        math.degrees(math.atan2(-turn[1, 2], turn[2, 2])),
        math.degrees(math.asin(max(-1.0, min(1.0, turn[0, 2])))),
        math.degrees(math.atan2(-turn[0, 1], turn[0, 0])),
    )


def place(spec: dict, rows: list[dict], scale: float) -> None:
    """Write into `spec` (its [[surface]] rows and [image]) the breaks and gaps of the decentres of `rows`
    (SO, the surfaces, SI); nothing where none decentres. SolasError for a ZDE on surface 1 (it would move the
    lens along its axis against the object) or a decentre on SO."""
    if not any("moves" in r or "decentre_type" in r for r in rows):
        return
    if "moves" in rows[0] or "decentre_type" in rows[0]:
        raise SolasError(f"{rows[0]['ident']}: a decentre on SO (the object) is not supported")
    tables = [*spec["surface"], spec.setdefault("image", {})]
    first = rows[1].get("moves", {}).get("ZDE", 0.0)
    if first and rows[1].get("decentre_type") != "REV":
        raise SolasError(f"{rows[1]['ident']}: ZDE on surface 1 is not supported (put the shift in SO's thickness)")
    for k in range(1, len(rows)):
        if k == 1:
            shift, turn = _relative({}, rows[1], 0.0, scale)
        else:
            shift, turn = _relative(rows[k - 1], rows[k], tables[k - 2]["thickness"], scale)
            tables[k - 2]["thickness"] = float(shift[2])
        values = (float(shift[0]), float(shift[1]), *_tilts(turn))
        if any(values):
            tables[k - 1].update({key: v for key, v in zip(KEYS, (*values, 0)) if v})
    if not spec["image"]:
        del spec["image"]


__all__ = ["MOVES", "TYPES", "note", "place"]
