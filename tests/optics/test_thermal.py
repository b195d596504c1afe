"""A lens at a temperature and pressure (`optics.thermal`, `Lens.at`): the glass formula against the vendor's
published table, the air's index against Ciddor's equations, a thin singlet's focal shift against the
first-order thermal optics formula, and the default conditions changing nothing."""

import dataclasses
import math
import warnings

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.optics import glass, thermal
from solas_mi.optics.paraxial import paraxial

# SCHOTT's N-BK7 data sheet, "Temperature Coefficients of Refractive Index" (1e-6/K): the mean of dn/dT over
# each temperature range, relative to air and absolute, at 1060.0 nm, e (546.07 nm) and g (435.83 nm).
BK7_WAVELENGTHS_NM = (1060.0, 546.074, 435.835)
BK7_TABLE = {
    (-40.0, -20.0): ((2.4, 2.9, 3.3), (0.3, 0.8, 1.2)),
    (20.0, 40.0): ((2.4, 3.0, 3.5), (1.1, 1.6, 2.1)),
    (60.0, 80.0): ((2.5, 3.1, 3.7), (1.5, 2.1, 2.7)),
}


def _relative(name: str, wavelength_nm: float, temperature_c: float, pressure_kpa: float = 101.325) -> float:
    return float(glass.resolve(name).at(temperature_c, pressure_kpa).index(wavelength_nm))


def _absolute(name: str, wavelength_nm: float, temperature_c: float) -> float:
    return _relative(name, wavelength_nm, temperature_c) * thermal.air_index(
        wavelength_nm / 1000.0, temperature_c, 101.325
    )


@pytest.mark.parametrize("span", sorted(BK7_TABLE))
def test_n_bk7_against_the_data_sheet(span):
    """Mean dn/dT, relative and absolute, within 2e-7/K of the data sheet's (printed to 1e-7/K)."""
    (t1, t2), (relative, absolute) = span, BK7_TABLE[span]
    for w, rel, ab in zip(BK7_WAVELENGTHS_NM, relative, absolute):
        ours_rel = (_relative("N-BK7", w, t2) - _relative("N-BK7", w, t1)) / (t2 - t1)
        ours_abs = (_absolute("N-BK7", w, t2) - _absolute("N-BK7", w, t1)) / (t2 - t1)
        assert ours_rel == pytest.approx(rel * 1e-6, abs=2e-7), (w, span)
        assert ours_abs == pytest.approx(ab * 1e-6, abs=2e-7), (w, span)


# N-SF6's published coefficients (SCHOTT data sheet): Sellmeier B1-3, C1-3 (µm²) and the temperature
# formula's D0, D1, D2, E0, E1, λ_TK (µm); no data-sheet table of N-SF6 was found, so its mean dn_abs/dT is
# the integral of TIE-19's dn_abs/dT formula (the derivative form, a route independent of ours).
SF6_SELLMEIER = ((1.77931763, 0.338149866, 2.08734474), (0.0133714182, 0.0617533621, 174.01759))
SF6_THERMAL = (-4.93e-6, 7.02e-9, -2.4e-11, 9.84e-7, 1.54e-9, 0.29)


def _sf6_dn_abs_dt(wavelength_um: float, dt: np.ndarray) -> np.ndarray:
    l2 = wavelength_um**2
    n = math.sqrt(1 + sum(b * l2 / (l2 - c) for b, c in zip(*SF6_SELLMEIER)))
    d0, d1, d2, e0, e1, ltk = SF6_THERMAL
    return (n * n - 1) / (2 * n) * (d0 + 2 * d1 * dt + 3 * d2 * dt**2 + (e0 + 2 * e1 * dt) / (l2 - ltk**2))


@pytest.mark.parametrize("span", [(-40.0, -20.0), (20.0, 40.0), (60.0, 80.0), (80.0, 105.0)])
def test_n_sf6_against_the_published_formula(span):
    t1, t2 = span
    for w in (1060.0, 546.074, 435.835):
        dt = np.linspace(t1 - 20.0, t2 - 20.0, 2001)
        published = float(np.mean((_sf6_dn_abs_dt(w / 1000.0, dt)[1:] + _sf6_dn_abs_dt(w / 1000.0, dt)[:-1]) / 2))
        ours = (_absolute("N-SF6", w, t2) - _absolute("N-SF6", w, t1)) / (t2 - t1)
        assert ours == pytest.approx(published, abs=2e-9), (w, span)


def _ciddor(wavelength_um: float, temperature_c: float, pressure_pa: float) -> float:
    """Ciddor (1996, Appl. Opt. 35, 1566) for dry air with 450 ppm CO2: standard air's refractivity scaled by
    the density ratio, with the compressibility Z of his equation 12."""
    s2 = 1.0 / wavelength_um**2
    standard = 1e-8 * (5792105.0 / (238.0185 - s2) + 167917.0 / (57.362 - s2))

    def density(t_c: float, p: float) -> float:  # ∝ p/(Z T)
        t = t_c + 273.15
        z = 1 - p / t * (1.58123e-6 - 2.9331e-8 * t_c + 1.1043e-10 * t_c**2) + (p / t) ** 2 * 1.83e-11
        return p / (z * t)

    return 1.0 + standard * density(temperature_c, pressure_pa) / density(15.0, 101325.0)


def test_air_index_against_ciddor():
    """The vendors' air formula (SCHOTT TIE-19: Edlén 1953, scaled linearly in T) within 2e-7 of Ciddor's,
    0.06 % of the refractivity, over −40 … 105 °C and 80 … 110 kPa (measured worst 1.7e-7, at −40 °C and
    110 kPa, where the linear scaling and the compressibility Ciddor adds part most); within 3e-8 at 20 °C
    (the CO2 contents, 300 and 450 ppm, differ by 2e-8 alone)."""
    for w in (0.4358, 0.5461, 0.6563, 1.06):
        for t in (-40.0, 0.0, 20.0, 60.0, 105.0):
            for p in (80.0, 101.325, 110.0):
                ours, theirs = thermal.air_index(w, t, p), _ciddor(w, t, p * 1000.0)
                assert ours - 1.0 == pytest.approx(theirs - 1.0, rel=6e-4, abs=0), (w, t, p)
                assert abs(ours - theirs) < (3e-8 if t == 20.0 else 2e-7), (w, t, p)


def _singlet(material: str, thickness: float = 0.2, radius: float = 100.0) -> Lens:
    """A thin biconvex singlet, stop on its front face, image at its paraxial focus."""
    spec = {
        "name": "singlet",
        "wavelengths_nm": [587.5618],
        "surface": [
            {"radius": radius, "thickness": thickness, "diameter": 10.0, "material": material, "stop": True},
            {"radius": -radius, "thickness": 95.0, "diameter": 10.0, "material": "AIR"},
        ],
    }
    spec["surface"][1]["thickness"] = paraxial(Lens.from_dict(spec), 587.5618).bfd_mm
    return Lens.from_dict(spec)


@pytest.mark.parametrize("material", ["N-BK7", "N-SF6"])
@pytest.mark.parametrize("temperature", [-40.0, 105.0])
def test_thin_singlet_focal_shift(material, temperature):
    """Δf = −f·β·ΔT, β = (dn_rel/dT)/(n_rel − 1) − α_glass; the focus against an aluminium mount moves by
    −f·(β + α_mount)·ΔT: both within 1 %."""
    lens, w, delta = _singlet(material), 587.5618, temperature - 20.0
    hot = lens.at(temperature, mount="aluminium")
    g = glass.resolve(material)
    n = float(g.index(w))
    beta = (_relative(material, w, temperature) - n) / delta / (n - 1.0) - g.cte
    f0, f1 = paraxial(lens, w).efl_mm, paraxial(hot, w).efl_mm
    assert f1 - f0 == pytest.approx(-f0 * beta * delta, rel=0.01)
    focus = paraxial(hot, w).image_offset_mm - paraxial(lens, w).image_offset_mm  # image plane − paraxial focus
    assert -focus == pytest.approx(-f0 * (beta + thermal.MOUNTS["aluminium"]) * delta, rel=0.01)


@pytest.mark.parametrize(
    "name", ["solas-doublet", "cooke-triplet", "double-gauss-50mm", "nikkor-fisheye", "wide-angle-22mm"]
)
def test_default_conditions_are_the_lens_itself(name):
    """20 °C and 101.325 kPa: the very lens (every figure bit-identical), the same hash; its glasses the
    catalogue's own objects."""
    lens = Lens.load(name)
    assert lens.at() is lens and lens.at(20.0, 101.325, mount="steel") is lens
    assert all(s.glass.environment is None for s in lens.surfaces)


def test_default_conditions_leave_the_hash(tmp_path, doublet):
    """A lens file that states 20 °C and 101.325 kPa reads as the same lens, hash included (PSF caches)."""
    text = doublet.save(tmp_path / "d.toml").read_text()
    assert "temperature_c" not in text
    stated = tmp_path / "stated.toml"
    stated.write_text(text.replace("field_deg =", "temperature_c = 20.0\npressure_kpa = 101.325\nfield_deg ="))
    assert Lens.load(stated).hash == doublet.hash


def test_a_lens_at_a_temperature_writes_and_reads_back(tmp_path, doublet):
    hot = doublet.at(70.0, 95.0)
    again = Lens.load(hot.save(tmp_path / "hot.toml"))
    assert again.hash == hot.hash != doublet.hash
    assert paraxial(again, 531.0).efl_mm == paraxial(hot, 531.0).efl_mm
    back = again.at(20.0, 101.325)  # lengths are linear in T from 20 °C: there and back is the lens again
    assert back.hash == doublet.hash
    assert paraxial(back, 531.0).efl_mm == pytest.approx(paraxial(doublet, 531.0).efl_mm, rel=1e-13)


def test_pressure_alone_changes_indices_not_sizes(doublet):
    thin = doublet.at(20.0, 80.0)
    assert [s.radius for s in thin.surfaces] == [s.radius for s in doublet.surfaces]
    n0, n1 = doublet.indices(531.0)[1], thin.indices(531.0)[1]
    air = thermal.air_index(0.531, 20.0, 101.325), thermal.air_index(0.531, 20.0, 80.0)
    assert n1 == pytest.approx(n0 * air[0] / air[1], rel=1e-12)


def test_a_glass_without_thermal_data_is_named():
    lens = Lens.load("double-gauss-50mm")
    with pytest.warns(UserWarning, match=r"model:1\.603/38\b.*without thermal data"):
        lens.at(60.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lens.at(20.0, 90.0)  # pressure alone: every index follows its air, nothing held


@pytest.mark.parametrize(
    "temperature, pressure, mount",
    [
        (math.nan, 101.325, "aluminium"),
        (-300.0, 101.325, "aluminium"),
        (20.0, -1.0, "aluminium"),
        (25.0, 101.325, "wood"),
        (25.0, 101.325, 1.0),
        (25.0, 101.325, True),
        (25.0, 101.325, ["aluminium"]),
    ],
)
def test_bad_conditions_are_refused(doublet, temperature, pressure, mount):
    with pytest.raises(SolasError, match=r"temperature|pressure|mount"):
        doublet.at(temperature, pressure, mount)


def test_mount_per_gap_and_expansion(doublet):
    """Glass grows by its CTE, each gap by its own mount's."""
    delta = 50.0
    hot = doublet.at(20.0 + delta, mount=["none", "none", "none", 10e-6])
    s0, s1 = doublet.surfaces, hot.surfaces
    assert s1[0].radius == pytest.approx(s0[0].radius * (1 + glass.resolve("N-BK7").cte * delta), rel=1e-12)
    assert s1[1].thickness == pytest.approx(s0[1].thickness * (1 + glass.resolve("SCHOTT:F2").cte * delta), rel=1e-12)
    assert s1[2].thickness == s0[2].thickness
    assert s1[3].thickness == pytest.approx(s0[3].thickness * (1 + 10e-6 * delta), rel=1e-12)
    assert (
        dataclasses.replace(
            s1[0], radius=s0[0].radius, diameter=s0[0].diameter, thickness=s0[0].thickness, glass=s0[0].glass
        )
        == s0[0]
    )


def test_every_lens_command_takes_the_environment(capsys, tmp_path):
    """`lens info LENS --temperature-c 60 --pressure-kpa 90 --mount steel` is `Lens.at(60, 90, "steel")`,
    recorded in its JSON; without the options the lens file's own (nothing added to the JSON); `lens
    convert` writes the lens there, which reads back as it."""
    from strict_json import strict_loads

    from solas_mi.cli import main

    lens = Lens.load("solas-doublet")
    assert (
        main(
            [
                "lens",
                "info",
                "solas-doublet",
                "--json",
                "--temperature-c",
                "60",
                "--pressure-kpa",
                "90",
                "--mount",
                "steel",
            ]
        )
        == 0
    )
    info = strict_loads(capsys.readouterr().out)
    assert info["hash"] == lens.at(60.0, 90.0, "steel").hash
    assert (info["temperature_c"], info["pressure_kpa"]) == (60.0, 90.0)
    assert main(["lens", "info", "solas-doublet", "--json"]) == 0
    plain = strict_loads(capsys.readouterr().out)
    assert plain["hash"] == lens.hash and "temperature_c" not in plain
    assert main(["lens", "convert", "solas-doublet", "--temperature-c", "-40", "-o", str(tmp_path / "cold.zmx")]) == 0
    assert Lens.load(tmp_path / "cold.zmx").temperature_c == -40.0
    assert main(["lens", "info", "solas-doublet", "--temperature-c", "60"]) == 0
    assert "at 60 °C in air of 101.325 kPa" in capsys.readouterr().out
    assert main(["lens", "info", "solas-doublet", "--mount", "wood", "--temperature-c", "30"]) == 2
    assert "mount 'wood'" in capsys.readouterr().err
    assert main(["lens", "info", "solas-doublet", "--mount", "wood"]) == 2  # checked with no temperature too


def test_a_lens_file_names_the_mount_of_each_gap(tmp_path, doublet):
    """A surface's `mount` holds the gap after it (read, written back, used by `Lens.at` unless a call names
    one); a bad one is refused naming the surface."""
    text = doublet.save(tmp_path / "d.toml").read_text()
    rows = text.split("[[surface]]")
    rows[-1] = rows[-1].replace('material = "AIR"', 'material = "AIR"\nmount = 5e-6', 1)
    path = tmp_path / "mounted.toml"
    path.write_text("[[surface]]".join(rows))
    lens = Lens.load(path)
    assert lens.surfaces[-1].mount == 5e-6 and Lens.load(lens.save(tmp_path / "again.toml")).surfaces[-1].mount == 5e-6
    hot = lens.at(70.0)
    assert hot.surfaces[-1].thickness == pytest.approx(lens.surfaces[-1].thickness * (1 + 5e-6 * 50), rel=1e-12)
    assert hot.surfaces[2].thickness == pytest.approx(lens.surfaces[2].thickness * (1 + 23.6e-6 * 50), rel=1e-12)
    assert lens.at(70.0, mount="none").surfaces[-1].thickness == lens.surfaces[-1].thickness
    path.write_text(path.read_text().replace("mount = 5e-6", 'mount = "wood"'))
    with pytest.raises(SolasError, match=r"surface 4 .*mount 'wood'"):
        Lens.load(path)


def test_an_obsolete_schott_glass_has_its_catalogue_thermal_data():
    """SCHOTT's LAK33 (OpticStudio's 2008 catalogue, TD and ED lines): its index follows the temperature with
    the formula of those numbers, its CTE 6e-6/K; no warning for a lens of it."""
    g = glass.resolve("LAK33")
    assert g.thermal == (2.57e-06, 1.16e-08, -7.29e-11, 6.01e-07, 1.59e-10, 0.114) and g.cte == 6e-6
    n = float(g.index(587.5618))
    hot = _relative("LAK33", 587.5618, 60.0) * thermal.air_index(0.5875618, 60.0, 101.325)
    cold = n * thermal.air_index(0.5875618, 20.0, 101.325)
    assert hot - cold == pytest.approx(float(thermal.absolute_change(g.thermal, n, 0.5875618, 40.0)), rel=1e-9)
