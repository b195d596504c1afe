"""Symmetric tolerances (`optics.tolerance`, `optics.melt`): each kind moves what it says by the amount it
says (checked by another route: the sag, the glass's own n_d/V_d, a paraxial matrix), draws are reproducible
from (seed, index) alone, drawn lenses survive their lens files, and a bad entry is refused by name."""

import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.optics import tolerance as tol
from solas_mi.optics.glass import LINE_C, LINE_D, LINE_F

ALL_KINDS = [
    {"kind": "radius", "surfaces": "all", "fringes": 2.0},
    {"kind": "thickness", "surfaces": "all", "mm": 0.02, "distribution": "uniform"},
    {"kind": "index", "surfaces": "all", "delta": 5e-4, "truncate": 2.0},
    {"kind": "abbe", "surfaces": "all", "percent": 0.5},
    {"kind": "irregularity", "surfaces": [1, 4], "fringes": 0.5},
    {"kind": "despace", "mm": 0.01},
]


@pytest.fixture(scope="module")
def cooke():
    return Lens.load("cooke-triplet")


@pytest.fixture(scope="module")
def spec(cooke):
    return tol.spec_from_dict(cooke, {"tolerance": ALL_KINDS})


def _paraxial_efl_and_derivative(lens, wavelength_nm: float, surface: int) -> tuple[float, float]:
    """EFL and dEFL/dR of surface `surface` (0-based) by the reduced (y, n·u) matrices: refraction
    [[1, 0], [−(n'−n) c, 1]], transfer [[1, t/n'], [0, 1]]; EFL = −1/M[1, 0], d/dc from the refraction's
    derivative [[0, 0], [−(n'−n), 0]] in its place, dc/dR = −1/R²."""
    n = lens.indices(wavelength_nm)

    def system(derivative_at: int | None) -> np.ndarray:
        m = np.eye(2)
        for i, s in enumerate(lens.surfaces):
            power = n[i + 1] - n[i]
            bend = (
                np.array([[0.0, 0.0], [-power, 0.0]])
                if i == derivative_at
                else np.array([[1.0, 0.0], [-power * s.curvature, 1.0]])
            )
            m = bend @ m
            if i < len(lens.surfaces) - 1:
                m = np.array([[1.0, s.thickness / n[i + 1]], [0.0, 1.0]]) @ m
        return m

    c10, dc10 = system(None)[1, 0], system(surface)[1, 0]
    radius = lens.surfaces[surface].radius
    return -1.0 / c10, dc10 / c10**2 * (-1.0 / radius**2)


def test_radius_sensitivity_of_efl_is_the_analytic_derivative(cooke):
    """The sensitivity table's dEFL/dR (central difference of ±1e-3 % of R) against the derivative of the
    paraxial system matrix: within 1e-6 relative, on every surface."""
    spec = tol.spec_from_dict(cooke, {"tolerance": [{"kind": "radius", "surfaces": "all", "percent": 1e-3}]})
    rows = tol.paraxial_sensitivity(cooke, spec)
    for i, row in enumerate(rows):
        efl, derivative = _paraxial_efl_and_derivative(cooke, cooke.primary_wavelength, i)
        assert row["term"] == f"radius s{i + 1}"
        assert efl == pytest.approx(0.5 * (row["efl_mm_minus"] + row["efl_mm_plus"]), rel=1e-8)
        assert row["defl_dparameter"] == pytest.approx(derivative, rel=1e-6)


def test_fringes_of_power_and_irregularity_move_the_sag_at_the_rim(cooke):
    """N fringes at λ: the sag at the semi-diameter moves by N λ/2 (toward the centre of curvature's side);
    an irregularity leaves the vertex and the paraxial curvature alone."""
    wavelength_mm = 632.8e-6
    for kind in ("radius", "irregularity"):
        spec = tol.spec_from_dict(cooke, {"tolerance": [{"kind": kind, "surfaces": "all", "fringes": 1.0}]})
        for k, term in enumerate(spec.terms):
            before = cooke.surfaces[term.surface]
            for sign in (-1.0, 1.0):
                after = tol.alone(cooke, spec, k, sign).surfaces[term.surface]
                y = before.semi_diameter
                moved = (after.sag(y) - before.sag(y)) * math.copysign(1.0, before.radius)
                assert moved == pytest.approx(sign * 0.5 * wavelength_mm, rel=1e-9)
                if kind == "irregularity":
                    assert after.radius == before.radius and after.sag(0.0) == 0.0


def test_a_melt_has_the_asked_nd_and_vd_and_keeps_the_partial_dispersion(cooke):
    spec = tol.spec_from_dict(
        cooke,
        {
            "tolerance": [
                {"kind": "index", "surfaces": [3], "delta": 1e-3},
                {"kind": "abbe", "surfaces": [3], "delta": 0.5},
            ]
        },
    )
    before = cooke.surfaces[2].glass
    after = tol.perturbed(cooke, spec, [1e-3, -0.5]).surfaces[2].glass
    nd, vd = before.abbe()
    assert after.abbe() == pytest.approx((nd + 1e-3, vd - 0.5), rel=1e-12)

    def partial(g):  # P_g,F: (n_g − n_F) / (n_F − n_C), g = 435.8343 nm
        return (g.index(435.8343) - g.index(LINE_F)) / (g.index(LINE_F) - g.index(LINE_C))

    assert partial(after) == pytest.approx(partial(before), rel=1e-12)
    assert after.index(LINE_D) == pytest.approx(before.index(LINE_D) + 1e-3, abs=1e-14)


def test_model_glass_melts_to_the_model_glass_of_its_new_values():
    lens = Lens.from_dict(
        {
            "surface": [
                {"radius": 50.0, "thickness": 5.0, "diameter": 20.0, "material": "model:1.6/40"},
                {"radius": -50.0, "thickness": 45.0, "diameter": 20.0, "stop": True},
            ]
        }
    )
    spec = tol.spec_from_dict(
        lens,
        {
            "tolerance": [
                {"kind": "index", "surfaces": [1], "delta": 2e-3},
                {"kind": "abbe", "surfaces": [1], "percent": 1.0},
            ]
        },
    )
    moved = tol.perturbed(lens, spec, [2e-3, 1.0])
    assert moved.surfaces[0].glass.abbe() == pytest.approx((1.602, 40.4), rel=1e-12)
    assert Lens.from_dict(
        {
            "surface": [
                {"radius": 1.0, "thickness": 1.0, "diameter": 1.0, "stop": True, "material": moved.surfaces[0].material}
            ]
        }
    ).surfaces[0].glass.abbe() == pytest.approx((1.602, 40.4), rel=1e-12)


def test_a_sample_is_its_seed_and_index_alone(cooke, spec):
    """Sample i is the same drawn alone, after others or in another order; another seed or index differs."""
    forward = [tol.draw(cooke, spec, 7, i)[0].hash for i in range(4)]
    backward = [tol.draw(cooke, spec, 7, i)[0].hash for i in reversed(range(4))][::-1]
    assert forward == backward and len(set(forward)) == 4
    assert tol.draw(cooke, spec, 8, 0)[0].hash not in forward
    deltas = tol.draw_deltas(spec, 7, 2)
    for term, delta in zip(spec.terms, deltas):
        bound = term.value * (term.truncate if term.distribution == "normal" else 1.0)
        assert 0 < abs(delta) <= bound


def test_a_drawn_lens_survives_its_lens_file(cooke, spec, tmp_path):
    drawn, _ = tol.draw(cooke, spec, 1, 0)
    assert drawn.hash != cooke.hash
    again = Lens.load(drawn.save(tmp_path / "sample.toml"))
    assert again.hash == drawn.hash
    for a, b in zip(again.surfaces, drawn.surfaces):
        if b.glass.kind != "air":
            assert a.glass.index(LINE_F) == b.glass.index(LINE_F)


@pytest.mark.parametrize(
    "entry, named",
    [
        ({"kind": "decentre", "surfaces": [1, 3], "mm": 0.01}, "decentre"),
        ({"kind": "tilt", "surfaces": [1], "mm": 0.01}, "tilt"),
        ({"kind": "sensor_tilt", "mm": 0.01}, "sensor_tilt"),
        ({"kind": "wedge", "surfaces": [1], "mm": 0.01}, "wedge"),
        ({"kind": "radius", "surfaces": [1]}, "one of fringes, percent"),
        ({"kind": "radius", "surfaces": [1], "fringes": 1.0, "percent": 1.0}, "exactly one"),
        ({"kind": "radius", "surfaces": [1], "fringes": -1.0}, "fringes = -1.0"),
        ({"kind": "radius", "surfaces": [1], "fringes": 1.0, "sigma": 1.0}, "sigma"),
        ({"kind": "radius", "surfaces": [9], "fringes": 1.0}, "surfaces = [9]"),
        ({"kind": "radius", "surfaces": [1], "fringes": 1.0, "distribution": "cauchy"}, "cauchy"),
        ({"kind": "radius", "surfaces": [1], "fringes": 1.0, "distribution": "uniform", "truncate": 2.0}, "truncate"),
        ({"kind": "index", "surfaces": [2], "delta": 1e-4}, "index on surface 2"),
        ({"kind": "thickness", "surfaces": [6], "mm": 0.01}, "despace"),
        ({"kind": "despace", "surfaces": [6], "mm": 0.01}, "takes no surfaces"),
    ],
)
def test_bad_entries_are_refused_by_name(cooke, entry, named):
    with pytest.raises(SolasError, match="tolerance 1") as caught:
        tol.spec_from_dict(cooke, {"tolerance": [entry]})
    assert named in str(caught.value)


@pytest.mark.parametrize(
    "table, named",
    [
        ({"tolerance": [], "extra": 1}, "extra"),
        ({"tolerance": []}, "no [[tolerance]]"),
        ({"compensator": {"back_focus": "autofocus"}, "tolerance": ALL_KINDS}, "autofocus"),
        ({"tolerance": ALL_KINDS[:1] * 2}, "radius s1"),
        ({"test_wavelength_nm": 0, "tolerance": ALL_KINDS}, "test_wavelength_nm"),
    ],
)
def test_bad_files_are_refused_by_name(cooke, table, named):
    with pytest.raises(SolasError) as caught:
        tol.spec_from_dict(cooke, table)
    assert named in str(caught.value)


def test_percent_of_a_flat_radius_is_refused(cooke):
    flat = Lens.from_dict(
        {
            "surface": [
                {"radius": 0.0, "thickness": 5.0, "diameter": 20.0, "material": "N-BK7"},
                {"radius": -50.0, "thickness": 95.0, "diameter": 20.0, "stop": True},
            ]
        }
    )
    with pytest.raises(SolasError, match="surface 1.*flat"):
        tol.spec_from_dict(flat, {"tolerance": [{"kind": "radius", "surfaces": [1], "percent": 1.0}]})
    fringes = tol.spec_from_dict(flat, {"tolerance": [{"kind": "radius", "surfaces": "all", "fringes": 1.0}]})
    assert [t.name for t in fringes.terms] == ["radius s1", "radius s2"]  # fringes bend a flat


def test_draws_follow_their_distributions(cooke):
    """4000 samples: a normal truncated at k σ has the standard deviation σ √(1 − 2 k φ(k) / (2 Φ(k) − 1)) and
    nothing beyond k σ; a uniform of limit L has L/√3 and nothing beyond L (within 4 sampling errors)."""
    spec = tol.spec_from_dict(
        cooke,
        {
            "tolerance": [
                {"kind": "thickness", "surfaces": [1], "mm": 0.02, "truncate": 1.5},
                {"kind": "thickness", "surfaces": [2], "mm": 0.03, "distribution": "uniform"},
                {"kind": "despace", "mm": 0.01},
            ]
        },
    )
    draws = np.array([tol.draw_deltas(spec, 3, i) for i in range(4000)])
    k = 1.5
    phi, big_phi = math.exp(-k * k / 2) / math.sqrt(2 * math.pi), 0.5 * (1 + math.erf(k / math.sqrt(2)))
    expected = [0.02 * math.sqrt(1 - 2 * k * phi / (2 * big_phi - 1)), 0.03 / math.sqrt(3), 0.01]
    for column, sigma, bound in zip(draws.T, expected, (0.03, 0.03, 0.03)):
        assert abs(column.mean()) < 4 * sigma / math.sqrt(len(column))
        assert column.std() == pytest.approx(sigma, rel=4 / math.sqrt(2 * len(column)))
        assert np.abs(column).max() <= bound


def test_a_draw_that_cannot_be_built_is_refused_naming_the_sample(cooke):
    """The front crown (3.26 mm at the centre, about 0.74 mm at its rim) drawn 0.9 mm thinner: its faces cross."""
    spec = tol.spec_from_dict(
        cooke, {"tolerance": [{"kind": "thickness", "surfaces": [1], "mm": 1.0, "distribution": "uniform"}]}
    )
    seed = next(s for s in range(100) if tol.draw_deltas(spec, s, 0)[0] < -0.9)
    with pytest.raises(SolasError, match=f"tolerance sample 0 of seed {seed}: .*cannot be built"):
        tol.draw(cooke, spec, seed, 0)
