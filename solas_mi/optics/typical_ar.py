"""The typical anti-reflection coating of a lens whose source states none: one quarter-wave layer of MgF₂ at
550 nm on every air–glass surface (`TYPICAL_AR`), the catalogue lens makers' standard single-layer AR (e.g.
Edmund Optics' "MgF₂ @ 550 nm" and Thorlabs' "uncoated or MgF₂" lens options; Macleod, *Thin-Film Optical
Filters*, ch. 3: the single-layer quarter-wave AR, MgF₂ the usual material). Cemented interfaces stay bare
(glass to glass reflects a few 1e-4 and no coating is put there).

The shipped lenses state their coatings as their sources give them, none (bare glass, Fresnel's equations), so
that their figures, hashes and mesh renders stay those of their sources; `lens info` states that and their
on-axis transmittance with this typical coating beside it (`note`), and `with_typical_ar` (`lens convert
--typical-ar`) gives the lens coated so.
"""

from __future__ import annotations

from dataclasses import replace

from .coating import coating_from_table
from .glass import AIR
from .lens import Lens

TYPICAL_AR = {"kind": "quarter_wave", "material": "MgF2", "design_nm": 550.0}


def air_glass(lens: Lens) -> list[int]:
    """The surfaces (0-based) between air and glass: a change of medium with air on one side."""
    media = [lens.object_glass] + [s.glass for s in lens.surfaces]
    return [k for k in range(len(lens.surfaces)) if media[k] != media[k + 1] and AIR in (media[k], media[k + 1])]


def with_typical_ar(lens: Lens) -> Lens:
    """`lens` with `TYPICAL_AR` on each air–glass surface that states no coating of its own.

    Examples
    --------
    >>> from solas_mi import Lens
    >>> coated = with_typical_ar(Lens.load("cooke-triplet"))
    >>> sum(s.coating is not None for s in coated.surfaces), coated.hash != Lens.load("cooke-triplet").hash
    (6, True)
    """
    coating = coating_from_table(TYPICAL_AR, "the typical AR coating")
    bare = [k for k in air_glass(lens) if lens.surfaces[k].coating is None]
    if not bare:  # every air-glass surface states its own: nothing added, the name stays
        return lens
    surfaces = list(lens.surfaces)
    for k in bare:
        surfaces[k] = replace(surfaces[k], coating=coating)
    return replace(lens, name=f"{lens.name} (typical AR)", surfaces=tuple(surfaces))


def note(lens: Lens) -> dict:
    """What `lens info` says of a lens that states no coating ({} for one that does): that its surfaces are bare,
    and its on-axis transmittance bare and with `TYPICAL_AR`."""
    from .coating import metadata

    if any(s.coating is not None for s in lens.surfaces) or not air_glass(lens):
        return {}
    coated = metadata(with_typical_ar(lens))["coatings"]
    typical = coated[coated.rindex("; on-axis") + 2 :]
    return {
        "coatings": f"none stated (bare glass, Fresnel's equations); with a typical single-layer AR, "
        f"{TYPICAL_AR['material']} a quarter wave at {TYPICAL_AR['design_nm']:g} nm on its {len(air_glass(lens))} "
        f"air-glass surfaces: {typical}"
    }
