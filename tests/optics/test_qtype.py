"""Forbes' Q-type aspheres: the Qbfs recurrence against the closed forms and the slope-orthonormality
that defines the polynomials, Qcon against scipy's Jacobi polynomials, the sag's slope against finite
differences, a Qbfs surface equal to a known even asphere traced alike, and .zmx QED_TYPE surfaces
(as OpticStudio writes them) against a paraxial hand calculation."""

import math

import numpy as np
import pytest
from scipy.special import eval_jacobi

from solas_mi import Lens, SolasError, paraxial
from solas_mi.optics import forbes
from solas_mi.optics import tracer as T
from solas_mi.optics.sag import sag, sag_slope
from solas_mi.optics.zemax import read_spec

QBFS = {"radius": 30.0, "conic": -0.7, "qbfs": [0.05, -0.02, 0.01, 0.004], "norm_radius": 9.0}


def test_qbfs_recurrence_equals_the_closed_forms():
    """Forbes 2007: Q0 = 1, Q1 = (13 − 16x)/√19, Q2 = 2(29 − 4x(25 − 19x))/√190."""
    x = np.linspace(0.0, 1.0, 11)
    closed = [np.ones_like(x), (13 - 16 * x) / math.sqrt(19), 2 * (29 - 4 * x * (25 - 19 * x)) / math.sqrt(190)]
    for m, q in enumerate(closed):
        value, slope = forbes.qbfs_sum(x, (0.0,) * m + (1.0,))
        assert np.abs(value - q).max() < 1e-13
        assert np.abs(slope - np.gradient(q, x, edge_order=2)).max() < 1e-10


def test_qbfs_slopes_are_orthonormal():
    """The definition: ⟨d/du[u²(1 − u²)Q_m] d/du[u²(1 − u²)Q_n]⟩ = δ_mn, weight 1/√(1 − u²)
    (Gauss–Chebyshev quadrature, u = cos θ), for m, n < 10."""
    theta = (np.arange(400) + 0.5) * math.pi / 800  # u = cos θ over (0, 1]: ∫ g(u)/√(1−u²) du = ∫ g(cos θ) dθ
    u = np.cos(theta)
    x = u * u
    slopes = []
    for m in range(10):
        q, dq = forbes.qbfs_sum(x, (0.0,) * m + (1.0,))
        slopes.append((2 * u - 4 * u**3) * q + x * (1 - x) * dq * 2 * u)  # d/du, chain rule x = u²
    gram = np.array([[np.sum(a * b) * (math.pi / 2 / 400) / (math.pi / 2) for b in slopes] for a in slopes])
    assert np.abs(gram - np.eye(10)).max() < 1e-9


def test_qcon_rewritten_as_even_terms_equals_the_jacobi_sum():
    a, rho = (1e-3, -4e-4, 2e-4, 1e-4, -5e-5, 2e-5), 7.5
    r = np.linspace(0.0, 8.0, 17)
    u2 = (r / rho) ** 2
    direct = u2 * u2 * sum(am * eval_jacobi(m, 0, 4, 2 * u2 - 1) for m, am in enumerate(a))
    even = forbes.qcon_to_even(a, rho)
    assert len(even) == len(a)
    assert np.abs(sag(r * r, 0.0, 0.0, tuple(even)) - direct).max() < 1e-15


def test_qbfs_sag_and_slope():
    """Sag: the conic plus φ x(1 − x) S(x), φ written out here; slope: central differences."""
    c, k, a, rho = 1 / QBFS["radius"], QBFS["conic"], tuple(QBFS["qbfs"]), QBFS["norm_radius"]
    r = np.linspace(0.0, 9.5, 20)
    x = (r / rho) ** 2
    s = sum(am * forbes.qbfs_sum(x, (0.0,) * m + (1.0,))[0] for m, am in enumerate(a))
    phi = np.sqrt((1 - k * c * c * r * r) / (1 - (1 + k) * c * c * r * r))
    expected = c * r * r / (1 + np.sqrt(1 - (1 + k) * c * c * r * r)) + phi * x * (1 - x) * s
    assert np.abs(sag(r * r, c, k, qbfs=a, norm_radius=rho) - expected).max() < 1e-14
    h, r = 1e-4, r[1:]  # r > 0: the difference quotient in r²
    numeric = sag((r + h) ** 2, c, k, qbfs=a, norm_radius=rho) - sag((r - h) ** 2, c, k, qbfs=a, norm_radius=rho)
    numeric /= (r + h) ** 2 - (r - h) ** 2
    assert np.abs(sag_slope(r * r, c, k, qbfs=a, norm_radius=rho) - numeric).max() < 1e-8


def _as_qbfs(c: float, a4: float, a6: float, rho: float) -> list[float]:
    """Qbfs coefficients (flat base, φ = 1) whose departure is the polynomial c r²/2 + A4 r⁴ + A6 r⁶:
    a least-squares fit on the Q basis, exact to rounding when the polynomial lies in its span."""
    x = np.linspace(0.0, 1.2, 40)
    basis = np.stack([x * (1 - x) * forbes.qbfs_sum(x, (0.0,) * m + (1.0,))[0] for m in range(2)], -1)
    target = c / 2 * rho**2 * x + a4 * rho**4 * x**2 + a6 * rho**6 * x**3
    coefficients, *_ = np.linalg.lstsq(basis, target, rcond=None)
    assert np.abs(basis @ coefficients - target).max() < 1e-14
    return [float(v) for v in coefficients]


def test_a_qbfs_surface_equal_to_an_even_asphere_traces_alike():
    """A paraboloid with r⁴ and r⁶ terms is a polynomial in r²; a flat-based Qbfs surface holding the
    same polynomial must give the same EFL and the same traced rays."""
    c, a4, rho = 1 / 40.0, -2e-5, 10.0
    a6 = -(a4 * rho**4 + c * rho**2 / 2) / rho**6  # what x(1 − x)(s0 + s1 x) forces
    back = {"radius": -80.0, "thickness": 60.0, "diameter": 18.0}
    even = {"radius": 40.0, "conic": -1.0, "aspheric": [a4, a6]}
    qbfs = {"radius": 0.0, "qbfs": _as_qbfs(c, a4, a6, rho), "norm_radius": rho}
    lenses = [
        Lens.from_dict(
            {
                "wavelengths_nm": [587.5618],
                "field_deg": 5.0,
                "surface": [{"thickness": 5.0, "diameter": 18.0, "material": "N-BK7", "stop": True, **front}, back],
            }
        )
        for front in (even, qbfs)
    ]
    assert lenses[1].surfaces[0].paraxial_curvature == pytest.approx(c, rel=1e-14)
    efl = [paraxial(lens).efl_mm for lens in lenses]
    assert efl[1] == pytest.approx(efl[0], rel=1e-12)
    ex, ey = np.meshgrid(np.linspace(-8, 8, 9), np.linspace(-8, 8, 9))
    out = []
    for lens in lenses:
        rays = T.launch(
            lens,
            T.F(0.0 * ex.ravel()),
            T.F(0.0 * ex.ravel() + math.tan(math.radians(5))),
            T.F(ex.ravel()),
            T.F(ey.ravel()),
        )
        tr = T.trace(lens, rays, T.F(0.5875618))
        out.append(np.stack(T.to_numpy(*T.to_plane(tr, lens.image_z)[:2], tr.ok), -1))
    assert out[0][:, 2].all() and out[1][:, 2].all()
    assert np.abs(out[0] - out[1]).max() < 1e-9


def test_qbfs_trace_lands_on_the_surface():
    lens = Lens.from_dict(
        {"surface": [{"thickness": 10.0, "diameter": 18.0, "material": "N-BK7", "stop": True, **QBFS}]}
    )
    s = lens.surfaces[0]
    rng = np.random.default_rng(3)
    ex, ey = rng.uniform(-6, 6, 100), rng.uniform(-6, 6, 100)
    rays = T.launch(lens, T.F(np.full(100, 0.1)), T.F(np.full(100, -0.05)), T.F(ex), T.F(ey))
    tr = T.trace(lens, rays, T.F(0.5876))
    x, y, z, ok = T.to_numpy(tr.rays.x, tr.rays.y, tr.rays.z, tr.ok)
    assert ok.all()
    assert np.abs(z - s.sag(np.hypot(x, y))).max() < 1e-12


def _zmx(kind: int, terms: list[float], rho: float, conic: float = 0.0) -> str:
    xdat = "\n".join(f'  XDAT {k} {v!r} 0 0 1 0 0 ""' for k, v in enumerate([kind, len(terms), rho, *terms], 1))
    return f"""VERS 200914
UNIT MM X W X CM MR CPMM
ENPD 10
FTYP 0 0 1 1 0 0 0 1
XFLN 0
YFLN 0
WAVM 1 0.5875618 1
PWAV 1
SURF 0
  DISZ INFINITY
SURF 1
  STOP
  TYPE QED_TYPE
  CURV 0.04 0 0 0 0 ""
{xdat}
  DISZ 4
  GLAS ___BLANK 1 0 1.5 0 0 0
  CONI {conic!r}
  DIAM 6 1 0 0 1 ""
SURF 2
  DISZ 40
  DIAM 6 1 0 0 1 ""
SURF 3
  DISZ 0
"""


def test_zmx_qbfs_surface_bends_the_vertex():
    """OpticStudio's layout (XDAT 1 type 0, 2 terms, 3 ρ, 4… a_m): the paraxial power of the plano-convex
    lens is (n − 1)(c + 2 Σ a_m Q_m(0)/ρ²), Q_m(0) = 1, 13/√19, 58/√190."""
    a, rho = [0.3, -0.1, 0.02], 8.0
    spec = read_spec(_zmx(0, a, rho, conic=-0.5), "q.zmx")
    row = spec["surface"][0]
    assert row["qbfs"] == a and row["norm_radius"] == rho and row["conic"] == -0.5
    lens = Lens.from_dict(spec)
    bend = a[0] + a[1] * 13 / math.sqrt(19) + a[2] * 58 / math.sqrt(190)
    assert paraxial(lens).efl_mm == pytest.approx(1 / (0.5 * (0.04 + 2 * bend / rho**2)), rel=1e-12)


def test_zmx_qcon_surface_is_its_even_asphere(tmp_path):
    a, rho = [2e-3, -5e-4, 1e-4], 6.0
    lens = Lens.from_dict(read_spec(_zmx(1, a, rho), "q.zmx"))
    r = np.linspace(0.0, 6.0, 13)
    u2 = (r / rho) ** 2
    direct = 0.04 * r * r / (1 + np.sqrt(1 - (0.04 * r) ** 2))
    direct += u2 * u2 * sum(am * eval_jacobi(m, 0, 4, 2 * u2 - 1) for m, am in enumerate(a))
    assert np.abs(lens.surfaces[0].sag(r) - direct).max() < 1e-15


def test_qbfs_lens_round_trips_through_toml_and_zmx(tmp_path):
    lens = Lens.from_dict(
        {
            "surface": [
                {"thickness": 5.0, "diameter": 18.0, "material": "N-BK7", "stop": True, **QBFS},
                {"radius": -60.0, "thickness": 40.0, "diameter": 18.0},
            ]
        }
    )
    for suffix in (".toml", ".zmx"):
        again = Lens.load(lens.save(tmp_path / f"q{suffix}"))
        assert again.surfaces[0].qbfs == lens.surfaces[0].qbfs
        assert again.surfaces[0].norm_radius == lens.surfaces[0].norm_radius
        assert again.hash == lens.hash


def test_qbfs_needs_its_normalisation_radius():
    with pytest.raises(SolasError, match="norm_radius"):
        Lens.from_dict(
            {
                "surface": [
                    {
                        "radius": 30.0,
                        "thickness": 5.0,
                        "diameter": 10.0,
                        "stop": True,
                        "material": "N-BK7",
                        "qbfs": [0.1],
                    }
                ]
            }
        )
    with pytest.raises(SolasError, match="type 0 .Qbfs. or 1 .Qcon."):
        read_spec(_zmx(2, [0.1], 5.0), "q.zmx")
