"""Derived lens data cannot go stale: paraxial data are memoised by the lens's content, so a lens
changed with `dataclasses.replace` or `focused` always gets its own data."""

import math
from dataclasses import fields, replace

import pytest

from solas_mi.optics import glass
from solas_mi.optics.focus import focused
from solas_mi.optics.lens import Lens
from solas_mi.optics.paraxial import paraxial


def fresh(lens: Lens) -> Lens:
    """The same prescription as a newly built Lens value (no state carried over from `lens`)."""
    return Lens(**{f.name: getattr(lens, f.name) for f in fields(Lens) if f.compare})


def test_a_refocused_lens_has_its_own_image_plane(doublet):
    paraxial(doublet)  # the data of the lens as loaded, computed first
    near = focused(doublet, 20e3)
    assert paraxial(near).image_z_mm == near.image_z  # the refocused lens's own plane
    assert paraxial(near) == paraxial(fresh(near))
    assert paraxial(near).image_z_mm != paraxial(doublet).image_z_mm


def test_a_replaced_object_distance_gets_fresh_data(doublet):
    paraxial(doublet)
    moved = replace(doublet, object_distance=140e3)
    assert paraxial(moved) is not paraxial(doublet)
    assert paraxial(moved).focus_z_mm != paraxial(doublet).focus_z_mm
    assert paraxial(moved) == paraxial(fresh(moved))


def _last_thickness(lens):
    return replace(
        lens, surfaces=lens.surfaces[:-1] + (replace(lens.surfaces[-1], thickness=lens.surfaces[-1].thickness + 0.5),)
    )


def _first_radius(lens):
    return replace(
        lens, surfaces=(replace(lens.surfaces[0], radius=lens.surfaces[0].radius * 1.01),) + lens.surfaces[1:]
    )


def _first_glass(lens):
    other = glass.resolve("N-SF5")
    return replace(lens, surfaces=(replace(lens.surfaces[0], glass=other, material=other.name),) + lens.surfaces[1:])


def _object_glass(lens):
    return replace(lens, object_glass=glass.resolve("model:1.1"))


CHANGES = {
    "object distance": lambda lens: replace(lens, object_distance=5e3),
    "image plane": _last_thickness,
    "a radius": _first_radius,
    "a glass": _first_glass,
    "the object space's glass": _object_glass,
    "the field": lambda lens: replace(lens, field_deg=lens.field_deg + 1.0),
    "the design wavelengths": lambda lens: replace(lens, wavelengths_nm=(486.0, 587.6, 656.0)),
}


@pytest.mark.parametrize("change", CHANGES)
def test_replacing_any_optical_field_gives_fresh_data(doublet, change):
    before = paraxial(doublet)
    changed = CHANGES[change](doublet)
    assert changed != doublet and hash(changed) != hash(doublet)
    assert paraxial(changed) == paraxial(fresh(changed))
    assert paraxial(changed) != before
    assert paraxial(doublet) == before  # the original keeps its own


def test_equal_lenses_share_their_data(doublet):
    assert paraxial(fresh(doublet)) is paraxial(doublet)
    assert math.isfinite(paraxial(doublet).efl_mm)
