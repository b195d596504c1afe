"""What a lens's metadata says of its unusual parts, one entry each where present: a virtual object
(`virtual_object`), ideal thin lenses (`ideal`), surfaces that overlap (`overlap`), coatings and the
iris (`coating`), a temperature or pressure other than 20 °C and 101.325 kPa (`thermal`), paraxial data about
the nominal axis of a lens whose breaks decentre or tilt (`placement`). `lens info` and PSF
metadata carry the same entries."""

from __future__ import annotations

from . import coating, ideal, overlap, placement, thermal, virtual_object


def metadata(lens) -> dict:
    """The notes of `lens`'s virtual object, ideal lenses, overlaps, coatings and iris, environment and
    placements ({} for an ordinary lens)."""
    return {
        **virtual_object.metadata(lens),
        **ideal.metadata(lens),
        **overlap.metadata(lens),
        **coating.metadata(lens),
        **thermal.metadata(lens),
        **placement.metadata(lens),
    }


__all__ = ["metadata"]
