import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.optics import glass

# Schott data-sheet values n_d, V_d, typed from the data sheets (not read from the catalogue files).
SCHOTT = {
    "N-BK7": (1.51680, 64.17),
    "SCHOTT:F2": (1.62004, 36.37),
    "N-SF5": (1.67271, 32.25),
    "N-SK16": (1.62041, 60.32),
    "N-LAK9": (1.69100, 54.71),
    "N-SF11": (1.78472, 25.68),
    "SCHOTT:F5": (1.60342, 38.03),
    "N-BAF10": (1.67003, 47.11),
    "N-SSK8": (1.61773, 49.83),
}
# What each vendor's formulas reproduce of its stated n_d / V_d (computed at 587.5618 / 486.1327 /
# 656.2725 nm). Measured worst cases: SCHOTT 4.8e-6 / 0.0087 (N-LAK21, SF6G05), HOYA 5.5e-6 / 0.0088
# (FDS18-W, FC5), OHARA, CDGM, HIKARI 5e-7 / 5e-5 (the database states their n_d / V_d to 6 decimals,
# from the formulas), SUMITA 3.8e-5 / 0.23 (K-PSFn214(M), K-CaFK95: V_d stated to 0.1, looser fits).
# MISC: fused silica's data-sheet n_d 1.4585 / V_d 67.8 against Malitson's formula (1.45846 / 67.82), to the
# sheets' last digit. The OpticStudio catalogues CORNING, LIGHTPATH, RPO, ZEON, OSAKAGASCHEMICAL, ANGSTROMLINK and
# MISC's plastics state n_d / V_d to 6 decimals from their formulas: worst 5e-7 / 5e-7 (MISC's plastics are held to
# MISC's tolerance).
# An entry `fitted` to a data sheet's table of 4-decimal indices (SCHOTT:B270): n_d within
# half that digit, V_d within what ±5e-5 in n_F and n_C allows (±1e-4 in n_F − n_C ≈ 0.0089: ±0.7).
TOLERANCE = {
    "SCHOTT": (1e-5, 0.01),
    "HOYA": (1e-5, 0.01),
    "OHARA": (1e-6, 1e-4),
    "CDGM": (1e-6, 1e-4),
    "HIKARI": (1e-6, 1e-4),
    "SUMITA": (4e-5, 0.25),
    "MISC": (5e-5, 0.05),
    "CORNING": (1e-6, 1e-4),
    "LIGHTPATH": (1e-6, 1e-4),
    "RPO": (1e-6, 1e-4),
    "ZEON": (1e-6, 1e-4),
    "OSAKAGASCHEMICAL": (1e-6, 1e-4),
    "ANGSTROMLINK": (1e-6, 1e-4),
}
FITTED = (5e-5, 0.7)
COUNTS = {
    "SCHOTT": 356,
    "OHARA": 410,
    "HOYA": 190,
    "CDGM": 314,
    "SUMITA": 176,
    "HIKARI": 363,
    "MISC": 9,
    "CORNING": 1,
    "LIGHTPATH": 10,
    "RPO": 38,
    "ZEON": 9,
    "OSAKAGASCHEMICAL": 3,
    "ANGSTROMLINK": 3,
}


@pytest.mark.parametrize("name", sorted(SCHOTT))
def test_catalogue_reproduces_schott_data_sheets(name):
    nd, vd = glass.resolve(name).abbe()
    assert nd == pytest.approx(SCHOTT[name][0], abs=5e-6)
    assert vd == pytest.approx(SCHOTT[name][1], abs=0.01)


@pytest.mark.parametrize("vendor", sorted(TOLERANCE))
def test_every_entry_reproduces_its_stated_nd_vd(vendor):
    """Every catalogue entry's formula gives its stated n_d and V_d within the vendor's tolerance."""
    entries = {k: g for k, g in glass.load_catalog().items() if k.startswith(vendor + ":")}
    assert len(entries) == COUNTS[vendor]
    bad = []
    for key, g in entries.items():
        nd_tol, vd_tol = FITTED if "fitted" in glass._entries(None)[key] else TOLERANCE[vendor]
        nd, vd = g.abbe()
        if not (abs(nd - g.nd) <= nd_tol and abs(vd - g.vd) <= vd_tol):
            bad.append((key, nd, g.nd, vd, g.vd))
    assert not bad


def test_catalogue_formulas_and_names():
    cat = glass.load_catalog()
    assert {g.kind for g in cat.values()} == {"sellmeier", "polynomial", "conrady"}
    assert all(key.split(":", 1)[0] in glass.VENDORS and key == g.name for key, g in cat.items())
    for key, g in cat.items():  # every range covers the d, F and C lines and the formulas are finite there
        assert g.range_nm[0] <= glass.LINE_F and g.range_nm[1] >= glass.LINE_C, key


def test_polynomial_formula():
    """HOYA TAFD5F, the power series n² = Σ K λ^P, against the value the formula gives by hand."""
    g = glass.resolve("TAFD5F")
    assert g.kind == "polynomial"
    lam = 0.5875618
    k = [3.275546, -0.014470354, 0.030922062, 0.00073289981, 4.6573307e-06, 1.8242746e-06]
    p = [0, 2, -2, -4, -6, -8]
    assert g.index(587.5618) == pytest.approx(sum(a * lam**e for a, e in zip(k, p)) ** 0.5, abs=1e-15)
    assert g.index(587.5618) == pytest.approx(1.83481, abs=1e-5)
    import drjit as dr  # the tracer's path: the same formula on Dr.Jit arrays
    from drjit.llvm import Float64

    n = g.index_formula(Float64([0.4861327, lam]), dr.sqrt)
    assert list(n) == pytest.approx(list(g.index([486.1327, 587.5618])), abs=1e-14)


@pytest.mark.parametrize(
    "name,key",
    [
        ("S-LAH59", "OHARA:S-LAH59"),
        ("ohara:s-lah59", "OHARA:S-LAH59"),
        ("TAFD5G", "HOYA:TAFD5G"),
        ("H-ZF52", "CDGM:H-ZF52"),
        ("E-LASF05", "HIKARI:E-LASF05"),
        ("K-LaSFn9", "SUMITA:K-LaSFn9"),
        ("BK7", "SCHOTT:N-BK7"),
        ("N-BAF10", "SCHOTT:N-BAF10"),
    ],
)
def test_bare_names_resolve_to_one_entry(name, key):
    assert glass.resolve(name).name == key


def test_a_name_of_two_vendors_is_ambiguous():
    with pytest.raises(SolasError, match=r"glass name 'F2' is ambiguous: it matches CDGM:F2, HIKARI:F2, SCHOTT:F2"):
        glass.resolve("F2")
    with pytest.raises(SolasError, match=r"'sf11' is ambiguous: it matches HIKARI:SF11, SCHOTT:SF11"):
        glass.resolve("sf11")
    assert glass.resolve("SCHOTT:F2").nd == 1.62004 and glass.resolve("CDGM:F2").nd == pytest.approx(1.61293, abs=1e-5)


def test_match_finds_the_glasses_within_tolerance():
    found = glass.match(1.81600, 46.62)
    assert found[0].key == "OHARA:S-LAH59"
    assert {m.key for m in found} >= {"OHARA:S-LAH59", "HIKARI:E-LASF09", "OHARA:LAH59"}
    for m in found:
        assert abs(min(abs(m.nd - 1.816), abs(m.formula_nd - 1.816))) <= glass.MATCH_ND
    assert [m.key for m in glass.match(1.816, 46.6206, 1e-6, 1e-3)] == ["OHARA:S-LAH59"]
    assert glass.match(1.2, 46.0) == []


def test_design_indices():
    """DESIGN.md's indices at the three design wavelengths."""
    bk7, f2 = glass.resolve("BK7"), glass.resolve("SCHOTT:F2")
    assert bk7.index([486, 531, 656]) == pytest.approx([1.5223859, 1.5195281, 1.5143308], abs=1e-7)
    assert f2.index([486, 531, 656]) == pytest.approx([1.6321030, 1.6258107, 1.6150484], abs=1e-7)


def test_bk7_is_schott_n_bk7():
    assert glass.resolve("BK7") is glass.resolve("SCHOTT:N-BK7") is glass.resolve("n-bk7")


def test_model_glass_has_given_nd_vd():
    nd, vd = glass.resolve("model:1.62/36.4").abbe()
    assert (nd, vd) == pytest.approx((1.62, 36.4), abs=1e-9)


def test_unknown_glass_is_named():
    with pytest.raises(
        SolasError,
        match=r"unknown glass 'N-BK8'; close: .*SCHOTT:N-BK7.*; allowed: AIR, a catalogue "
        r"glass \(1882 of ANGSTROMLINK, CDGM, CORNING, HIKARI, HOYA, LIGHTPATH, "
        r"MISC, OHARA, OSAKAGASCHEMICAL, RPO, SCHOTT, SUMITA, ZEON",
    ):
        glass.resolve("N-BK8")


def test_ambiguous_name_fails_in_a_catalogue_file(tmp_path):
    cat = tmp_path / "cat.toml"
    cat.write_text(
        '[glass."SCHOTT:F2"]\nB=[1.3,0.2,0.9]\nC=[0.01,0.05,110.0]\nrange_nm=[320.0,2500.0]\n'
        '[glass."CDGM:F2"]\nB=[1.3,0.2,0.9]\nC=[0.01,0.05,110.0]\nrange_nm=[320.0,2500.0]\n'
    )
    with pytest.raises(SolasError, match="ambiguous.*CDGM:F2, SCHOTT:F2"):
        glass.resolve("F2", str(cat))
    assert glass.resolve("CDGM:F2", str(cat)).name == "CDGM:F2"


@pytest.mark.parametrize("wavelength", [250.0, 2600.0, np.nan])
def test_outside_valid_range(wavelength):
    with pytest.raises(SolasError, match="outside glass SCHOTT:N-BK7's valid range 300-2500 nm"):
        glass.resolve("N-BK7").index(wavelength)


def test_malformed_model_glass():
    with pytest.raises(
        SolasError, match=r"model glass 'model:1.2.3/40' must read model:n_d/V_d"
    ):  # not "unknown glass"
        glass.resolve("model:1.2.3/40")


@pytest.mark.parametrize(
    "name, key",
    [
        # precision-moulding (low-Tg) glasses of the lens files of moulded aspheres
        ("L-BAL35", "OHARA:L-BAL35"),
        ("L-TIM28", "OHARA:L-TIM28"),
        ("L-LAH53", "OHARA:L-LAH53"),
        ("M-TAF1", "HOYA:M-TAF1"),
        ("MC-TAF1", "HOYA:MC-TAF1"),
        ("MP-FDS1", "HOYA:MP-FDS1"),
        ("D-ZK3", "CDGM:D-ZK3"),
    ],
)
def test_moulding_glasses(name, key):
    """Moulded aspheres' glasses resolve by their bare names, the formula giving the catalogue's n_d / V_d."""
    g = glass.resolve(name)
    assert g.name == key
    nd, vd = g.abbe()
    nd_tol, vd_tol = TOLERANCE[key.split(":")[0]]
    assert abs(nd - g.nd) <= nd_tol and abs(vd - g.vd) <= vd_tol


def test_discontinued_glasses_are_kept_and_say_so():
    entries = glass._entries(None)
    assert entries["HOYA:M-TAF1"]["discontinued"].startswith("Not in a position to accept new order")
    assert entries["SCHOTT:SF14"]["discontinued"] == "was replaced by N-SF14"
    assert "discontinued" not in entries["SCHOTT:N-BK7"]


def test_b270_and_fused_silica():
    """B270 (SCHOTT's sheet crown) follows its data sheet's indices, typed here from the sheet (August 1993),
    to its 4 decimals, and is offered over OpticStudio's range for it, 334-2500 nm (920 nm, where COTS
    near-infrared lenses work, included), refused below; fused silica (Malitson's formula) reaches 248 nm,
    where lithography lenses work."""
    b270 = glass.resolve("B270")
    assert b270.name == "SCHOTT:B270"
    sheet = {
        435.83: 1.5341,
        479.99: 1.5297,
        486.13: 1.5292,
        546.07: 1.5251,
        587.56: 1.5230,
        589.29: 1.5229,
        643.85: 1.5207,
        656.27: 1.5203,
    }
    assert max(abs(b270.index(w) - n) for w, n in sheet.items()) < 5e-5
    silica = glass.resolve("SILICA")
    assert silica.name == "MISC:SILICA" and glass.resolve("FUSED-SILICA") is silica
    assert 1.5 < silica.index(248.0) < 1.52
    with pytest.raises(SolasError, match=r"wavelength 300 nm is outside glass SCHOTT:B270's valid range 334-2500 nm"):
        b270.index(300.0)


def test_b270_in_the_near_infrared_keeps_opticstudios_dispersion():
    """Past the sheet, B270 is OpticStudio's formula (its SCHOTT catalogue: n² = Σ K λ^P over 334-2500 nm,
    coefficients typed here) less a constant offset: the index difference between them is the same at
    920, 1064 and 1550 nm as at the d line to 1e-6 (the constant K0 alone was fitted), and its dispersion
    is a crown's: n falls with λ, below n_C."""
    k = (2.286575, -8.7334582e-3, 1.1742884e-2, 2.9041756e-4, -1.2506695e-5, 9.2646253e-7)

    def opticstudio(nm):
        lam = nm / 1000.0
        return np.sqrt(sum(c * lam**p for c, p in zip(k, (0, 2, -2, -4, -6, -8))))

    b270 = glass.resolve("B270")
    # n² differs by the constant ΔK0, so n differs by ΔK0 / (n + n'): nearly constant, exactly so in n².
    shift = b270.index(587.5618) ** 2 - opticstudio(587.5618) ** 2
    for nm in (334.0, 920.0, 1064.0, 1550.0, 2500.0):
        assert b270.index(nm) ** 2 - opticstudio(nm) ** 2 == pytest.approx(shift, abs=1e-12)
    assert -3e-4 < shift < -2.5e-4  # the sheet lies about 1e-4 in n below OpticStudio's formula
    assert b270.index(920.0) < b270.index(656.27) < b270.index(435.83)


def test_obsolete_schott_glasses_answer_to_their_names_only_where_no_other_glass_does():
    """OpticStudio's SCHOTT catalogue's obsolete glasses (LAK33, BAF3, F4, ...) load by name; a name that a
    glass of the current catalogues also has keeps meaning that glass (CDGM's F4, with SCHOTT preferred
    too, as before they were added), the obsolete one being reachable by its full key; a table's n_d / V_d
    is never matched to one. Values typed from SCHOTT's catalogue of 2008 (n_d, V_d)."""
    lak33 = glass.resolve("LAK33")
    assert lak33.name == "SCHOTT:LAK33"
    assert lak33.abbe() == pytest.approx((1.753977, 52.430467), abs=(1e-5))
    assert glass._entries(None)["SCHOTT:LAK33"]["discontinued"].startswith("obsolete")
    assert glass.candidates("F4") == ["CDGM:F4"]
    assert glass.resolve("F4", prefer=("SCHOTT",)).name == "CDGM:F4"
    assert glass.resolve("SCHOTT:F4").name == "SCHOTT:F4"
    assert glass.resolve("BAF3").name == "HIKARI:BAF3"  # the same melt data as SCHOTT's obsolete BAF3
    baf3 = glass.load_catalog()["SCHOTT:BAF3"]
    assert "SCHOTT:BAF3" not in [m.key for m in glass.match(*baf3.abbe())]
    assert glass.material_for(1.753977, 52.430467).startswith("model:")  # only LAK33 and N-LAK33 have these


def test_table_matching_is_unchanged_by_the_obsolete_glasses(tmp_path):
    """Every catalogue glass's stated (n_d, V_d) and every shipped lens written as a .dat table and read
    back get the same material as from a catalogue without the `by_name` entries."""
    import tomllib

    from solas_mi.optics import pbrt_dat
    from solas_mi.optics.lens import Lens

    entries = glass._entries(None)
    kept = {k: e for k, e in entries.items() if not e.get("by_name")}
    assert len(entries) - len(kept) == 199
    lines = ["[glass]"] + [f'"{k}" = {_inline(e)}' for k, e in kept.items()]
    current = tmp_path / "current.toml"
    current.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert tomllib.loads(current.read_text(encoding="utf-8"))["glass"].keys() == kept.keys()
    for key, g in glass.load_catalog().items():
        if g.nd is not None and key in kept:
            assert glass.material_for(g.nd, g.vd) == glass.material_for(g.nd, g.vd, catalog=str(current)), key
    for name in ("cooke_triplet", "double_gauss_50mm", "nikkor_fisheye", "solas_doublet", "wide_angle_22mm"):
        spec = pbrt_dat.read_spec(pbrt_dat.dumps(Lens.load(name)), name)
        for row in spec["surface"]:
            material = row.get("material", "AIR")
            assert material.startswith(("model:", "AIR")) or material in kept, (name, material)


def _inline(entry: dict) -> str:
    """A catalogue entry as a TOML inline table."""

    def value(v):
        return (
            "[" + ", ".join(value(x) for x in v) + "]"
            if isinstance(v, list)
            else ('"' + v.replace('"', '\\"') + '"' if isinstance(v, str) else ("true" if v is True else repr(v)))
        )

    return "{" + ", ".join(f"{k} = {value(v)}" for k, v in entry.items()) + "}"


def test_corning_7980_is_fused_silica():
    """C79-80 (OpticStudio's name of Corning HPFS 7980) follows Corning's Sellmeier formula, typed here from
    the sheet, and agrees with Malitson's independent measurement of fused silica (MISC:SILICA) to 2e-5 in the
    visible and near infrared, 5e-5 at 248 nm; it is offered over 185-1120 nm, OpticStudio's range."""
    c7980 = glass.resolve("C79-80")
    assert c7980.name == "CORNING:C79-80" and glass.resolve("corning:c79-80") is c7980
    b, c = (0.683740494, 0.420323613, 0.58502748), (0.00460352869, 0.0133968856, 64.4932732)
    for nm in (193.368, 587.5618, 1064.0):
        l2 = (nm / 1000) ** 2
        n = (1 + sum(bi * l2 / (l2 - ci) for bi, ci in zip(b, c))) ** 0.5
        assert c7980.index(nm) == pytest.approx(n, abs=1e-15)
    silica = glass.resolve("SILICA")
    visible = np.linspace(400.0, 1100.0, 36)
    assert np.max(np.abs(c7980.index(visible) - silica.index(visible))) < 2e-5
    assert abs(c7980.index(248.3) - silica.index(248.3)) < 6e-5
    with pytest.raises(SolasError, match="outside glass CORNING:C79-80's valid range 185-1120 nm"):
        c7980.index(1550.0)


# Moulded glass as its moulder's catalogue gives it (after moulding) and the glass it is moulded from.
MOULDED = {
    "LIGHTPATH:D-ZK3M": "CDGM:D-ZK3",
    "RPO:L-TIM28_MOLD": "OHARA:L-TIM28",
    "RPO:N-BK7_MOLD": "SCHOTT:N-BK7",
    "RPO:S-LAL12_MOLD": "OHARA:S-LAL12",
    "RPO:P-SK57_MOLD": "SCHOTT:P-SK57",
    "RPO:TAF1_MOLD": "HOYA:TAF1",
}


@pytest.mark.parametrize(
    "name, key",
    [
        ("D-ZK3M", "LIGHTPATH:D-ZK3M"),
        ("L-TIM28_MOLD", "RPO:L-TIM28_MOLD"),
        ("C79-80", "CORNING:C79-80"),
        ("E48R", "ZEON:E48R"),
        ("OKP4HT", "OSAKAGASCHEMICAL:OKP4HT"),
        ("PMMA", "MISC:PMMA"),
        ("POLYCARB", "MISC:POLYCARB"),
        ("POLYSTYR", "MISC:POLYSTYR"),
        ("COC", "MISC:COC"),
        ("F_SILICA", "MISC:SILICA"),
        ("L-TIM28", "OHARA:L-TIM28"),
        ("AL-6263-(OKP4HT)", "ANGSTROMLINK:AL-6263-(OKP4HT)"),
    ],
)
def test_plastics_and_moulded_glass_names(name, key):
    """The names OpticStudio files use for plastics and moulded glass resolve by themselves (no vendor shares
    them), the moulded variants without taking the name of the glass they are moulded from."""
    assert glass.resolve(name).name == key


@pytest.mark.parametrize("moulded", sorted(MOULDED))
def test_moulding_lowers_the_index(moulded):
    """Moulding (fast cooling through the transformation range) lowers a glass's index by a few 1e-3 and
    leaves its dispersion nearly as it was: each moulded entry's n_d lies 1e-3 to 1e-2 below its parent's,
    its V_d within 1 of it."""
    nd, vd = glass.resolve(moulded).abbe()
    nd0, vd0 = glass.resolve(MOULDED[moulded]).abbe()
    assert 1e-3 < nd0 - nd < 1e-2 and abs(vd - vd0) < 1.0


def test_plastic_crowns_and_flints_and_their_index_with_temperature():
    """Optical plastics: the acrylic PMMA and the cyclo-olefin E48R are low-index crowns (n_d 1.49-1.54, V_d
    55-58), polycarbonate, polystyrene and OKP4HT flints (n_d 1.58-1.64, V_d 23-31); ZEON's K26R entries for
    -15 … 80 °C fall in index with temperature at about -1e-4 /K, a plastic's dn/dT (glass: ~1e-6 /K)."""
    for name in ("PMMA", "E48R", "COC", "330R"):
        nd, vd = glass.resolve(name).abbe()
        assert 1.49 < nd < 1.54 and 55.0 < vd < 58.0, name
    for name in ("POLYCARB", "POLYSTYR", "OKP4HT", "OKP4", "AL-6263-(OKP4HT)", "AL-6261-(OKP4)"):
        nd, vd = glass.resolve(name).abbe()
        assert 1.58 < nd < 1.64 and 23.0 < vd < 31.0, name
    temps = [-15, 0, 25, 40, 60, 80]
    nd = [glass.resolve(f"K26R_{t}").index(glass.LINE_D) for t in temps]
    slopes = np.diff(nd) / np.diff(temps)
    assert np.all(slopes < 0) and np.all(np.abs(slopes + 1.05e-4) < 0.3e-4)


def test_calcium_fluoride_daimon():
    """CAF2_DAIMON-20 (the name optiland's files give Daimon and Masumura's 20 °C formula) follows their
    Sellmeier formula, typed here from the paper, and agrees with Malitson's independent measurement of CaF2
    (1963, 24 °C; CaF2's index falls about 1e-5 per kelvin) to 5e-5 over 400-1000 nm and in V_d to 0.3."""
    caf2 = glass.resolve("CAF2_DAIMON-20")
    assert caf2.name == "MISC:CAF2_DAIMON-20"
    b, c = (0.443749998, 0.444930066, 0.150133991, 8.85319946), (0.00178027854, 0.00788536061, 0.0124119491, 2752.28175)
    for nm in (157.6, 587.5618, 2000.0):
        l2 = (nm / 1000) ** 2
        assert caf2.index(nm) == pytest.approx((1 + sum(bi * l2 / (l2 - ci) for bi, ci in zip(b, c))) ** 0.5, abs=1e-15)
    malitson = glass.Glass(
        "CaF2 Malitson", "sellmeier", ((0.5675888, 0.4710914, 3.8484723), (0.050263605**2, 0.1003909**2, 34.649040**2))
    )
    misc = glass.resolve("CAF2")  # OpticStudio's MISC CAF2: Malitson's formula, its C_i squared to 7 digits
    assert misc.name == "MISC:CAF2" and misc.index(587.5618) == pytest.approx(malitson.index(587.5618), abs=2e-7)
    visible = np.linspace(400.0, 1000.0, 31)
    assert np.max(np.abs(caf2.index(visible) - malitson.index(visible))) < 5e-5
    assert abs(caf2.abbe()[1] - malitson.abbe()[1]) < 0.3


def test_conrady_formula():
    """LightPath's NICHIA_MELT1, the Zemax AGF's formula 5 (Conrady, n = A0 + A1/λ + A2/λ^3.5), against the
    formula by hand, and on Dr.Jit arrays (the tracer's path) the same."""
    import drjit as dr  # the tracer's array type

    g = glass.resolve("NICHIA_MELT1")
    assert g.kind == "conrady" and g.name == "LIGHTPATH:NICHIA_MELT1"
    a = (1.47444837, 0.0103147698, 0.00026742387)
    for nm in (400.0, 587.5618, 1550.0):
        lam = nm / 1000
        assert g.index(nm) == pytest.approx(a[0] + a[1] / lam + a[2] / lam**3.5, abs=1e-15)
    waves = np.linspace(400.0, 1000.0, 7)
    traced = np.asarray(g.index_formula(dr.llvm.Float64(waves / 1000), dr.sqrt, dr.select))
    assert traced == pytest.approx(g.index(waves), abs=1e-15)


def test_the_shipped_catalogue_is_kept_parsed_and_read_back_as_its_toml_reads(fresh_cache, capsys):
    """The shipped catalogue's [glass] tables (`glass._entries`) are kept parsed in the cache folder
    (`caches.parsed_files`): a process that finds them there gets the same tables, in the same order, as
    tomllib reading the vendor files; a kept file that was changed is said so and parsed again."""
    import tomllib

    from solas_mi.optics import glass

    direct: dict = {}
    for file in glass.catalog_files():
        direct.update(tomllib.loads(file.read_text("utf-8"))["glass"])
    glass._entries.cache_clear()
    first = glass._entries(None)
    kept = list((fresh_cache / "glass").glob("*.marshal"))
    assert len(kept) == 1
    glass._entries.cache_clear()
    again = glass._entries(None)
    assert list(first.items()) == list(direct.items()) and list(again.items()) == list(direct.items())
    kept[0].write_bytes(kept[0].read_bytes()[:-9] + b"truncated")
    glass._entries.cache_clear()
    assert list(glass._entries(None).items()) == list(direct.items())
    assert "is not reused" in capsys.readouterr().err
    glass._entries.cache_clear()
