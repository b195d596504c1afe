"""pbrt-style lens tables (.dat, text): read into our lens-file dictionary and written from a `Lens`.

One row per surface, from the object side: radius, thickness (to the next row's surface), index of
refraction n_d of the medium after it (0 or 1: air), aperture diameter, all lengths in mm, and an
optional fifth column, the Abbe number V_d (0: none given). Rows are whitespace-separated numbers;
`#` starts a comment; a row's comment "glass = model:..." names its model glass (written by us, so
that a model glass is not read back as a catalogue glass of the same n_d and V_d; checked against the
row's n_d). Indices between 0 and 1, negative Abbe numbers and numbers that are not finite are
errors naming the line. The aperture stop is the row of radius 0 in air (pbrt's convention), or the row
named by a `# stop = N` comment (1-based; written by us when the stop is a curved surface, which
pbrt's table cannot mark). Glass: `glass.material_for(n_d, V_d)` — the one catalogue glass that
matches within the printed digits (half a unit of the last one), else a model glass. A last thickness of 0 (pbrt focuses the camera itself) is replaced by the
paraxial back focal distance at the d line, so the image plane is at the focus for an object at
infinity; the object is at infinity and the wavelengths are the F, d and C lines.
"""

from __future__ import annotations

import math
import re
from decimal import Decimal, InvalidOperation

from ..errors import SolasError
from . import glass as glass_mod

_STOP_RE = re.compile(r"^\s*#\s*stop\s*=\s*(\d+)\s*$", re.IGNORECASE)
_GLASS_RE = re.compile(r"^\s*glass\s*=\s*(model:\S+)\s*$", re.IGNORECASE)


def _half_unit(token: str) -> float:
    """Half a unit of the last digit printed in `token` ("1.670" → 5e-4)."""
    try:
        return 0.5 * 10.0 ** Decimal(token).as_tuple().exponent
    except (InvalidOperation, TypeError):
        return 0.0


def _rows(text: str, where: str) -> tuple[list[list[float]], int | None, list[tuple[float, float]], dict[int, str]]:
    """The rows' numbers (checked: `_check_row`), the stop row named by a comment (or None), per row
    half a unit of the last printed digit of n_d and V_d, and the glasses named by row comments
    ("# glass = model:n_d/V_d", written for model glasses; row index from 0)."""
    rows, stop, digits, named = [], None, [], {}
    for number, raw in enumerate(text.splitlines(), start=1):
        m = _STOP_RE.match(raw)
        if m:
            stop = int(m.group(1))
        line, _, comment = raw.partition("#")
        line = line.split()
        if not line:
            continue
        try:
            values = [float(v) for v in line]
        except ValueError:
            raise SolasError(f"{where}: line {number}: {raw.strip()!r} is not a row of numbers") from None
        if len(values) not in (4, 5):
            raise SolasError(
                f"{where}: line {number} has {len(values)} numbers; a row is radius, thickness, "
                "index, aperture diameter (mm) and optionally the Abbe number"
            )
        _check_row(values, f"{where}: line {number}")
        g = _GLASS_RE.match(comment)
        if g:
            named[len(rows)] = g.group(1)
        rows.append(values)
        digits.append((_half_unit(line[2]), _half_unit(line[4]) if len(line) == 5 else 0.0))
    if not rows:
        raise SolasError(f"{where}: no rows; a lens table holds radius, thickness, index, aperture per surface")
    return rows, stop, digits, named


def _check_row(values: list[float], where: str) -> None:
    """SolasError unless every number is finite, the index is 0 or 1 (air) or above 1 (a glass), and
    V_d, when given, is 0 (none) or positive."""
    names = ("radius", "thickness", "index", "aperture", "Abbe number")
    bad = next((n for n, v in zip(names, values) if not math.isfinite(v)), None)
    if bad:
        raise SolasError(f"{where}: the {bad} is {values[names.index(bad)]}; a row holds finite numbers")
    if values[2] not in (0.0, 1.0) and values[2] <= 1.0:
        raise SolasError(f"{where}: index {values[2]:g} is neither air (0 or 1) nor a glass (above 1)")
    if len(values) == 5 and values[4] < 0:
        raise SolasError(f"{where}: Abbe number {values[4]:g} is negative; give a positive V_d or 0 for none")


def _back_focus(rows: list[list[float]], indices: list[float]) -> float:
    """Paraxial distance (mm) from the last surface to the focus of a collimated beam, with the index
    after each surface at the d line (a y-nu marginal ray trace)."""
    y, nu, n = 1.0, 0.0, 1.0
    for k, ((radius, thickness, *_), n_after) in enumerate(zip(rows, indices)):
        if radius:
            nu -= y * (n_after - n) / radius
        n = n_after
        if k < len(rows) - 1:
            y += thickness * nu / n
    if nu >= 0:
        raise SolasError("the lens table has no positive power: its last thickness 0 cannot be replaced by a focus")
    return -y * n / nu


def _check_named(material: str, nd: float, where: str) -> None:
    """SolasError unless the glass a row's comment names exists and has the row's n_d (an edited row
    whose comment was left behind is not read as the old glass)."""
    try:
        have = glass_mod.resolve(material).index(glass_mod.LINE_D)
    except SolasError as exc:
        raise SolasError(f"{where}: its glass comment {material!r}: {exc}") from None
    if not abs(have - nd) <= 1e-6 * nd:
        raise SolasError(
            f"{where}: n_d {nd!r} differs from its glass comment {material!r} (n_d {have:.7g}); "
            "correct the row or remove the comment"
        )


def read_spec(text: str, where: str) -> dict:
    """The lens-file dictionary of a .dat text; `where` names it in messages."""
    rows, stop, digits, named = _rows(text, where)
    if stop is None:
        air = [i for i, r in enumerate(rows) if r[0] == 0 and r[2] <= 1 and (i == 0 or rows[i - 1][2] <= 1)]
        if len(air) != 1:
            raise SolasError(
                f"{where}: {len(air)} rows of radius 0 in air; exactly one must mark the aperture "
                "stop (or name it with a '# stop = N' comment)"
            )
        stop = air[0] + 1
    if not 1 <= stop <= len(rows):
        raise SolasError(f"{where}: stop = {stop} names no row (1..{len(rows)})")
    surfaces = []
    for i, ((radius, thickness, index, aperture, *abbe), (nd_tol, vd_tol)) in enumerate(zip(rows, digits), start=1):
        vd = abbe[0] if abbe and abbe[0] > 0 else None
        material = named.get(i - 1) or glass_mod.material_for(index, vd, nd_tol=nd_tol, vd_tol=vd_tol)
        if i - 1 in named:
            _check_named(material, index, f"{where}: row {i}")
        surfaces.append(
            {"label": f"row {i}", "radius": radius, "thickness": thickness, "diameter": aperture, "material": material}
        )
    surfaces[stop - 1]["stop"] = True
    if surfaces[-1]["thickness"] == 0:
        indices = [glass_mod.resolve(s["material"]).index(glass_mod.LINE_D) for s in surfaces]
        surfaces[-1]["thickness"] = _back_focus(rows, indices)
    return {
        "object": {"distance": "infinity"},
        "surface": surfaces,
        "wavelengths_nm": [glass_mod.LINE_F, glass_mod.LINE_D, glass_mod.LINE_C],
    }


def check_steps(lens, where: str, then: str) -> None:
    """SolasError naming the first of `lens`'s overlaps (`Lens.overlaps`: a negative step, faces that cross),
    `then` said after it: pbrt's RealisticCamera drops a ray whose step to the next element is negative, so
    no .dat table holds such a lens, whether written (`dumps`) or read (`check_read`)."""
    if lens.overlaps:
        raise SolasError(
            f"{where}: {lens.overlaps[0].split(': traced')[0]}; pbrt's realistic camera steps only "
            f"forward from surface to surface, so {then}"
        )


def check_read(lens) -> None:
    """A lens read from a .dat table: refused where pbrt cannot trace it (`check_steps`), a damaged table
    (as pbrt's unscaled dgauss.dat and telephoto.dat, whose spacing column is one row off)."""
    check_steps(
        lens,
        f"lens file {lens.source}",
        "pbrt cannot trace this table: a damaged table (a thickness column one row off reads so)",
    )


def dumps(lens) -> str:
    """The .dat text of `lens` (a `solas_mi.optics.lens.Lens`, object at infinity, spherical surfaces):
    five columns, n_d and V_d of each glass from its dispersion formula (0 for air)."""
    if not lens.at_infinity:
        raise SolasError(f"lens {lens.name}: a .dat lens table holds no object distance; its object is at infinity")
    ideal = [i for i, s in enumerate(lens.surfaces, start=1) if s.ideal]
    if ideal:
        raise SolasError(
            f"lens {lens.name}: surface {ideal[0]} is an ideal thin lens (focal_length); a .dat lens "
            "table holds spheres only; save it as .toml or .zmx"
        )
    check_steps(lens, f"lens {lens.name}", "a .dat lens table cannot hold it; save it as .toml or .zmx")
    bad = [i for i, s in enumerate(lens.surfaces, start=1) if not s.is_sphere]
    if bad:
        raise SolasError(f"lens {lens.name}: surface {bad[0]} is aspheric; a .dat lens table holds spheres only")
    from .lens_toml import text

    lines = [f"# {text(lens.name)}: lens table written by solas-mi", "# radius thickness n_d aperture V_d (mm)"]
    flat_air = [
        i
        for i, s in enumerate(lens.surfaces)
        if s.radius == 0 and s.glass.kind == "air" and (i == 0 or lens.surfaces[i - 1].glass.kind == "air")
    ]
    if flat_air != [lens.stop_index]:
        lines.append(f"# stop = {lens.stop_index + 1}")
    for s in lens.surfaces:
        if s.glass.kind == "air":
            nd, vd = 1.0, 0.0
        elif s.glass.kind == "model" and s.glass.coefficients[1][0] == 0:
            nd, vd = s.glass.coefficients[0][0], 0.0
        else:
            nd, vd = s.glass.abbe()
        row = " ".join(repr(float(v)) for v in (s.radius, s.thickness, nd, s.diameter, vd))
        # a model glass is named, so that it is not read back as a catalogue glass of the same n_d / V_d
        lines.append(f"{row}  # glass = {s.glass.name}" if s.glass.kind == "model" else row)
    return "\n".join(lines) + "\n"
