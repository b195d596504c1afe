import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.optics import glass

# Schott catalogue values n_d, V_d: a check on every coefficient in the catalogue.
CATALOG = {
    "N-BK7": (1.51680, 64.17), "F2": (1.62004, 36.37), "N-SF5": (1.67271, 32.25), "N-SK16": (1.62041, 60.32),
    "N-LAK9": (1.69100, 54.71), "N-SF11": (1.78472, 25.68), "F5": (1.60342, 38.03), "N-BAF10": (1.67003, 47.11),
    "N-SSK8": (1.61773, 49.83),
}


@pytest.mark.parametrize("name", sorted(CATALOG))
def test_catalogue_reproduces_nd_vd(name):
    nd, vd = glass.resolve(name).abbe()
    assert nd == pytest.approx(CATALOG[name][0], abs=2e-5)
    assert vd == pytest.approx(CATALOG[name][1], abs=0.02)


def test_design_indices():
    """DESIGN.md's indices at the three design wavelengths."""
    bk7, f2 = glass.resolve("BK7"), glass.resolve("F2")
    assert bk7.index([486, 531, 656]) == pytest.approx([1.5223859, 1.5195281, 1.5143308], abs=1e-7)
    assert f2.index([486, 531, 656]) == pytest.approx([1.6321030, 1.6258107, 1.6150484], abs=1e-7)


def test_bk7_is_schott_n_bk7():
    assert glass.resolve("BK7") is glass.resolve("SCHOTT:N-BK7") is glass.resolve("n-bk7")


def test_model_glass_has_given_nd_vd():
    nd, vd = glass.resolve("model:1.62/36.4").abbe()
    assert (nd, vd) == pytest.approx((1.62, 36.4), abs=1e-9)


def test_unknown_glass_is_named():
    with pytest.raises(SolasError, match="unknown glass 'N-BK8'"):
        glass.resolve("N-BK8")


def test_ambiguous_name_fails(tmp_path):
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
    with pytest.raises(SolasError, match="unknown glass 'model:1.2.3/40'"):
        glass.resolve("model:1.2.3/40")
