"""Zemax files as their authors meant them, each feature in a file written here and checked against
numbers derived by hand: the thick-lens formulas of a singlet of constant index, and a meridional
real-ray trace written out below (Snell's law at spheres, in two dimensions, independent of the tracer)."""

import math
import re

import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics import pupil as P
from solas_mi.optics.paraxial import paraxial
from solas_mi.optics.placement import Placement

N = 1.5  # the singlet's constant index (model glass without dispersion)
R1, R2, T1 = 60.0, -240.0, 8.0  # mm
# thick lens: 1/f = (n − 1)(1/R1 − 1/R2 + (n − 1) t / (n R1 R2)); BFD = f (1 − (n − 1) t / (n R1))
EFL = 1.0 / ((N - 1) * (1 / R1 - 1 / R2 + (N - 1) * T1 / (N * R1 * R2)))
BFD = EFL * (1 - (N - 1) * T1 / (N * R1))
WL = 0.55  # µm


def zmx(
    *,
    aperture="ENPD 20",
    fields="FTYP 0 0 2 1 0 0 0\nXFLN 0 0\nYFLN 0 10",
    obj="INFINITY",
    s1="DIAM 12 1",
    s2="DIAM 14 1",
    extra="",
    header="",
):
    """A singlet, stop on surface 1, image plane at the paraxial focus; pieces replaceable."""
    return f"""VERS 190513 80 123457 L123457
MODE SEQ
NAME singlet
{header}UNIT MM X W X CM MR CPMM
{aperture}
{fields}
WAVM 1 {WL} 1
PWAV 1
SURF 0
  TYPE STANDARD
  CURV 0.0
  DISZ {obj}
SURF 1
  STOP
  TYPE STANDARD
  CURV {1 / R1!r}
  DISZ {T1}
  GLAS ___BLANK 1 0 {N} 0 0 0 0 0 0
  {s1}
SURF 2
  TYPE STANDARD
  CURV {1 / R2!r}
  DISZ {BFD!r}
  {s2}
{extra}SURF 9
  TYPE STANDARD
  CURV 0.0
  DISZ 0
"""


def load(tmp_path, text, name="lens.zmx", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return Lens.load(path)


def hand_trace(theta_deg, y_stop, surfaces=((1 / R1, T1, N), (1 / R2, BFD, 1.0))):
    """A meridional real ray of angle θ meeting surface 1 (the stop) at height y_stop: its heights at each
    surface and on the image plane."""
    u = math.radians(theta_deg)
    c = surfaces[0][0]
    sag = c * y_stop**2 / (1 + math.sqrt(1 - (c * y_stop) ** 2))
    y, z, dy, dz, n = y_stop - math.tan(u) * (10.0 + sag), -10.0, math.sin(u), math.cos(u), 1.0
    heights, vertex = [], 0.0
    for c, t, n2 in surfaces:
        # ray p + s d meets c|p − v|² − 2 (p_z − v_z) = 0
        pz = z - vertex
        b = dz - c * (y * dy + pz * dz)
        cc = c * (y * y + pz * pz) - 2 * pz
        s = cc / (b + math.sqrt(b * b - c * cc))
        y, z = y + s * dy, z + s * dz
        ny, nz = -c * y, 1 - c * (z - vertex)
        norm = math.hypot(ny, nz)
        ny, nz = ny / norm, nz / norm
        cosi = dy * ny + dz * nz
        mu = n / n2
        cost = math.sqrt(1 - mu * mu * (1 - cosi * cosi))
        dy, dz = mu * dy + (cost - mu * cosi) * ny, mu * dz + (cost - mu * cosi) * nz
        heights.append(y)
        vertex += t
        n = n2
    return heights, y + (vertex - z) / dz * dy


def test_the_singlet_is_the_thick_lens_of_the_formulas(tmp_path):
    lens = load(tmp_path, zmx())
    p = paraxial(lens, WL * 1000)
    assert p.efl_mm == pytest.approx(EFL, rel=1e-12) and p.bfd_mm == pytest.approx(BFD, rel=1e-12)
    assert lens.surfaces[0].diameter == pytest.approx(20.0, rel=1e-12)  # ENPD 20, the stop at surface 1
    assert not lens.dispersive


@pytest.mark.parametrize(
    "aperture, epd",
    [
        ("ENPD 15", 15.0),  # the stop's DIAM 12 (24 mm) does not win
        ("FNUM 4 0", EFL / 4.0),  # image-space F/# = EFL / EPD
        ("FLOA\nENPD 15", 24.0),  # float by stop size: the stop's DIAM
    ],
)
def test_aperture_types_size_the_stop(tmp_path, aperture, epd):
    lens = load(tmp_path, zmx(aperture=aperture))
    p = paraxial(lens, WL * 1000)
    assert p.entrance_pupil_diameter_mm == pytest.approx(epd, rel=1e-12)
    assert p.f_number == pytest.approx(EFL / epd, rel=1e-12)


def test_object_space_na(tmp_path):
    # finite object 500 mm before the stop (surface 1): the marginal ray's n sin u = NA
    lens = load(tmp_path, zmx(aperture="OBNA 0.02 0", obj="500"))
    assert lens.surfaces[0].semi_diameter == pytest.approx(500.0 * math.tan(math.asin(0.02)), rel=1e-12)
    with pytest.raises(SolasError, match="object-space NA needs a finite object"):
        load(tmp_path, zmx(aperture="OBNA 0.02 0"))
    with pytest.raises(
        SolasError,
        match="system aperture type not supported; allowed: .* paraxial working F/# "
        r"\(FNUM x 1\)",
    ):
        load(tmp_path, zmx(aperture="FNUM 4 2"))


def test_paraxial_working_f_number(tmp_path):
    """FNUM x 1, the paraxial working F/# 1 / (2 n' u'): the marginal ray from the axial object point 500 mm
    before the stop (surface 1), traced by hand (y–nu: n' u' = n u − y φ), leaves at u' = 1 / (2 · 4)."""
    lens = load(tmp_path, zmx(aperture="FNUM 4 1", obj="500"))
    u = (1.0 / 500.0 - (N - 1) / R1) / N  # a ray through the stop at height 1
    leaving = N * u - (1.0 + T1 * u) * (1 - N) / R2
    p = paraxial(lens, WL * 1000)
    assert p.entrance_pupil_diameter_mm == pytest.approx(2.0 / (2.0 * 4.0 * abs(leaving)), rel=1e-12)
    assert p.working_f_number == pytest.approx(4.0, rel=1e-12)


def test_field_types(tmp_path):
    # 1: object height h at 500 mm before the entrance pupil (the stop, surface 1): tan θ = h / 500
    lens = load(tmp_path, zmx(fields="FTYP 1 0 2 1 0 0 0\nXFLN 0 0\nYFLN 0 30", obj="500"))
    assert lens.field_deg == pytest.approx(math.degrees(math.atan(30 / 500)), rel=1e-12)
    # 2: paraxial image height at the focus of a distant object: h' = f tan θ
    lens = load(tmp_path, zmx(fields="FTYP 2 0 2 1 0 0 0\nXFLN 0 3\nYFLN 0 4"))
    assert lens.field_deg == pytest.approx(math.degrees(math.atan(5 / EFL)), rel=1e-12)
    # 3: real image height: the hand-traced chief ray (through the stop centre) of that angle lands there
    lens = load(tmp_path, zmx(fields="FTYP 3 0 2 1 0 0 0\nXFLN 0 0\nYFLN 0 20", s1="DIAM 0 0", s2="DIAM 0 0"))
    assert hand_trace(lens.field_deg, 0.0)[1] == pytest.approx(20.0, rel=1e-10)
    assert abs(lens.field_deg - math.degrees(math.atan(20 / EFL))) > 0.01  # not the paraxial angle
    with pytest.raises(SolasError, match="FTYP 4: field type not supported"):
        load(tmp_path, zmx(fields="FTYP 4 0 2 1 0 0 0\nXFLN 0 0\nYFLN 0 20"))


def test_automatic_semi_diameters(tmp_path):
    """No DIAM (or DIAM 0): the largest height of the chief and stop-rim rays of every field; at the
    stop its rim, behind it the meridional rim ray of the full field, traced by hand."""
    lens = load(tmp_path, zmx(s1="", s2="DIAM 0 0"))
    s1, s2 = lens.surfaces
    assert s1.semi_diameter == pytest.approx(10.0, rel=1e-12)
    lower = abs(hand_trace(10.0, -10.0)[0][1])
    upper = abs(hand_trace(10.0, 10.0)[0][1])
    assert s2.semi_diameter == pytest.approx(max(lower, upper), rel=1e-9)
    chief = P.chief_rays(lens, [[0.0, 10.0]], [WL * 1000])
    assert not chief.vignetted.any()


def test_dummy_surfaces_and_axial_coordinate_breaks(tmp_path):
    base = load(tmp_path, zmx())
    dummy = "SURF 3\n  TYPE STANDARD\n  CURV 0\n  DISZ 0\n  DIAM 0 0\n"
    axial = "SURF 4\n  TYPE COORDBRK\n  DISZ 0\n  PARM 1 0\n  PARM 3 0\n"
    undo = (
        "SURF 5\n  TYPE COORDBRK\n  DISZ 0\n  PARM 3 12.5\n  PARM 1 0.5\n"
        "SURF 6\n  TYPE COORDBRK\n  DISZ 0\n  PARM 3 -12.5\n  PARM 1 -0.5\n  PARM 6 1\n"
    )
    text = (
        zmx(extra=dummy + axial + undo)
        .replace(f"DISZ {BFD!r}", f"DISZ {BFD - 7!r}")
        .replace("SURF 4\n  TYPE COORDBRK\n  DISZ 0", "SURF 4\n  TYPE COORDBRK\n  DISZ 7")
    )
    lens = load(tmp_path, text)
    assert len(lens.surfaces) == 2 and lens.surfaces[1].thickness == pytest.approx(BFD, rel=1e-12)
    assert paraxial(lens, WL * 1000).efl_mm == pytest.approx(paraxial(base, WL * 1000).efl_mm, rel=1e-12)
    tilted = zmx(extra="SURF 3\n  TYPE COORDBRK\n  DISZ 0\n  PARM 3 5\n")  # the sensor tilted (test_as_built)
    assert load(tmp_path, tilted).image_placement == Placement(tilt_x=5.0)
    with pytest.raises(SolasError, match=r"SURF 3 \(line \d+\): COORDBRK decentres or tilts the axis"):
        load(tmp_path, tilted.replace("PARM 3 5\n", "PARM 3 5\nSURF 4\n  TYPE COORDBRK\n  DISZ 0\n  PARM 3 1\n"))


def test_dummy_with_zemax_automatic_aperture_and_a_negative_gap(tmp_path):
    """A flat air surface whose DIAM has solve type 0 (Zemax's automatic semi-diameter, the value only its
    last computation: it cuts no ray) is a dummy, even when a negative gap leads to it (met in published
    files: the lens's back face, 3 mm back to a dummy, 3 mm + BFD on to the image); its thickness joins the
    gap before, which leaves the same lens: BFD and EFL of the thick-lens formulas."""
    dummy = f'SURF 3\n  TYPE STANDARD\n  CURV 0\n  DISZ {3.0 + BFD!r}\n  DIAM 9.87654321 0 0 0 1 ""\n'
    lens = load(tmp_path, zmx(extra=dummy).replace(f"DISZ {BFD!r}", "DISZ -3.0"))
    p = paraxial(lens, WL * 1000)
    assert len(lens.surfaces) == 2 and lens.surfaces[1].thickness == pytest.approx(BFD, rel=1e-12)
    assert p.efl_mm == pytest.approx(EFL, rel=1e-12) and p.bfd_mm == pytest.approx(BFD, rel=1e-12)
    fixed = dummy.replace("9.87654321 0", "9.87654321 1")  # solve type 1: the user's aperture, a real surface
    kept = load(tmp_path, zmx(extra=fixed).replace(f"DISZ {BFD!r}", "DISZ -3.0"))  # traced through the negative gap
    assert len(kept.surfaces) == 3 and kept.surfaces[1].thickness == -3.0
    assert re.match(r"surfaces 2 \(SURF 2\) and 3 \(SURF 3\) overlap .*thickness -3 mm", kept.overlaps[0])
    q = paraxial(kept, WL * 1000)
    assert q.efl_mm == pytest.approx(EFL, rel=1e-12) and q.bfd_mm == pytest.approx(BFD, rel=1e-12)


def test_odd_asphere_even_terms(tmp_path):
    even = zmx(s2="DIAM 14 1").replace(
        "SURF 2\n  TYPE STANDARD", "SURF 2\n  TYPE EVENASPH\n  PARM 2 1e-6\n  PARM 3 -2e-9"
    )
    odd = zmx(s2="DIAM 14 1").replace(
        "SURF 2\n  TYPE STANDARD", "SURF 2\n  TYPE ODDASPH\n  PARM 4 1e-6\n  PARM 6 -2e-9"
    )
    a, b = load(tmp_path, even, "even.zmx"), load(tmp_path, odd, "odd.zmx")
    assert a.surfaces[1].aspheric == b.surfaces[1].aspheric == (1e-6, -2e-9)
    with pytest.raises(SolasError, match=r"SURF 2 \(line \d+\): ODDASPH PARM 3 \(the r\^3 term\)"):
        load(tmp_path, odd.replace("PARM 4 1e-6", "PARM 3 1e-5"))


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be", "latin-1", "utf-8"])
def test_encodings(tmp_path, encoding):
    """OpticStudio's Unicode files (UTF-16, with or without a byte-order mark) and ANSI ones."""
    lens = load(tmp_path, zmx().replace("NAME singlet", "NAME Ø18 mm singlet"), encoding=encoding)
    assert lens.name == "Ø18 mm singlet"
    assert paraxial(lens, WL * 1000).efl_mm == pytest.approx(EFL, rel=1e-12)


def test_names_round_trip_on_one_line(tmp_path):
    lens = load(tmp_path, zmx().replace("NAME singlet", "NAME Ø18 mm ½ singlet"))
    assert Lens.load(lens.save(tmp_path / "back.zmx")).name == "Ø18 mm ½ singlet"
    from dataclasses import replace

    with pytest.raises(SolasError, match="holds control characters"):  # no lens holds a name the writer would split
        replace(lens, name="x\nUNIT IN\nNAME y")


def test_model_glass_writes_its_digits(tmp_path):
    lens = load(tmp_path, zmx().replace(f"___BLANK 1 0 {N} 0", "___BLANK 1 0 1.699 30.1"))
    assert lens.surfaces[0].glass.name == "model:1.699/30.1"
    text = lens.save(tmp_path / "back.zmx").read_text()
    assert "___BLANK 1 0 1.699 30.1 " in text
    assert Lens.load(tmp_path / "back.zmx").surfaces[0].glass.name == "model:1.699/30.1"


def test_model_glass_given_by_n_d_alone_and_bad_numbers(tmp_path):
    lens = load(tmp_path, zmx().replace(f"___BLANK 1 0 {N} 0 0 0 0 0 0", "___BLANK 1 0 1.62"))
    assert lens.surfaces[0].glass.name == "model:1.62"
    with pytest.raises(
        SolasError, match=r"SURF 1 \(line \d+\): model glass GLAS ___BLANK n_d V_d: 'nan 0' must be finite"
    ):
        load(tmp_path, zmx().replace(f"___BLANK 1 0 {N} 0", "___BLANK 1 0 nan 0"))
    with pytest.raises(SolasError, match=r"needs n_d"):
        load(tmp_path, zmx().replace(f"___BLANK 1 0 {N} 0 0 0 0 0 0", "___BLANK 1 0"))


def test_vignetting_factors_shape_the_automatic_apertures(tmp_path):
    """VCXN/VCYN 0.5 at every field (compression: the pupil coordinate p becomes 0.5 p) squeeze the beam
    to half the pupil: surface 2's automatic semi-diameter is that of the lens with half the ENPD; a
    decentre VDYN moves the squeezed beam, so the upper and lower cuts differ."""
    fields = "FTYP 0 0 2 1 0 0 0\nXFLN 0 0\nYFLN 0 10\n"
    vignetted = load(tmp_path, zmx(fields=fields + "VCXN 0.5 0.5\nVCYN 0.5 0.5", s2="DIAM 0 0"), "a.zmx")
    smaller = load(tmp_path, zmx(aperture="ENPD 10", fields=fields, s2="DIAM 0 0"), "b.zmx")
    full = load(tmp_path, zmx(fields=fields, s2="DIAM 0 0"), "c.zmx")
    assert vignetted.surfaces[1].diameter == pytest.approx(smaller.surfaces[1].diameter, rel=1e-9)
    assert vignetted.surfaces[1].diameter < full.surfaces[1].diameter
    assert vignetted.surfaces[0].diameter == pytest.approx(20.0, rel=1e-12)  # the stop keeps ENPD 20
    up, down = (
        load(tmp_path, zmx(fields=fields + f"VDYN 0 {d}\nVCYN 0 0.3", s2="DIAM 0 0"), "d.zmx") for d in (0.3, -0.3)
    )  # the pupil moved up (cut below) or down (cut above, at the widest ray)
    assert up.surfaces[1].diameter == pytest.approx(full.surfaces[1].diameter, rel=1e-12)
    assert smaller.surfaces[1].diameter < down.surfaces[1].diameter < full.surfaces[1].diameter
    with pytest.raises(SolasError, match="leave no pupil"):
        load(tmp_path, zmx(fields=fields + "VCYN 0 1.5", s2="DIAM 0 0"), "e.zmx")


@pytest.mark.parametrize("header", ["", "GCAT CORNING\n", "GCAT SCHOTT CORNING\n"])
def test_corning_fused_silica_loads(tmp_path, header):
    """OpticStudio's name of Corning HPFS 7980, C79-80, loads with or without its catalogue in GCAT; the
    singlet's EFL is the thick-lens formula's at the index of Corning's Sellmeier formula, typed here; it
    is written back as GCAT CORNING, GLAS C79-80."""
    glas = "GLAS C79-80 0 0 1.458464 67.82 0 0 0 0 0 0"
    text = zmx(header=header).replace("GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0", glas)
    lens = load(tmp_path, text)
    assert lens.surfaces[0].glass.name == "CORNING:C79-80" and lens.dispersive
    l2 = WL**2
    n = (
        1
        + sum(
            b * l2 / (l2 - c)
            for b, c in [(0.683740494, 0.00460352869), (0.420323613, 0.0133968856), (0.58502748, 64.4932732)]
        )
    ) ** 0.5
    efl = 1.0 / ((n - 1) * (1 / R1 - 1 / R2 + (n - 1) * T1 / (n * R1 * R2)))
    assert paraxial(lens, WL * 1000).efl_mm == pytest.approx(efl, rel=1e-12)
    saved = lens.save(tmp_path / "again.zmx")
    assert "GCAT CORNING" in saved.read_text() and "GLAS C79-80 " in saved.read_text()
    assert Lens.load(saved).surfaces[0].glass.name == "CORNING:C79-80"


def test_every_plastic_and_moulded_glass_loads_by_its_zemax_name(tmp_path):
    """A singlet naming each glass of the moulders' and plastics' catalogues (LIGHTPATH, RPO, ZEON,
    OSAKAGASCHEMICAL, ANGSTROMLINK, CORNING, MISC's plastics) by its OpticStudio name, in a file without GCAT
    and in one with GCAT naming the vendor (as Thorlabs' files of LightPath lenses write GCAT LIGHTPATH
    SCHOTT), loads that glass; its EFL is the thick-lens formula's at the glass's index."""
    from solas_mi.optics import glass

    keys = [
        k
        for k in glass.load_catalog()
        if k.split(":")[0] in ("LIGHTPATH", "RPO", "ZEON", "OSAKAGASCHEMICAL", "ANGSTROMLINK", "CORNING")
    ]
    keys += [f"MISC:{n}" for n in ("PMMA", "POLYCARB", "POLYSTYR", "ACRYLIC", "SAN", "COC")]
    assert len(keys) == 70
    for key in keys:
        vendor, name = key.split(":")
        glas = f"GLAS {name} 0 0 1.5 50 0 0 0 0 0 0"
        for header in ("", f"GCAT {vendor} SCHOTT\n"):
            lens = load(tmp_path, zmx(header=header).replace("GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0", glas))
            assert lens.surfaces[0].glass.name == key
        n = glass.resolve(key).index(WL * 1000)
        efl = 1.0 / ((n - 1) * (1 / R1 - 1 / R2 + (n - 1) * T1 / (n * R1 * R2)))
        assert paraxial(lens, WL * 1000).efl_mm == pytest.approx(efl, rel=1e-12), key


@pytest.mark.parametrize("header", ["", "GCAT SCHOTT\n", "GCAT SCHOTT CDGM\n"])
def test_obsolete_schott_glass_loads_and_a_shared_name_keeps_its_current_glass(tmp_path, header):
    """A file naming SCHOTT's obsolete LAK33 loads it (OpticStudio's SCHOTT catalogue carries it: n_d 1.753977,
    V_d 52.430467, typed here); its EFL is the thick-lens formula's at that glass's index at 550 nm from
    its Sellmeier coefficients, typed here. F4, which CDGM sells and SCHOTT made, stays CDGM's F4 whatever
    GCAT says (as before SCHOTT's obsolete glasses were added), and the written file names the obsolete
    glass so that it reads back the same."""
    glas = "GLAS LAK33 0 0 1.753977 52.430467 0 0 0 0 0 0"
    lens = load(tmp_path, zmx(header=header).replace("GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0", glas))
    assert lens.surfaces[0].glass.name == "SCHOTT:LAK33"
    l2 = WL**2
    n = (
        1
        + sum(
            b * l2 / (l2 - c)
            for b, c in [(1.45796869, 0.0068054528), (0.555403936, 0.0225253283), (1.19938794, 82.7543327)]
        )
    ) ** 0.5
    efl = 1.0 / ((n - 1) * (1 / R1 - 1 / R2 + (n - 1) * T1 / (n * R1 * R2)))
    assert paraxial(lens, WL * 1000).efl_mm == pytest.approx(efl, rel=1e-12)
    assert Lens.load(lens.save(tmp_path / "again.zmx")).surfaces[0].glass.name == "SCHOTT:LAK33"
    f4 = load(tmp_path, zmx(header=header).replace("GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0", "GLAS F4 0 0 1.62 36 0 0"))
    assert f4.surfaces[0].glass.name == "CDGM:F4"


def test_flat_stop_on_a_concave_face(tmp_path):
    """Zemax's stop "on" a lens surface: a flat stop 7e-7 mm before a concave face (R −40 mm), whose sag
    reaches 0.31 mm in front of the stop's plane at the stop's rim (r = 5 mm). The stop refracts nothing,
    so a sequential trace checks each ray where its straight line crosses the plane, as OpticStudio does:
    the lens loads, its EFL is the thick-lens formula's, and its real chief ray (through the stop centre,
    the face's vertex to 7e-7 mm) lands where the hand trace of the same prescription puts it. The same
    crossing, where the stop plane refracts (glass after it) or where two faces cross, is an overlap: named."""
    r1, r2, t = -40.0, -15.0, 8.0
    efl = 1.0 / ((N - 1) * (1 / r1 - 1 / r2 + (N - 1) * t / (N * r1 * r2)))
    bfd = efl * (1 - (N - 1) * t / (N * r1))
    stop = 'SURF 1\n  STOP\n  TYPE STANDARD\n  CURV 0.0\n  DISZ 7e-07\n  DIAM 5 0 0 0 1 ""\n'
    text = (
        zmx(aperture="ENPD 10", s2="DIAM 8 1")
        .replace("SURF 2\n", "SURF 3\n")
        .replace("SURF 1\n  STOP\n", stop + "SURF 2\n")
        .replace(f"CURV {1 / R1!r}", f"CURV {1 / r1!r}")
        .replace(f"CURV {1 / R2!r}", f"CURV {1 / r2!r}")
        .replace(f"DISZ {T1}", f"DISZ {t}")
        .replace(f"DISZ {BFD!r}", f"DISZ {bfd!r}")
        .replace("DIAM 12 1", "DIAM 8 1")
    )
    lens = load(tmp_path, text)
    assert [s.stop for s in lens.surfaces] == [True, False, False]
    assert lens.surfaces[1].sag(5.0) < -0.3  # the face is in front of the stop's plane over its rim
    assert paraxial(lens, WL * 1000).efl_mm == pytest.approx(efl, rel=1e-9)
    chief = P.chief_rays(lens, [[0.0, 10.0]], [WL * 1000])
    image = hand_trace(10.0, 0.0, surfaces=((1 / r1, t, N), (1 / r2, bfd, 1.0)))[1]
    assert chief.image_xy[0, 1] == pytest.approx(image, rel=1e-6)
    assert lens.overlaps == ()
    for crossed in (
        text.replace("  DISZ 7e-07\n", "  DISZ 7e-07\n  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0\n"),
        text.replace("  CURV 0.0\n  DISZ 7e-07", f"  CURV {1 / 200!r}\n  DISZ 7e-07"),
    ):
        notes = load(tmp_path, crossed).overlaps  # traced as Zemax does, and named
        assert len(notes) == 1 and notes[0].startswith("surfaces 1 (SURF 1) and 2 (SURF 2) cross at r = ")


def test_image_plane_before_the_last_surface(tmp_path):
    """A negative distance to the image (a diverging singlet's file, its image plane on the virtual focus
    6.56 mm before its back face: OpticStudio traces rays backwards to it) is a virtual image: refused
    with that reason, not as a negative air gap."""
    with pytest.raises(
        SolasError,
        match=r"surface 2 \(SURF 2\): distance to the image -5 mm must be positive: "
        r"the image plane lies before the last surface, a virtual image",
    ):
        load(tmp_path, zmx().replace(f"DISZ {BFD!r}", "DISZ -5.0"))


def test_float_by_stop_size_on_a_stop_without_diameter(tmp_path):
    """FLOA takes the beam's size from the stop's DIAM: a stop without one leaves it undefined (ef35mm_f2.0
    of a public corpus): refused naming FLOA and the stop; the same stop under ENPD loads, its size the
    system aperture's (20 mm: the stop is the first surface)."""
    with pytest.raises(
        SolasError,
        match=r"floats by stop size \(FLOA, or no aperture named\) on the stop, surface 1 "
        r"\(SURF 1\), which "
        r"has no DIAM",
    ):
        load(tmp_path, zmx(aperture="FLOA", s1=""))
    assert load(tmp_path, zmx(s1="")).surfaces[0].diameter == pytest.approx(20.0)


def test_constant_index_media_hold_at_every_wavelength_and_below_air(tmp_path):
    """A lithography lens's way (fused silica 1.5602889 at 193.304 nm in a purge gas of 0.999712, indices
    relative to air, each a model glass without dispersion): the singlet's power is the thick-lens formula
    with index differences, φ = (n − m)(c1 − c2) + (n − m)² t c1 c2 / n, at a wavelength outside the
    dispersive model glass's range."""
    n, m, wl = 1.5602889, 0.999712, 193.304
    text = (
        zmx(obj="100")
        .replace("WAVM 1 0.55 1", f"WAVM 1 {wl / 1000!r} 1")
        .replace(f"___BLANK 1 0 {N} 0", f"___BLANK 1 0 {n} 0")
    )
    text = text.replace("  DISZ 100\n", f"  DISZ 100\n  GLAS ___BLANK 1 0 {m} 0 0 0 0 0 0\n")
    text = text.replace(f"  DISZ {BFD!r}\n", f"  DISZ {BFD!r}\n  GLAS ___BLANK 1 0 {m} 0 0 0 0 0 0\n")
    lens = load(tmp_path, text)
    assert lens.object_glass.index(wl) == m and lens.surfaces[1].glass.index(wl) == m
    c1, c2 = 1 / R1, 1 / R2
    power = (n - m) * (c1 - c2) + (n - m) ** 2 * T1 * c1 * c2 / n
    assert paraxial(lens, wl).efl_mm == pytest.approx(1 / power, rel=1e-12)
    with pytest.raises(
        SolasError,
        match=r"SURF 1 \(line \d+\): model glass n_d=0.5: a constant index must lie in "
        r"\(0.9, 3.0\)",
    ):
        load(tmp_path, zmx().replace(f"___BLANK 1 0 {N} 0", "___BLANK 1 0 0.5 0"))
    with pytest.raises(SolasError, match=r"n_d must lie in \(1, 3\) and V_d in \(5, 150\)"):
        load(tmp_path, zmx().replace(f"___BLANK 1 0 {N} 0", "___BLANK 1 0 0.999712 40"))


@pytest.mark.parametrize("aperture", ["FLOA", ""])
def test_a_file_without_stop_takes_surface_1_as_opticstudio_does(tmp_path, aperture):
    """A minimal file (optrace's public edge-case file is one) without a STOP line, surface 1 holding
    DIAM 12 and surface 2 none: refused with "diameter = None must be a finite number". An OpticStudio lens
    always has a stop, surface 1 in a new lens: it is read so, the description says so, and the stop's DIAM
    12 is the semi-diameter that sizes the beam, floating by stop size or with no aperture named: the same
    lens as with the STOP line (EPD 24 mm, the stop on the first surface). STOP on the object or the image
    is refused by name."""
    text = zmx(aperture=aperture, s2="")
    assert "  STOP\n" in text
    with_stop, without = load(tmp_path, text), load(tmp_path, text.replace("  STOP\n", ""), name="nostop.zmx")
    assert without.stop_index == 0 and "no STOP in the file: the stop is surface 1" in without.description
    assert without.surfaces[0].diameter == pytest.approx(24.0)
    assert paraxial(without, WL * 1000).entrance_pupil_diameter_mm == pytest.approx(24.0, rel=1e-12)
    assert [s.diameter for s in without.surfaces] == [s.diameter for s in with_stop.surfaces]
    for where in ("SURF 0\n", "SURF 9\n"):
        with pytest.raises(SolasError, match="STOP on the object or the image surface"):
            load(tmp_path, text.replace("  STOP\n", "").replace(where, where + "  STOP\n"), name="bad.zmx")


@pytest.mark.parametrize("header", ["ENVD 5.0E+1 0.9 0\n", "TEMP 50\nPRES 0.9\n"])
def test_envd_is_where_the_prescription_holds(tmp_path, header):
    """ENVD (°C, atmospheres; older files: TEMP and PRES): the lens at 50 °C in air of 0.9 atm, radii and
    thicknesses as given, glass indices there; written back as ENVD it reads as the same lens."""
    from solas_mi.optics import thermal

    text = zmx().replace("GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0", "GLAS N-BK7 0 0 1.5168 64.17 0 0 0 0 0 0")
    base, hot = (
        load(tmp_path, text),
        load(
            tmp_path,
            zmx(header=header).replace("GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0", "GLAS N-BK7 0 0 1.5168 64.17 0 0 0 0 0 0"),
            "hot.zmx",
        ),
    )
    assert (hot.temperature_c, hot.pressure_kpa) == (50.0, pytest.approx(0.9 * 101.325))
    assert hot.hash == thermal.in_environment(base, 50.0, hot.pressure_kpa).hash != base.hash
    assert Lens.load(hot.save(tmp_path / "again.zmx")).hash == hot.hash
    assert "ENVD 20.0 1.0 0" in base.save(tmp_path / "base.zmx").read_text()


def test_a_circular_aperture_is_the_surfaces_clear_aperture(tmp_path):
    """CLAP 0 R is the hard aperture Zemax stops rays at: it replaces DIAM's semi-diameter (14 here), which Zemax
    draws but does not stop rays with; before, CLAP was dropped without a word and rays passed out to 14 mm."""
    lens = load(tmp_path, zmx(s2='DIAM 14 1 0 0 1 ""\n  CLAP 0 5 0'))
    assert lens.surfaces[1].diameter == pytest.approx(10.0, rel=1e-12)
    assert load(tmp_path, zmx(s2="CLAP 0 5.5 0")).surfaces[1].diameter == pytest.approx(11.0, rel=1e-12)


@pytest.mark.parametrize(
    "line, words",
    [
        ("SQAP 3 2 0", "SQAP (rectangular aperture)"),
        ("ELAP 3 2 0", "ELAP (elliptical aperture)"),
        ("OBSC 0 1 0", "OBSC (circular obscuration)"),
        ("CLAP 2 5 0", "CLAP 2 5: a circular aperture must run from radius 0"),
        ("CLAP 0 5 0\n  OBDC 0.5 0", "OBDC 0.5 0 decentres the aperture"),
    ],
)
def test_apertures_other_than_a_centred_circle_are_refused_by_name(tmp_path, line, words):
    """A rectangle, an ellipse, an obscuration, an annulus or a decentred aperture: reading DIAM instead (as
    before, silently) would trace rays the real lens stops."""
    with pytest.raises(SolasError, match=re.escape(words)):
        load(tmp_path, zmx(s2=f"DIAM 14 1\n  {line}"))
