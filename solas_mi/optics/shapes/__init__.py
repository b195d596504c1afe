"""Surface shapes as geometry objects (`base.Shape`: sag and unit normal at (x, y), ray intersection, the
vertex curvature about the axis when it has one, its lens-file entries), one module per kind, registered
once in `KINDS` (a `solas_mi.registry.Registry`). Each entry's function is the kind's class; its extras:
`keys`, the lens file's entries of the kind (in the class's field order), `lists` (those of them that
are lists of numbers) and `symmetric` (rotationally symmetric about the axis).

The rotationally symmetric kinds are what a [[surface]] row with
`radius`, `conic`, `aspheric`, `qbfs` and `focal_length` describes (`rotational` builds one from a
`Surface`); the others are named in the row by `kind` (`NAMED`) and held by the surface whole
(`Surface.form`). Lengths in mm.
"""

from __future__ import annotations

from dataclasses import fields

from ...registry import Registry
from .asphere import EvenAsphere
from .base import Shape
from .biconic import Biconic
from .conic import Conic
from .cylinder import Cylinder
from .ideal_lens import IdealLens
from .plane import Plane
from .qtype import Qbfs
from .toroid import Toroid

KINDS = Registry("surface kind", default="conic")
"""The surface kinds by name (a `solas_mi.registry.Registry`): each entry's function is the kind's
`base.Shape` class; `keys`, `lists` and `symmetric` its extras (the module docstring)."""
_SUMMARIES: dict[type[Shape], tuple[str, str]] = {  # summary, reference
    Plane: ("flat: radius 0", ""),
    Conic: ("a sphere (conic 0) or conic of revolution: radius, conic", ""),
    EvenAsphere: ("a conic plus even terms A4 r^4 + A6 r^6 + ...: aspheric", ""),
    Qbfs: ("a conic plus Forbes' Qbfs departure: qbfs, norm_radius", "G. W. Forbes, Opt. Express 15, 5218 (2007)"),
    IdealLens: ("an ideal thin lens of focal_length (mm), flat", "OpticStudio's PARAXIAL"),
    Toroid: (
        "named by kind: the y-z curve (radius, conic, terms_y on y^2, y^4, ...) rotated at radius_rotation (0: none)",
        "OpticStudio's TOROIDAL; optiland's ToroidalGeometry",
    ),
    Cylinder: ("named by kind: curved in y-z (radius, conic), straight along x", "OpticStudio's TOROIDAL, PARM 1 0"),
    Biconic: (
        "named by kind: z = (cx x^2 + cy y^2)/(1 + sqrt(1 - (1+kx) cx^2 x^2 - (1+ky) cy^2 y^2)): radius, conic "
        "(y), radius_x, conic_x",
        "OpticStudio's BICONICX, without its polynomial terms",
    ),
}
for _cls, (_summary, _reference) in _SUMMARIES.items():  # each a dataclass (mypy sees only type[Shape])
    KINDS.register(
        _cls.kind,
        _cls,
        summary=_summary,
        reference=_reference,
        keys=tuple(f.name for f in fields(_cls)),  # type: ignore[arg-type]
        lists=tuple(f.name for f in fields(_cls) if f.type == "tuple[float, ...]"),  # type: ignore[arg-type]
        symmetric=_cls.symmetric,
    )
NAMED = tuple(name for name, entry in KINDS.items() if not entry.extra["symmetric"])
"""The kinds a [[surface]] row names by `kind` (the others its keys tell)."""
KEYS = tuple(dict.fromkeys(key for _, entry in KINDS.items() for key in entry.extra["keys"]))
"""Every lens-file entry any kind takes, in the order first registered."""


def rotational(surface) -> Shape:
    """The rotationally symmetric shape a `Surface`'s radius, conic, aspheric, qbfs and focal_length say."""
    if surface.focal_length is not None:
        return IdealLens(surface.focal_length)
    if any(surface.qbfs):
        return Qbfs(surface.radius, surface.conic, surface.aspheric, surface.qbfs, surface.norm_radius)
    if any(surface.aspheric):
        return EvenAsphere(surface.radius, surface.conic, surface.aspheric)
    if surface.radius == 0.0 and surface.conic == 0.0:
        return Plane()
    return Conic(surface.radius, surface.conic)


__all__ = ["KINDS"]
