"""The ideal thin lens: a surface with `focal_length` (mm; Zemax's TYPE PARAXIAL, PARM 1 the focal
length). Flat, it bends every ray by n'·t' = n·t − h/f, t the direction tangents (dx/dz, dy/dz), h the
height where the ray meets it, n and n' the indices before and after (a change of medium allowed, as
in Zemax and optiland's thin lens). The map is linear in the tangents, so it images every object point
to one point, finite conjugates too: an object s before it (n/s + n'/s' = 1/f) lands s' behind it.

Its optical path: the tracer adds δ = n' g(h, t', w') − n g(h, t, w) (`deflect`), where w and w' are the
signed inverse distances to the object point whose pencil it images and to that point's image
(w' = (n w + 1/f)/n'), and g(h, t, w) = σ(|Q| − |Q − h|) for the point Q where the ray's line meets the
plane z = 1/w (σ its sign). Every ray of the pencil from that point then reaches its image with the
same optical path: the pencil is imaged without aberration (Zemax's OPD mode 1, "perfect"). w is the
paraxial image of the lens's object by the surfaces before the ideal lens, at the primary wavelength
(`paraxial.ideal_conjugates`; 0 at infinity; None where that point lies on the lens, as a virtual object
or an intermediate image there: every ray of its pencil meets the lens at one point h, and δ takes g's limit
there, the constant (n' − n)|h|), so δ is exact for a pencil that meets the ideal lens
stigmatic at that point (an ideal lens in front, or only ideal lenses before it, at any object
distance) and approximate for a pencil already aberrated by real surfaces or at other wavelengths
focused elsewhere. Zemax's OPD mode 0 (integrate the path over the pupil) is read as perfect too, and
the lens's description says so (`zemax`). The functions work on any array type given its `sqrt`.
"""

from __future__ import annotations

import math

from ..errors import SolasError

INTEGRATE = "OPD mode integrate (PARM 2 0) read as perfect (OPD mode 1): its pencil is imaged without aberration"


def check(value, ident: str, flat: bool) -> float:
    """A lens file's `focal_length` entry, checked: a finite nonzero number (mm) on a `flat` surface."""
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) or value == 0:
        raise SolasError(
            f"{ident}: focal_length = {value!r} must be a finite nonzero number (mm, negative for a "
            "diverging ideal lens)"
        )
    if not flat:
        raise SolasError(
            f"{ident}: an ideal thin lens (focal_length) is flat: radius must be 0 and conic, aspheric and qbfs absent"
        )
    return float(value)


def from_zemax(parameters: dict[int, float], scale: float, ident: str) -> dict:
    """The lens-file row entries of a Zemax PARAXIAL surface of PARM `parameters` (lengths times `scale`):
    flat (its CURV is ignored, as Zemax does), the focal length (PARM 1) and the OPD mode (PARM 2)."""
    if not parameters.get(1):
        raise SolasError(f"{ident}: PARAXIAL focal length (PARM 1) {parameters.get(1, 0.0):g} must be nonzero")
    return {"radius": 0.0, "focal_length": parameters[1] * scale, "opd_mode": parameters.get(2, 0.0)}


def to_zemax(focal_length: float | None) -> list[str]:
    """The PARM lines of a Zemax PARAXIAL surface: the focal length (mm) and OPD mode 1 (perfect); none
    for a surface without one."""
    return [] if focal_length is None else [f"  PARM 1 {float(focal_length)!r}", "  PARM 2 1"]


def zemax_notes(rows: list[dict], description: str | None) -> dict:
    """{"description": …} naming the PARAXIAL rows whose OPD mode (PARM 2) is not 1, read as perfect,
    after `description`; {} when there are none."""
    notes = [f"ideal lens {r['label']}: {INTEGRATE}" for r in rows if r.get("opd_mode", 1) != 1]
    return {"description": "; ".join(filter(None, (description, *notes)))} if notes else {}


def metadata(lens) -> dict:
    """{"ideal_lens_path": what the optical path of `lens`'s ideal lenses means}, {} when it has none: exact
    where only ideal lenses and non-dispersive media come before one, else approximate (module docstring)."""
    ideal = [k for k, s in enumerate(lens.surfaces) if s.ideal]
    if not ideal:
        return {}
    media = (lens.object_glass, *(s.glass for s in lens.surfaces))
    rough = [
        k + 1
        for k in ideal
        if any(g.dispersive for g in media[: k + 1])
        or any(not s.ideal and media[j + 1] != media[j] for j, s in enumerate(lens.surfaces[:k]))
    ]
    where = ", ".join(str(k + 1) for k in ideal)
    return {
        "ideal_lens_path": f"surface {where}: ideal thin lens, its optical path the one that images its pencil "
        "perfectly (Zemax's OPD mode 1), "
        + (
            "exact"
            if not rough
            else f"approximate at surface {', '.join(map(str, rough))}: the pencil it meets is aberrated by the surfaces "
            "before it, or focused elsewhere at other wavelengths, and its path is the perfect one for the "
            "paraxial conjugate at the primary wavelength"
        )
    }


def deflect(x, y, d, n, n_after, inv_f, w, sqrt):
    """Directions after an ideal lens of power `inv_f` (1/mm) of rays meeting it at (x, y) (its vertex
    frame) with unit directions `d` (dz > 0) from index `n` into `n_after`, and the optical path δ it
    adds for the pencil from the point at signed inverse distance `w` (None: a point on the lens; module
    docstring)."""
    dx, dy, dz = d
    tx, ty = dx / dz, dy / dz
    ux, uy = (n * tx - x * inv_f) / n_after, (n * ty - y * inv_f) / n_after
    if w is None:  # the pencil's point on the lens: g → |h| for the rays in and out, a constant per pencil
        delta = (n_after - n) * sqrt(x * x + y * y)
    else:
        delta = n_after * _pencil_path(x, y, ux, uy, (n * w + inv_f) / n_after, sqrt) - n * _pencil_path(
            x, y, tx, ty, w, sqrt
        )
    inv = 1.0 / sqrt(ux * ux + uy * uy + 1.0)
    return (ux * inv, uy * inv, inv), delta


def _pencil_path(x, y, tx, ty, w, sqrt):
    """g = σ(|Q| − |Q − h|) for Q = (h + z t, z) on the line through h = (x, y, 0) of tangents t, z = 1/w:
    (2 t·h + w|h|²)/(√(|t + w h|² + 1) + √(|t|² + 1)), free of cancellation, h·d at w = 0 (d the unit
    direction of t: a point at infinity)."""
    ax, ay = tx + w * x, ty + w * y
    return (2.0 * (tx * x + ty * y) + w * (x * x + y * y)) / (
        sqrt(ax * ax + ay * ay + 1.0) + sqrt(tx * tx + ty * ty + 1.0)
    )


__all__ = ["check", "deflect", "metadata", "from_zemax", "to_zemax", "zemax_notes", "INTEGRATE"]
