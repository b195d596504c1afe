"""CODE V sequence files (.seq): the shipped lenses re-expressed in CODE V syntax load as the same lens
(EFL, BFD, f/#, real chief rays to 1e-9), and a first-order trace written out here (y–nu, from the
catalogue's indices, independent of `paraxial`) gives the doublet's EFL and BFD; units, curvature
mode, aspheres, model glass and the system-aperture and field types each in a file written here."""

import math

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics import glass as G
from solas_mi.optics import pupil as P
from solas_mi.optics.paraxial import paraxial

DOUBLET = """! The SOLAS paper doublet (scenes/lenses/solas_doublet.toml) in CODE V syntax
LEN NEW
RDM
TIT 'solas doublet (CODE V)'
DIM M
WL 486.0 531.0 656.0
REF 2
WTW 1 2 1
INI 'SOL'
XAN 0.0 0.0 ; YAN 0.0 2.0
WTF 1 1
SO 0.0 1e+11
S 92.847 6.0 'N-BK7_SCHOTT'
  CIR 15.0
  SLB 'Surface 1'
S -30.716 3.0 F2_SCHOTT; CIR 15 ; CCY 0; THC 0
S -78.197 57.376
  CIR 15.0
STO 0.0 39.496   ! the stop: its CIR sets the aperture (no EPD)
  CIR 2.5
SI 0.0 0.0
  CIR 10.0
GO
"""

TRIPLET = """RDM;LEN "Cooke triplet"
TITLE 'cooke triplet (CODE V)'
EPD {epd!r}
DIM M
WL 656.2725 587.5618 486.1327
REF 2
YAN 0 14 20
SO 0 1e20
S 22.01359 3.25896 NSK16_SCHOTT
CIR 10
S -435.7604 6.007551
CIR 10
S -22.21328 0.9999746
GLA F2_SCHOTT
CIR 8
S 20.29192 4.750409
STO
S 79.68364 2.952076 'N-SK16_SCHOTT'; CIR 8
S -18.3783 42.20778; CIR 8
SI 0 0; CIR 18
"""


def load(tmp_path, text, name="lens.seq"):
    path = tmp_path / name
    path.write_text(text)
    return Lens.load(path)


def same_lens(a, b, fields):
    """EFL, BFD, f/#, the surfaces and the real chief rays of `fields` at every wavelength agree to 1e-9."""
    for wl in a.wavelengths_nm:
        pa, pb = paraxial(a, wl), paraxial(b, wl)
        for key in ("efl_mm", "bfd_mm", "f_number", "entrance_pupil_diameter_mm", "exit_pupil_z_mm"):
            assert getattr(pa, key) == pytest.approx(getattr(pb, key), rel=1e-9), key
        xy = [[0.0, f] for f in fields]
        ca, cb = P.chief_rays(a, xy, [wl] * len(xy)), P.chief_rays(b, xy, [wl] * len(xy))
        np.testing.assert_allclose(ca.image_xy, cb.image_xy, rtol=1e-9, atol=1e-12)
    assert [s.glass.name for s in a.surfaces] == [s.glass.name for s in b.surfaces]
    assert [s.stop for s in a.surfaces] == [s.stop for s in b.surfaces]


def test_doublet_is_the_shipped_doublet(tmp_path):
    lens, toml = load(tmp_path, DOUBLET), Lens.load("solas-doublet")
    assert lens.name == "solas doublet (CODE V)" and lens.at_infinity
    assert lens.wavelengths_nm == toml.wavelengths_nm and lens.primary_wavelength == 531.0
    assert lens.field_deg == 2.0 and lens.image_diameter == 20.0
    assert [s.diameter for s in lens.surfaces] == [s.diameter for s in toml.surfaces]
    assert lens.surfaces[0].label == "Surface 1"
    same_lens(lens, toml, [0.0, 1.0, 2.0])
    # the stop marked on the line after its surface, or named by number: the same lens
    for mark in ("S 0.0 39.496\n  STO", "S 0.0 39.496\nSTO S4"):
        other = load(tmp_path, DOUBLET.replace("STO 0.0 39.496", mark), "other.seq")
        same_lens(other, toml, [0.0, 2.0])
    with pytest.raises(SolasError, match="STO S7: the lens has surfaces S1 to S4"):
        load(tmp_path, DOUBLET.replace("STO 0.0 39.496", "S 0.0 39.496\nSTO S7"))


def test_doublet_against_a_hand_paraxial_trace(tmp_path):
    """y–nu trace of a ray parallel to the axis: EFL = y1 / −u', BFD = y_last / −u'."""
    lens = load(tmp_path, DOUBLET)
    wl = 531.0
    n = [1.0, G.resolve("SCHOTT:N-BK7").index(wl), G.resolve("SCHOTT:F2").index(wl), 1.0]
    radii, gaps = (92.847, -30.716, -78.197), (6.0, 3.0)
    y, nu = 1.0, 0.0
    for k, r in enumerate(radii):
        nu -= y * (n[k + 1] - n[k]) / r
        if k < len(gaps):
            y += gaps[k] * nu / n[k + 1]
    p = paraxial(lens, wl)
    assert p.efl_mm == pytest.approx(-1.0 / nu, rel=1e-12)
    assert p.bfd_mm == pytest.approx(-y / nu, rel=1e-12)
    assert p.f_number == pytest.approx(-1.0 / nu / p.entrance_pupil_diameter_mm, rel=1e-12)


def test_triplet_is_the_shipped_triplet(tmp_path):
    toml = Lens.load("cooke-triplet")
    epd = paraxial(toml, toml.primary_wavelength).entrance_pupil_diameter_mm
    lens = load(tmp_path, TRIPLET.format(epd=epd))
    assert lens.field_deg == 20.0 and lens.surfaces[3].stop
    assert lens.surfaces[3].diameter == pytest.approx(toml.surfaces[3].diameter, rel=1e-12)  # EPD sized the stop
    same_lens(lens, toml, [0.0, 14.0, 20.0])
    # FNO: the image-space F/# = EFL / EPD gives the same stop
    fno = paraxial(toml, toml.primary_wavelength).f_number
    by_fno = load(tmp_path, TRIPLET.format(epd=epd).replace(f"EPD {epd!r}", f"FNO {fno!r}"))
    assert by_fno.surfaces[3].diameter == pytest.approx(toml.surfaces[3].diameter, rel=1e-12)


N, R1, R2, T1 = 1.5, 60.0, -240.0, 8.0
EFL = 1.0 / ((N - 1) * (1 / R1 - 1 / R2 + (N - 1) * T1 / (N * R1 * R2)))
BFD = EFL * (1 - (N - 1) * T1 / (N * R1))


def singlet(scale=1.0, dim="M", mode="RDM", first=R1, second="", system="EPD 20\nYAN 0 10", last="PIM", glass="1.5:0"):
    """A singlet of constant index in lens units (mm / scale), stop on surface 1, PIM to the focus."""
    return f"""{mode}
DIM {dim}
WL 550
{system}
SO 0 1e10
STO {first / scale!r} {T1 / scale!r} {glass}
S {R2 / scale!r} 1.0
{second}{last}
SI 0 0
"""


@pytest.mark.parametrize("dim, scale", [("M", 1.0), ("C", 10.0), ("I", 25.4)])
def test_units_and_the_paraxial_image_solve(tmp_path, dim, scale):
    text = singlet(scale, dim, system=f"EPD {20 / scale!r}\nYAN 0 10")
    lens = load(tmp_path, text)
    p = paraxial(lens, 550.0)
    assert p.efl_mm == pytest.approx(EFL, rel=1e-12) and p.bfd_mm == pytest.approx(BFD, rel=1e-12)
    assert lens.surfaces[1].thickness == pytest.approx(BFD, rel=1e-12)  # PIM: the image at the focus
    assert p.entrance_pupil_diameter_mm == pytest.approx(20.0, rel=1e-12)
    assert not lens.dispersive


def test_curvature_mode_and_per_surface_commands(tmp_path):
    """CUM: S lines give curvatures; RDY, CUY, THI and GLA on lines of their own give the same lens."""
    base = load(tmp_path, singlet(), "a.seq")
    cum = singlet(mode="CUM").replace(f"STO {R1!r}", f"STO {1 / R1!r}").replace(f"S {R2!r}", f"S {1 / R2!r}")
    split = (
        singlet()
        .replace(f"STO {R1!r} {T1!r} 1.5:0", f"STO 0 0\nRDY {R1!r}\nTHI {T1!r}\nGLA 1.5:0")
        .replace(f"S {R2!r} 1.0", f"S; CUY {1 / R2!r}; THI 1")
    )
    for text in (cum, split):
        other = load(tmp_path, text, "b.seq")
        assert [s.radius for s in other.surfaces] == pytest.approx([s.radius for s in base.surfaces], rel=1e-12)
        assert [s.thickness for s in other.surfaces] == pytest.approx([s.thickness for s in base.surfaces], rel=1e-12)
        assert other.surfaces[0].stop and other.surfaces[0].glass.name == "model:1.5"


def test_aspheric_terms_and_units(tmp_path):
    asp = "ASP\nK -0.5\nA 1e-6\nB -2e-9\nD 3e-15\n"
    mm = load(tmp_path, singlet(second=asp), "mm.seq")
    s = mm.surfaces[1]
    assert s.conic == -0.5 and s.aspheric == (1e-6, -2e-9, 0.0, 3e-15)
    cm = load(
        tmp_path,
        singlet(10.0, "C", system="EPD 2\nYAN 0 10", second="ASP\nK -0.5\nA 1e-3\nB -2e-4\nD 3e-5\n"),
        "cm.seq",
    )
    # A (r⁴) scales as length⁻³, B as length⁻⁵, D (r¹⁰) as length⁻⁹
    assert cm.surfaces[1].aspheric == pytest.approx((1e-6, -2e-9, 0.0, 3e-14), rel=1e-12)
    sph = load(tmp_path, singlet(second=asp + "SPH\n"), "sph.seq")
    assert not any(sph.surfaces[1].aspheric) and sph.surfaces[1].conic == 0.0
    # the optimisation codes of the conic and of each coefficient (KC, AC … JC, as CODE V writes them for
    # variables and frozen values alike) say nothing of the surface: the same lens
    coded = load(
        tmp_path,
        singlet(
            second="ASP\nK -0.5; KC 100\nA 1e-6; AC 100\nB -2e-9; BC 0\nD 3e-15\n"
            "CC 0; DC 100; EC 0; FC 0; GC 0; HC 0; JC 0\n"
        ),
        "coded.seq",
    )
    assert coded.surfaces == mm.surfaces
    # a surface identifier on each surface (UID, as CODE V 2026 writes) and tolerances name no change
    tagged = singlet(second=asp).replace("SI 0 0", 'SI 0 0\nUID S0 "a1"\nUID S1 "b2"\nDSX S1 0.01\nBTY S2 0.02')
    assert load(tmp_path, tagged, "tagged.seq").surfaces == mm.surfaces


@pytest.mark.parametrize(
    "token, name",
    [
        ("1.699:30.1", "model:1.699/30.1"),
        ("699000.301000", "model:1.699/30.1"),
        ("'517000.642000'", "model:1.517/64.2"),
        ("1.62:0", "model:1.62"),
    ],
)
def test_model_glass(tmp_path, token, name):
    assert load(tmp_path, singlet(glass=token)).surfaces[0].glass.name == name


def test_field_types(tmp_path):
    # YOB: object height h, the object 500 mm before the stop (surface 1): tan θ = h / 500
    text = singlet(system="EPD 20\nYOB 0 30").replace("SO 0 1e10", "SO 0 500")
    assert load(tmp_path, text).field_deg == pytest.approx(math.degrees(math.atan(30 / 500)), rel=1e-12)
    # YIM: paraxial image height of a distant object, h' = f tan θ; XIM and YIM combine radially
    lens = load(tmp_path, singlet(system="EPD 20\nXIM 0 3\nYIM 0 4"))
    assert lens.field_deg == pytest.approx(math.degrees(math.atan(5 / EFL)), rel=1e-12)
    # YRI: the real chief ray lands there
    lens = load(tmp_path, singlet(system="EPD 20\nYRI 0 20"))
    hit = P.chief_rays(lens, [[0.0, lens.field_deg]], [550.0]).image_xy[0, 1]
    assert abs(hit) == pytest.approx(20.0, rel=1e-10)
    # NAO: the object-space NA of the marginal ray
    text = singlet(system="NAO 0.02\nYAN 0 1").replace("SO 0 1e10", "SO 0 500")
    assert load(tmp_path, text).surfaces[0].semi_diameter == pytest.approx(500 * math.tan(math.asin(0.02)), rel=1e-12)


@pytest.mark.parametrize(
    "insert, match",
    [
        ("RET S1\n", r"line \d+, surface S2: RET: coordinate returns to a named surface are not supported"),
        ("S -240.0 1.0 XYZ_SCHOTT\n", r"line \d+, surface S3: glass .XYZ_SCHOTT."),  # the surface its own line begins
        ("REFL\n", "REFL: mirrors"),
        ("DOE\n", "DOE: diffractive surfaces"),
        ("RDX 50\n", "RDX: anamorphic"),
        ("YTO\n", "YTO: toric surfaces"),
        ("FOO 1\n", "command FOO is not supported"),
        ("GLA XYZ_SCHOTT\n", "SCHOTT has no glass 'XYZ'"),
    ],
)
def test_refusals_name_the_surface_and_feature(tmp_path, insert, match):
    with pytest.raises(SolasError, match=match):
        load(tmp_path, singlet(second=insert))


def test_zero_decentres_pass_and_bad_structure(tmp_path):
    base = load(tmp_path, singlet(), "a.seq")
    zero = load(tmp_path, singlet(second="XDE 0\nADE 0.0\n"), "b.seq")
    assert paraxial(zero, 550.0).efl_mm == paraxial(base, 550.0).efl_mm
    with pytest.raises(SolasError, match="EPD and FNO both set"):
        load(tmp_path, singlet(system="EPD 20\nFNO 4\nYAN 0 1"))
    with pytest.raises(SolasError, match="needs SO"):
        load(tmp_path, "SO 0 1e10\nS 10 1\n")
    with pytest.raises(SolasError, match="DIM .X. is not supported"):
        load(tmp_path, singlet(dim="X"))


def test_what_code_v_writes(tmp_path):
    """Commands fused by `;`, a line continued with `&`, CODE V's 0.1E+14 infinity, the stop marked on the
    line after its surface, a six-digit glass code, an asphere's terms two to a line, comments."""
    text = f"""RDM;LEN       "VERSION: 2023.03       LENS VERSION: 89"
TITLE 'singlet'
EPD   20.0
DIM   M
WL    550.0
REF   1
YAN   0.0 5.0 &
      10.0
DOR   1.15 1.05
SO    0.0 0.1E+14
S     {R1!r} {T1!r} 500000.000000 ; CIR 12.5
  STO
S     {R2!r} {BFD!r}
  ASP
  K  0.0
  A  1.0E-07 ; B -2.0E-11 ! a comment
SI    0.0 0.0
GO
"""
    lens = load(tmp_path, text)
    p = paraxial(lens, 550.0)
    assert lens.surfaces[0].stop and lens.surfaces[0].glass.name == "model:1.5"
    assert p.efl_mm == pytest.approx(EFL, rel=1e-12) and p.entrance_pupil_diameter_mm == pytest.approx(20.0, rel=1e-12)
    assert lens.field_deg == 10.0 and lens.surfaces[1].aspheric == (1e-7, -2e-11)
    # without RDM, S lines of curvatures (as radii of 0.017 mm they form no real image) are read as curvatures
    cum = load(
        tmp_path,
        text.replace("RDM;LEN", "LEN")
        .replace(f"S     {R1!r}", f"S     {1 / R1!r}")
        .replace(f"S     {R2!r}", f"S     {1 / R2!r}"),
        "cum.seq",
    )
    assert [s.radius for s in cum.surfaces] == pytest.approx([R1, R2], rel=1e-12)
    assert "read as curvatures" in cum.description


@pytest.mark.parametrize(
    "change, match",
    [
        (("STO", "ZOO 2\nSTO"), "ZOO: zoom positions"),
        (("SO 0 1e10", "PRV\nPWL 550 600\n'X' 1.5\nEND\nSO 0 1e10"), "one index per PWL wavelength \\(2\\)"),
        (("SO 0 1e10", "PRV\nPWL 550\n'X' SEL 1 2 3\nEND\nSO 0 1e10"), "other dispersion formulas are not supported"),
        (("SI 0 0", "SI 0 0\nPRV\nPWL 550\n'X' 1.5"), "PRV \\(a private glass catalogue\\) has no END"),
    ],
)
def test_refused_systems(tmp_path, change, match):
    with pytest.raises(SolasError, match=match):
        load(tmp_path, singlet(system="FNO 4\nYAN 0 1").replace(*change))


def test_what_code_v_exports_also_hold(tmp_path):
    """Met in public .seq files: TEM at the catalogue's temperature, a zero CUF, CIR EDG (the edge
    aperture, drawn only), DER lines after SI, the object at 'inf', a three-digit glass code: the same
    lens as without them."""
    base = load(tmp_path, singlet(glass="500.600"), "a.seq")
    assert base.surfaces[0].glass.name == "model:1.5/60"
    text = singlet(glass="500.600").replace("WL 550", "WL 550\nTEM 20.0").replace("SO 0 1e10", "SO 0 inf")
    text = text.replace("PIM", "PIM\nCUF 0.0\nCIR EDG 30").replace("SI 0 0", "SI 0 0\nDER VAL I1 0.1")
    lens = load(tmp_path, text, "b.seq")
    assert lens.at_infinity and lens.surfaces == base.surfaces


def test_tem_and_pre_are_where_the_prescription_holds(tmp_path):
    """TEM (°C) and PRE (atmospheres): the lens at that temperature and pressure, radii and thicknesses as
    given, glass indices there (TEM outside 20-25 °C was refused)."""
    from solas_mi.optics import thermal

    text = singlet(glass="NBK7_SCHOTT", last="")  # no PIM: the image distance as given, not solved at 60 °C
    base = load(tmp_path, text, "a.seq")
    hot = load(tmp_path, text.replace("WL 550", "WL 550\nTEM 60\nPRE 0.9"), "b.seq")
    assert (hot.temperature_c, hot.pressure_kpa) == (60.0, pytest.approx(0.9 * 101.325))
    there = thermal.in_environment(base, 60.0, 0.9 * 101.325)  # automatic apertures aside (solved at 60 °C)
    assert [(s.radius, s.thickness, s.glass) for s in hot.surfaces] == [
        (s.radius, s.thickness, s.glass) for s in there.surfaces
    ]
    assert paraxial(hot, 550.0).efl_mm == paraxial(there, 550.0).efl_mm != paraxial(base, 550.0).efl_mm
    with pytest.raises(SolasError, match="temperature -300"):
        load(tmp_path, singlet().replace("WL 550", "WL 550\nTEM -300"), "c.seq")


@pytest.mark.parametrize(
    "change, match",
    [
        (("PIM", "PIM\nCUF 0.01"), "CUF: fringe curvatures"),
        (("PIM", "PIM\nCIR OBS 2"), "CIR OBS: obscurations"),
    ],
)
def test_what_code_v_exports_refused(tmp_path, change, match):
    with pytest.raises(SolasError, match=match):
        load(tmp_path, singlet().replace(*change))


def test_without_sto_the_stop_is_surface_1(tmp_path):
    """CODE V's default stop is surface 1, and the lens's description says so."""
    marked = load(tmp_path, singlet(), "a.seq")
    unmarked = load(tmp_path, singlet().replace("STO ", "S "), "b.seq")
    assert unmarked.surfaces == marked.surfaces
    assert "stop is surface 1" in unmarked.description and "stop" not in marked.description


def test_commands_by_their_first_three_letters(tmp_path):
    """CODE V knows a command by its first three letters: STOP on a line of its own marks the stop as STO
    does, TITLE and TEMPERATURE are TIT and TEM; a word beginning with a refused command (REFLECT) is
    refused as that one, not read as REF (the reference wavelength)."""
    marked = load(tmp_path, singlet(), "a.seq")
    words = (
        singlet(system="EPD 20\nYAN 0 10\nTITLE 'words'\nTEMPERATURE 20")
        .replace(f"STO {R1!r}", f"S {R1!r}")
        .replace(f"S {R2!r} 1.0", f"STOP\nS {R2!r} 1.0")
    )
    worded = load(tmp_path, words, "b.seq")
    assert worded.surfaces == marked.surfaces and worded.name == "words"
    with pytest.raises(SolasError, match="REFL: mirrors are not supported"):
        load(tmp_path, singlet().replace("PIM", "PIM\nREFLECT"), "c.seq")
    with pytest.raises(SolasError, match="command NAME is not supported"):
        load(tmp_path, singlet().replace("PIM", "PIM\nNAME 1"), "d.seq")


def test_vignetting_factors_shape_the_automatic_apertures(tmp_path):
    """Vignetting factors of 0.5 on every side at every field squeeze the beam at the stop to half its
    radius: the automatic semi-diameters are those of the same lens with half the entrance pupil."""
    lens = """RDM
WL 550
YAN 0 8 12
SO 0 1e10
S 40 5 1.6:40
S -120 10
S 0 10
STO
S -40 4 1.6:40
S 60 30
SI 0 0
"""
    half = "VUX 0.5 0.5 0.5\nVLX 0.5 0.5 0.5\nVUY 0.5 0.5 0.5\nVLY 0.5 0.5 0.5\n"
    vignetted = load(tmp_path, "EPD 16\n" + half + lens, "a.seq")
    smaller = load(tmp_path, "EPD 8\n" + lens, "b.seq")
    full = load(tmp_path, "EPD 16\n" + lens, "c.seq")
    for k in (0, 1, 3, 4):
        assert vignetted.surfaces[k].diameter == pytest.approx(smaller.surfaces[k].diameter, rel=1e-9)
        assert vignetted.surfaces[k].diameter < full.surfaces[k].diameter
    assert vignetted.surfaces[2].diameter == pytest.approx(full.surfaces[2].diameter, rel=1e-12)  # the stop
    with pytest.raises(SolasError, match="VUY '0.5 1.2'"):
        load(tmp_path, "EPD 16\nVUY 0.5 1.2\n" + lens, "d.seq")


def test_without_rdm_the_s_lines_are_radii(tmp_path):
    """A file saying neither RDM nor CUM is read in radii (as CODE V shows lens data and hand-written files
    give it): the singlet in radii without RDM is the singlet of the thick-lens formula, and its
    description says how it was read."""
    lens = load(tmp_path, singlet(mode=""))
    p = paraxial(lens, 550.0)
    assert [s.radius for s in lens.surfaces] == [R1, R2]
    assert p.efl_mm == pytest.approx(EFL, rel=1e-12) and p.bfd_mm == pytest.approx(BFD, rel=1e-12)
    assert "no RDM in the file: its S lines read as radii" in lens.description
    assert "RDM" not in load(tmp_path, singlet(), "rdm.seq").description  # RDM said so: nothing to note


@pytest.mark.parametrize("first, second", [(R1, R2), (-R2, -R1)])
def test_without_rdm_curvatures_are_taken_where_radii_form_no_real_image(tmp_path, first, second):
    """The same singlet written in curvatures without RDM: as radii (1/60 mm and -1/240 mm) the lens forms
    no real image, as curvatures it is the singlet of the thick-lens formula; the description says so.
    Both orientations (the radii reading of the reversed singlet is a diverging lens, of the first one
    a lens that images no field)."""
    n_first, n_second = 1 / first, 1 / second
    text = singlet(mode="", first=n_first, system="EPD 20\nYAN 0 10").replace(f"S {R2!r} 1.0", f"S {n_second!r} 1.0")
    lens = load(tmp_path, text)
    efl = 1.0 / ((N - 1) * (1 / first - 1 / second + (N - 1) * T1 / (N * first * second)))
    assert [s.radius for s in lens.surfaces] == pytest.approx([first, second], rel=1e-12)
    assert paraxial(lens, 550.0).efl_mm == pytest.approx(efl, rel=1e-12)
    assert "as curvatures (RDM N) they do: read as curvatures" in lens.description
    with pytest.raises(SolasError):  # CUM said otherwise: no fallback
        load(tmp_path, "RDM\n" + text, "rdm.seq")


def test_a_lens_without_rdm_that_fails_both_ways_says_how_it_was_read(tmp_path):
    """Read as radii (-1/60 mm, 1/240 mm) the file images nothing, and as curvatures it is a diverging
    lens: the refusal says how it was read and what to add if the S lines are curvatures. A fault that is
    the same either way has no such hint."""
    text = singlet(mode="", first=-1 / R1).replace(f"S {R2!r} 1.0", f"S {-1 / R2!r} 1.0").replace("PIM", "")
    with pytest.raises(SolasError, match="no RDM: its S lines were read as radii.*if they are curvatures, add RDM N"):
        load(tmp_path, text)
    with pytest.raises(SolasError, match="needs SO") as refused:
        load(tmp_path, "SO 0 1e10\nS 10 1\n", "b.seq")
    assert "RDM" not in str(refused.value)


def test_fno_with_a_near_object_is_the_working_f_number(tmp_path):
    """CODE V's FNO of a near object is the paraxial working F/# 1 / (2 n' u'): the marginal ray from the
    axial object point 500 mm away, traced by hand (y–nu) through the singlet, leaves at u' = 1 / (2 · 4)."""
    lens = load(tmp_path, singlet(system="FNO 4\nYAN 0 1").replace("SO 0 1e10", "SO 0 500"))

    def leaving_slope(y1):  # n' u' = n u − y φ at each surface, the stop (surface 1) the entrance pupil
        u = (y1 / 500.0 - y1 * (N - 1) / R1) / N
        return N * u - (y1 + T1 * u) * (1 - N) / R2

    epd = 2.0 * 1.0 / (2.0 * 4.0 * abs(leaving_slope(1.0)))  # u' is linear in the stop height
    p = paraxial(lens, 550.0)
    assert p.entrance_pupil_diameter_mm == pytest.approx(epd, rel=1e-12)
    assert p.working_f_number == pytest.approx(4.0, rel=1e-12)
    assert p.f_number < 3.3  # not EFL / EPD = 4, which a distant object's FNO states


PRIVATE = """RDM
WL 486.1327 587.5618 656.2725
REF 2
EPD 20
YAN 0 5
PRV
  PWL {pwl}
  'MYGLASS' {index}
  'GLUE' LAU 2.36390625 0.0 0.025493134 -0.000580235 -0.349933e-5 0.445404e-7
END
SO 0 1e10
STO 60.0 8.0 {glass}
S -240.0 1.0
PIM
SI 0 0
"""


def test_private_glass_catalogue(tmp_path):
    """PRV … END: a glass given as indices at the PWL wavelengths (here N-BK7's, every 25 nm from 400 to
    1000 nm, listed out of order) is the spline through them: the table's own indices at its wavelengths, N-BK7's
    to 2e-8 at the d, F and C lines, and the lens traces as the same lens in N-BK7 to 4e-8 in EFL there; LAU, the Laurent series
    n² = A0 + A1 λ² + A2 λ⁻² + … (λ µm), by hand. The lens carries them as its own materials ([materials]):
    written to TOML and read back, the same lens; .zmx, which cannot name them, refuses."""
    bk7 = G.resolve("N-BK7")
    pwl = [float(w) for w in range(1000, 399, -25)]
    text = PRIVATE.format(
        pwl=" ".join(map(repr, pwl)), index=" ".join(repr(float(bk7.index(w))) for w in pwl), glass="MYGLASS"
    )
    lens = load(tmp_path, text)
    ref = load(tmp_path, text.replace("STO 60.0 8.0 MYGLASS", "STO 60.0 8.0 NBK7_SCHOTT"), "ref.seq")
    own = lens.surfaces[0].glass
    assert own.kind == "table" and [g.name for g in lens.materials] == ["MYGLASS", "GLUE"]
    assert own.index(np.array(pwl)) == pytest.approx(bk7.index(np.array(pwl)), abs=1e-15)
    for w in (486.1327, 587.5618, 656.2725):
        assert own.index(w) == pytest.approx(bk7.index(w), abs=2e-8)  # the spline's own error
        assert paraxial(lens, w).efl_mm == pytest.approx(paraxial(ref, w).efl_mm, rel=4e-8)  # Δn / (n − 1)
    glue, lam = lens.materials[1], 0.5875618
    a = (2.36390625, 0.0, 0.025493134, -0.000580235, -0.349933e-5, 0.445404e-7)
    hand = math.sqrt(a[0] + a[1] * lam**2 + sum(k * lam ** (-2 * i) for i, k in enumerate(a[2:], start=1)))
    assert glue.index(587.5618) == pytest.approx(hand, abs=1e-15)
    with pytest.raises(SolasError, match="outside glass MYGLASS's valid range 400-1000 nm"):
        own.index(1064.0)
    back = Lens.load(lens.save(tmp_path / "back.toml"))
    assert back.materials == lens.materials and back.hash == lens.hash
    with pytest.raises(SolasError, match="material 'MYGLASS' is the lens file's own"):
        lens.save(tmp_path / "back.zmx")


def test_private_glass_in_the_dr_jit_tracer(tmp_path):
    """The tracer's index of a table material (Dr.Jit, each ray its wavelength) is the NumPy spline's."""
    import drjit as dr  # the tracer's array type

    from solas_mi.optics.tracer import refractive_index

    own = G.own_material(
        "T", {"wavelengths_nm": [400.0, 500.0, 550.0, 700.0, 900.0], "index": [1.53, 1.52, 1.517, 1.512, 1.509]}, "test"
    )
    waves = np.linspace(400.0, 900.0, 41)
    traced = refractive_index(own, dr.llvm.Float64(waves / 1000.0))
    assert np.asarray(traced) == pytest.approx(own.index(waves), abs=1e-15)


def test_a_glass_without_thermal_data_is_named_at_tem(tmp_path):
    """A model glass in a file at 60 °C: its index cannot follow the temperature, and a warning says so."""
    with pytest.warns(UserWarning, match="glass model:1.5 without thermal data"):
        load(tmp_path, singlet().replace("WL 550", "WL 550\nTEM 60"), "a.seq")
