import math
import re

import pytest

from solas_mi import Lens, SolasError, paraxial


def test_load_by_name_and_path(doublet):
    again = Lens.load(doublet.source)
    assert again.hash == doublet.hash
    assert [s.radius for s in doublet.surfaces] == [92.847, -30.716, -78.197, 0.0]
    assert doublet.surfaces[0].glass.name == "SCHOTT:N-BK7"
    assert doublet.stop_index == 3 and math.isinf(doublet.object_distance)
    assert doublet.image_z == pytest.approx(6 + 3 + 57.376 + 39.496)


def test_unknown_lens_name():
    with pytest.raises(SolasError, match="unknown lens 'no-such-lens'.*solas-doublet"):
        Lens.load("no-such-lens")


def _bad(spec, match):
    with pytest.raises(SolasError, match=match):
        Lens.from_dict(spec, source="test.toml")


def test_negative_thickness(doublet_spec):
    """A negative air gap loads, as Zemax traces it, and says what overlaps (`test_overlap` checks the optics)."""
    doublet_spec["surface"][2]["thickness"] = -1.0
    notes = Lens.from_dict(doublet_spec, source="test.toml").overlaps
    assert len(notes) == 1
    assert re.match(
        r"surfaces 3 \(Surface 3\) and 4 \(Aperture stop\) overlap across their clear apertures .*"
        r"thickness -1 mm\): traced sequentially, as Zemax does",
        notes[0],
    )


def test_zero_glass_thickness(doublet_spec):
    """Glass of thickness 0 whose faces only touch (here the same face twice) holds no glass and overlaps
    nothing: refused. Where its faces cross (the biconvex element at thickness 0) it is an overlap, traced."""
    doublet_spec["surface"][0]["thickness"] = 0.0
    assert "surfaces 1 (Surface 1) and 2 (Surface 2) cross at" in Lens.from_dict(doublet_spec).overlaps[0]
    doublet_spec["surface"][1]["radius"] = doublet_spec["surface"][0]["radius"]
    _bad(doublet_spec, r"surface 1 \(Surface 1\): thickness 0 mm inside glass BK7")


def test_aperture_larger_than_sphere(doublet_spec):
    doublet_spec["surface"][1]["diameter"] = 62.0
    _bad(doublet_spec, r"surface 2 \(Surface 2\): clear semi-diameter 31 mm is not smaller than \|radius\| 30.716")


def test_crossing_sags(doublet_spec):
    """Faces that cross inside their clear apertures load (Zemax traces them) and are named."""
    assert Lens.from_dict(doublet_spec).overlaps == ()
    doublet_spec["surface"][0]["thickness"] = 2.0  # the biconvex element's edge thickness goes negative
    notes = Lens.from_dict(doublet_spec).overlaps
    assert len(notes) == 1 and notes[0].startswith("surfaces 1 (Surface 1) and 2 (Surface 2) cross at r = ")


def test_missing_stop(doublet_spec):
    del doublet_spec["surface"][3]["stop"]
    _bad(doublet_spec, "no surface is marked as the aperture stop")


def test_unknown_glass_names_surface(doublet_spec):
    doublet_spec["surface"][1]["material"] = "F33"
    _bad(doublet_spec, r"surface 2 \(Surface 2\): unknown glass 'F33'")
    doublet_spec["surface"][1]["material"] = "F3"  # CDGM's and HIKARI's
    _bad(doublet_spec, r"surface 2 \(Surface 2\): glass name 'F3' is ambiguous: it matches CDGM:F3, HIKARI:F3")


def test_wavelength_outside_glass_range(doublet):
    with pytest.raises(SolasError, match="wavelength 200 nm is outside glass SCHOTT:N-BK7"):
        paraxial(doublet, 200.0)


def test_hash_follows_optics_not_labels(doublet_spec):
    a = Lens.from_dict(doublet_spec)
    doublet_spec["surface"][0]["label"] = "renamed"
    assert Lens.from_dict(doublet_spec).hash == a.hash
    doublet_spec["surface"][0]["radius"] = 92.0
    assert Lens.from_dict(doublet_spec).hash != a.hash


@pytest.mark.parametrize(
    "key, value, match",
    [
        ("wavelengths_nm", [], r"wavelengths_nm = \[\] must be a non-empty list"),
        ("wavelengths_nm", ["green"], r"wavelengths_nm = 'green' must be a finite number \(nm\)"),
        ("field_deg", "two", r"field_deg = 'two' must be a finite number \(degrees\)"),
        ("object", 5, r"object = 5 must be a table"),
        ("image", {"diameter": "wide"}, r"image: diameter = 'wide' must be a finite number \(mm\)"),
        ("surface", [], r"no \[\[surface\]\] entries"),
        ("surface", [1, 2], r"surface = \[1, 2\]: each surface must be a table"),
        ("wavelengths_nm", [-531.0], r"wavelengths_nm holds -531; wavelengths must be positive"),
        ("field_deg", 180.0, r"field_deg = 180 must be a half field angle in \[0, 180\) degrees"),
        ("field_deg", -2.0, r"field_deg = -2 must be a half field angle"),
        ("image", {"diameter": -4.0}, r"image diameter -4 mm must be positive"),
    ],
)
def test_malformed_entries(doublet_spec, key, value, match):
    doublet_spec[key] = value
    _bad(doublet_spec, match)


def test_malformed_surface_number(doublet_spec):
    doublet_spec["surface"][0]["radius"] = "92.8"
    _bad(doublet_spec, r"surface 1 \(Surface 1\): radius = '92.8' must be a finite number \(mm\)")


@pytest.mark.parametrize(
    "where, key, value, match",
    [
        (
            "surface",
            "conik",
            -1.0,
            r"surface 1 \(Surface 1\): unknown key conik in the surface table; allowed: label, "
            r"radius, thickness, diameter, material, stop, conic, aspheric",
        ),
        ("lens", "focal", 100.0, r"unknown key focal in the lens table; allowed: name, description"),
        ("object", "angle", 3.0, r"object: unknown key angle in the object table; allowed: distance, material"),
        ("image", "width", 3.0, r"image: unknown key width in the image table; allowed: diameter"),
    ],
)
def test_unknown_keys_are_named(doublet_spec, where, key, value, match):
    table = {"lens": doublet_spec, "surface": doublet_spec["surface"][0]}.get(where) or doublet_spec.setdefault(
        where, {}
    )
    table[key] = value
    _bad(doublet_spec, match)


@pytest.mark.parametrize("value", ["false", 1, "yes"])
def test_stop_must_be_a_boolean(doublet_spec, value):
    doublet_spec["surface"][0]["stop"] = value
    _bad(doublet_spec, rf"surface 1 \(Surface 1\): stop = {value!r} must be true or false")


def test_a_lens_without_power_forms_no_image(doublet_spec):
    """Flat surfaces only: paraxial data is a clear refusal, not an infinite focus with warnings."""
    from solas_mi import paraxial

    for row in doublet_spec["surface"]:
        row["radius"] = 0.0
    lens = Lens.from_dict(doublet_spec)
    with pytest.raises(SolasError, match=r"forms no image at 531 nm: rays from an object point leave it parallel"):
        paraxial(lens, 531.0)


@pytest.mark.parametrize("wavelength", ["green", True, None])
def test_wavelength_must_be_a_number(doublet, wavelength):
    from solas_mi import paraxial

    with pytest.raises(SolasError, match=r"must be a positive number"):
        paraxial(doublet, wavelength) if wavelength is not None else doublet.check_wavelength(wavelength)
