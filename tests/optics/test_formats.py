"""Lens files in other formats: Zemax .zmx and pbrt .dat written by us and read back give the same
lens; hand-written files as other tools write them are read, or refused naming what is wrong."""

import math

import pytest

from solas_mi import Lens, SolasError
from solas_mi.cli import main
from solas_mi.optics.paraxial import paraxial

# A sequential Zemax file as OpticStudio writes it (abridged): a BK7 singlet with an even-asphere
# rear face, lengths in cm, three wavelengths, angle fields 0, 7, 10 deg.
ZMX = """VERS 190513 80 123457 L123457
MODE SEQ
NAME Aspheric singlet
UNIT CM X W X CM MR CPMM
ENPD 2
FTYP 0 0 3 3 0 0 0
XFLN 0 0 0 0 0 0 0 0 0 0 0 0
YFLN 0 7 10 0 0 0 0 0 0 0 0 0
WAVM 1 0.4861327 1
WAVM 2 0.5875618 1
WAVM 3 0.6562725 1
PWAV 2
SURF 0
  TYPE STANDARD
  CURV 0.0 0 0 0 0 ""
  DISZ INFINITY
SURF 1
  STOP
  TYPE STANDARD
  CURV 0.2 0 0 0 0 ""
  DISZ 0.6
  GLAS {glass} 0 0 1.5168 64.17 0 0 0 0 0 0
  DIAM 1.2 1 0 0 1 ""
SURF 2
  TYPE EVENASPH
  CURV -0.02 0 0 0 0 ""
  PARM 1 0
  PARM 2 1e-3
  PARM 3 -2e-5
  DISZ 9.2
  DIAM 1.2 1 0 0 1 ""
  CONI -1.5
SURF 3
  TYPE STANDARD
  CURV 0.0 0 0 0 0 ""
  DISZ 0
  DIAM 0.5 0 0 0 1 ""
"""


def surfaces(lens: Lens) -> list[tuple]:
    return [(s.curvature, s.thickness, s.diameter, s.glass.name, s.stop, s.conic, s.aspheric) for s in lens.surfaces]


def same_lens(a: Lens, b: Lens) -> None:
    assert len(a.surfaces) == len(b.surfaces)
    for sa, sb in zip(surfaces(a), surfaces(b)):
        assert sa[3:5] == sb[3:5]
        assert sa[:3] == pytest.approx(sb[:3], rel=1e-12, abs=1e-15)
        assert sa[5] == pytest.approx(sb[5], rel=1e-12) and sa[6] == pytest.approx(sb[6], rel=1e-12)
    for w in (486.1327, 587.5618):
        assert paraxial(b, w).efl_mm == pytest.approx(paraxial(a, w).efl_mm, rel=1e-9)


@pytest.mark.parametrize("name", ["solas-doublet", "cooke-triplet"])
@pytest.mark.parametrize("ext", [".zmx", ".dat", ".toml"])
def test_round_trip(name, ext, tmp_path):
    lens = Lens.load(name)
    back = Lens.load(lens.save(tmp_path / f"lens{ext}"))
    same_lens(lens, back)
    assert back.stop_index == lens.stop_index
    if ext != ".dat":  # a .dat table has no object distance, field or wavelengths
        assert back.wavelengths_nm == lens.wavelengths_nm and back.field_deg == lens.field_deg
        assert back.image_diameter == pytest.approx(lens.image_diameter)


def test_aspheric_round_trip_and_units(tmp_path):
    (tmp_path / "singlet.zmx").write_text(ZMX.format(glass="N-BK7"))
    lens = Lens.load(tmp_path / "singlet.zmx")
    s1, s2 = lens.surfaces
    # the system aperture (ENPD 2 cm) sizes the stop, surface 1, as in Zemax: its DIAM 1.2 cm is not the pupil
    assert (s1.radius, s1.thickness, s1.diameter, s1.stop) == pytest.approx((50.0, 6.0, 20.0, True))
    assert s2.radius == pytest.approx(-500.0) and s2.conic == -1.5
    assert s2.aspheric == pytest.approx((1e-3 * 10**-3, -2e-5 * 10**-5))  # A4 in cm⁻³ → mm⁻³, A6 in cm⁻⁵ → mm⁻⁵
    assert lens.wavelengths_nm == pytest.approx((486.1327, 587.5618, 656.2725)) and lens.field_deg == 10.0
    assert lens.image_diameter == pytest.approx(10.0) and math.isinf(lens.object_distance)
    for ext in (".zmx", ".toml"):
        same_lens(lens, Lens.load(lens.save(tmp_path / f"again{ext}")))
    with pytest.raises(SolasError, match=r"surface 2 is aspheric; a .dat lens table holds spheres only"):
        lens.save(tmp_path / "singlet.dat")


def test_finite_object_in_glass_round_trip(doublet_spec, tmp_path):
    doublet_spec["object"] = {"distance": 800.0, "material": "model:1.333/55"}
    lens = Lens.from_dict(doublet_spec)
    back = Lens.load(lens.save(tmp_path / "water.zmx"))
    same_lens(lens, back)
    assert back.object_distance == 800.0 and back.object_glass.name == "model:1.333/55"


def test_utf16_file_as_opticstudio_writes_it(tmp_path):
    (tmp_path / "utf16.zmx").write_bytes(ZMX.format(glass="N-BK7").encode("utf-16"))
    (tmp_path / "ascii.zmx").write_text(ZMX.format(glass="N-BK7"))
    same_lens(Lens.load(tmp_path / "ascii.zmx"), Lens.load(tmp_path / "utf16.zmx"))


def test_unknown_glass_is_named(tmp_path):
    (tmp_path / "other.zmx").write_text(ZMX.format(glass="S-BSL99"))
    with pytest.raises(SolasError, match=r"other.zmx: surface 1 \(SURF 1\): unknown glass 'S-BSL99'"):
        Lens.load(tmp_path / "other.zmx")


@pytest.mark.parametrize(
    "name,key",
    [
        ("S-LAH59", "OHARA:S-LAH59"),
        ("TAFD5G", "HOYA:TAFD5G"),
        ("TAFD5F", "HOYA:TAFD5F"),
        ("H-ZF52", "CDGM:H-ZF52"),
        ("S-BSL7", "OHARA:S-BSL7"),
    ],
)
def test_other_vendors_glass_names_load(name, key, tmp_path):
    (tmp_path / "vendor.zmx").write_text(ZMX.format(glass=name))
    lens = Lens.load(tmp_path / "vendor.zmx")
    assert lens.surfaces[0].glass.name == key
    same_lens(lens, Lens.load(lens.save(tmp_path / "again.zmx")))


def test_gcat_picks_the_vendor_of_a_shared_name(tmp_path):
    """ "F2" is SCHOTT's, CDGM's and HIKARI's: the file's GCAT line says which; without one, SCHOTT, as
    OpticStudio's default (stated in the description); a GCAT naming none of them leaves it ambiguous."""
    path = tmp_path / "f2.zmx"
    path.write_text(ZMX.format(glass="F2"))
    lens = Lens.load(path)
    assert lens.surfaces[0].glass.name == "SCHOTT:F2" and lens.catalogues == ("SCHOTT",)
    assert "SCHOTT" in lens.description and "default" in lens.description
    path.write_text(ZMX.format(glass="F2").replace("ENPD 2", "ENPD 2\nGCAT OHARA"))
    with pytest.raises(SolasError, match=r"glass name 'F2' is ambiguous: it matches CDGM:F2, HIKARI:F2, SCHOTT:F2"):
        Lens.load(path)
    for gcat, key in [("SCHOTT", "SCHOTT:F2"), ("OHARA CDGM", "CDGM:F2"), ("NIKON HOYA", "HIKARI:F2")]:
        path.write_text(ZMX.format(glass="F2").replace("ENPD 2", f"ENPD 2\nGCAT {gcat}"))
        assert Lens.load(path).surfaces[0].glass.name == key
    lens = Lens.load("solas-doublet")  # written with GCAT SCHOTT and GLAS F2, read back as SCHOTT:F2
    text = tmp_path / "doublet.zmx"
    lens.save(text)
    assert "GCAT SCHOTT" in text.read_text() and "GLAS F2 " in text.read_text()
    assert [s.glass.name for s in Lens.load(text).surfaces][:2] == ["SCHOTT:N-BK7", "SCHOTT:F2"]


def test_model_glass_and_refusals(tmp_path):
    path = tmp_path / "model.zmx"
    path.write_text(ZMX.format(glass="___BLANK 1 0 1.5168 64.17 0 0 0 0 0 0 ;"))
    assert Lens.load(path).surfaces[0].glass.name == "model:1.5168/64.17"
    for old, new, match in [
        (
            "TYPE EVENASPH",
            "TYPE SZERNSAG",
            r"SURF 2 \(line 24\): surface TYPE SZERNSAG is not "
            r"supported; allowed: STANDARD, EVENASPH",
        ),
        ("PARM 1 0", "PARM 1 0.01", r"PARM 1 \(the r² term\) = 0.01"),
        ("UNIT CM", "UNIT FT", r"UNIT 'FT' is not supported"),
        ("GLAS N-BK7", "GLAS MIRROR", r"GLAS MIRROR: mirrors are not supported"),
    ]:
        path.write_text(ZMX.format(glass="N-BK7").replace(old, new))
        with pytest.raises(SolasError, match=match):
            Lens.load(path)


def test_pbrt_table_with_and_without_abbe_numbers(tmp_path):
    """pbrt's own rows: four columns, air written 1 or 0, the stop a row of radius 0, last thickness 0
    (focused by the reader at the paraxial focus)."""
    path = tmp_path / "table.dat"
    path.write_text("# radius thickness n aperture\n50.0 6.0 1.5168 24.0\n-500.0 2.0 1 24.0\n0 0 0 10.0\n")
    lens = Lens.load(path)
    assert lens.stop_index == 2 and lens.surfaces[0].glass.name == "model:1.5168"
    assert paraxial(lens, 587.5618).image_offset_mm == pytest.approx(0.0, abs=1e-9)
    path.write_text("50.0 6.0 1.5168 24.0 64.17\n-500.0 2.0 1 24.0 0\n0 20 0 10.0 0\n0 30 0 10.0 0\n")
    with pytest.raises(SolasError, match=r"2 rows of radius 0 in air; exactly one must mark the aperture stop"):
        Lens.load(path)
    path.write_text("50.0 6.0 1.5168 24.0 64.17\n-500.0 2.0 1 24.0 0\n0 40 0 10.0 0\n")
    assert Lens.load(path).surfaces[0].glass.name == "SCHOTT:N-BK7"  # n_d, V_d of the catalogue's N-BK7
    # 3 decimals that several vendors' glasses share within the rounding: a model glass
    path.write_text("50.0 6.0 1.670 24.0 47.1\n-500.0 2.0 1 24.0 0\n0 40 0 10.0 0\n")
    assert Lens.load(path).surfaces[0].glass.name == "model:1.67/47.1"


def test_lens_convert_command(tmp_path, capsys):
    out = tmp_path / "triplet.zmx"
    assert main(["lens", "convert", "cooke-triplet", "-o", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    same_lens(Lens.load("cooke-triplet"), Lens.load(out))
    assert main(["lens", "convert", "cooke-triplet", "-o", str(tmp_path / "x.txt")]) != 0
    assert "unknown extension '.txt'; allowed: .toml, .zmx, .dat" in capsys.readouterr().err
    assert not (tmp_path / "x.txt").exists()
