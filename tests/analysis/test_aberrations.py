"""The aberration analyses against closed forms: a defocused ideal lens (its wavefront's Zernike Z4, its
ray and OPD fans, its spot, its flat field), a plane-parallel plate in a converging beam (its
sagittal and tangential focus shifts, and the through-focus MTF peaking at them), distortion of an
ideal lens, the diffraction-limited encircled energy; the Zernike polynomials themselves."""

import math

import numpy as np
import pytest
from ideal_lenses import WL, ideal_lens

from solas_mi.analysis.distortion import distortion
from solas_mi.analysis.energy import encircled_energy
from solas_mi.analysis.fans import opd_fan, ray_fan
from solas_mi.analysis.field_curvature import field_curvature
from solas_mi.analysis.spots import spot_diagram
from solas_mi.analysis.through_focus import through_focus
from solas_mi.analysis.wavefront import wavefront
from solas_mi.analysis.zernike import fringe_index, noll_index, polynomial
from solas_mi.errors import SolasError
from solas_mi.optics.lens import Lens


def defocus_wavefront(h: np.ndarray, f: float, defocus: float) -> np.ndarray:
    """W (waves) = OPL(chief) − OPL(ray) on the reference sphere (centre: the image point on the axis δ
    behind the focus F, through the lens centre) of the ray from stop height h toward F: every ray has
    one optical path to F, so W = |Q − F| − f, Q where the ray meets the sphere."""
    big_r = f + defocus
    out = []
    for hi in np.atleast_1d(h):
        u = np.array([-hi, f]) / math.hypot(hi, f)
        d = np.array([hi, -big_r])
        t = -(d @ u) - math.sqrt((d @ u) ** 2 - hi * hi)
        q = np.array([hi, 0.0]) + t * u
        out.append((math.hypot(q[0], q[1] - f) - f) / (WL * 1e-6))
    return np.array(out)


@pytest.mark.parametrize("kind, scale", [("fringe", 1.0), ("noll", 1.0 / math.sqrt(3.0))])
def test_a_pure_defocus_has_its_analytic_z4(kind, scale):
    """An ideal f/8 lens with the image plane 1 mm beyond focus: its wavefront is a defocus; the Fringe
    Z4 (2ρ² − 1) coefficient of W(ρ) is 6 ∫₀¹ W (2ρ² − 1) ρ dρ (the projection; W's higher terms are
    other Zernikes), by Gauss-Legendre quadrature of the exact W; Noll's Z4 is √3 (2ρ² − 1)."""
    f, n, defocus = 100.0, 8.0, 1.0
    nodes, weights = np.polynomial.legendre.leggauss(200)
    rho = (nodes + 1.0) / 2.0
    w = defocus_wavefront(rho * f / n / 2.0, f, defocus)
    expected = 6.0 * np.dot(weights / 2.0, w * (2 * rho**2 - 1) * rho) * scale
    result = wavefront(ideal_lens(f, n, defocus), fields_deg=[0.0], pupil_samples=64, zernike=kind)
    assert expected * (math.sqrt(3.0) if kind == "noll" else 1.0) > 1.5  # waves: a real defocus
    assert result.coefficients[0, 3] == pytest.approx(expected, abs=1e-6)
    assert np.abs(result.coefficients[0, [1, 2, 4, 5, 6, 7]]).max() < 1e-9  # no tilt, astigmatism or coma


def test_the_fans_of_a_defocused_ideal_lens():
    """A ray from stop height h meets the plane δ beyond the ideal lens's focus at −h δ/f from the chief
    ray, at any field; on the axis its W is the exact defocus wavefront."""
    f, n, defocus = 100.0, 8.0, 0.5
    r = f / n / 2.0
    rays = ray_fan(ideal_lens(f, n, defocus), fields_deg=[0.0, 3.0], fan_samples=11)
    expected = -rays.pupil * r * defocus / f * 1e3
    for field in range(2):
        assert rays.tangential[field, 0] == pytest.approx(expected, abs=1e-9)
        assert rays.sagittal[field, 0] == pytest.approx(expected, abs=1e-9)
    opd = opd_fan(ideal_lens(f, n, defocus), fields_deg=[0.0], fan_samples=11)
    assert opd.tangential[0, 0] == pytest.approx(defocus_wavefront(opd.pupil * r, f, defocus), abs=1e-8)


def test_the_spot_of_a_defocused_ideal_lens():
    """Hexapolar rings i = 1 … R of 6i rays at ρ = i/R land at −ρ r δ/f: RMS radius² = b² Σ 6i (i/R)² /
    (1 + Σ 6i), b = r δ/f; at focus every ray meets the chief ray. Off the axis `optics.spot` fills the
    disc inscribed in the pupil seen across the beam (radius r cos θ), which reaches the stop's rim in y
    and r cos θ in x: the RMS radius² then has a factor (1 + cos² θ)/2."""
    f, n, defocus, rings = 100.0, 8.0, 0.5, 6
    b = f / n / 2.0 * defocus / f * 1e3
    i = np.arange(1, rings + 1)
    rms = b * math.sqrt(np.sum(6 * i * (i / rings) ** 2) / (1 + np.sum(6 * i)))
    result = spot_diagram(ideal_lens(f, n, defocus), fields_deg=[0.0, 4.0], rings=rings)
    radii = result.radii()
    assert radii["0"]["all"]["rms_um"] == pytest.approx(rms, rel=1e-9)
    oblique = math.sqrt((1 + math.cos(math.radians(4.0)) ** 2) / 2)
    assert radii["4"]["all"]["rms_um"] == pytest.approx(rms * oblique, rel=1e-9)
    assert spot_diagram(ideal_lens(f, n), fields_deg=[4.0]).radii()["4"]["all"]["geo_um"] < 1e-9


def plate_lens(f=50.0, n=1.5, t=5.0, field=20.0) -> Lens:
    """An ideal lens (stop, f/10), then a plate of index n, thickness t 10 mm behind it; the image plane
    at the on-axis focus, f + t (1 − 1/n)."""
    return Lens.from_dict(
        {
            "name": "plate",
            "wavelengths_nm": [WL],
            "field_deg": field,
            "surface": [
                {"radius": 0.0, "thickness": 10.0, "diameter": f / 10.0, "stop": True, "focal_length": f},
                {"radius": 0.0, "thickness": t, "diameter": 40.0, "material": f"model:{n}"},
                {"radius": 0.0, "thickness": f + t * (1 - 1 / n) - 10.0 - t, "diameter": 40.0},
            ],
        }
    )


def plate_foci(theta: np.ndarray, n: float, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Axial shifts of the tangential and sagittal foci of a pencil crossing a plate at angle θ: each ray
    is displaced by d(θ) = t sin(θ − θ')/cos θ' across itself; the sagittal pair meets on the axis through
    the focus moved by d/sin θ, the tangential pair at the envelope, moved by d' cos θ + d sin θ."""

    def d(a):
        return t * (np.sin(a) - np.cos(a) * np.sin(a) / np.sqrt(n * n - np.sin(a) ** 2))

    step = 1e-6
    derivative = (d(theta + step) - d(theta - step)) / (2 * step)
    tangential = derivative * np.cos(theta) + d(theta) * np.sin(theta)
    with np.errstate(invalid="ignore", divide="ignore"):
        sagittal = np.where(theta > 0, d(theta) / np.sin(theta), t * (1 - 1 / n))
    return tangential, sagittal


def test_field_curvature_of_a_plate_in_a_converging_beam():
    """The plate's foci (`plate_foci`) about the image plane at its on-axis focus; an ideal lens alone
    has a flat field (T = S = −δ)."""
    n, t = 1.5, 5.0
    result = field_curvature(plate_lens(n=n, t=t), field_samples=5)
    tangential, sagittal = plate_foci(np.radians(result.fields_deg), n, t)
    assert result.tangential_mm[0] == pytest.approx(tangential - t * (1 - 1 / n), abs=1e-7)
    assert result.sagittal_mm[0] == pytest.approx(sagittal - t * (1 - 1 / n), abs=1e-7)
    assert result.tangential_mm[0, -1] - result.sagittal_mm[0, -1] > 0.2  # 20°: 0.22 mm of astigmatism
    flat = field_curvature(ideal_lens(50.0, 8.0, 0.25, field=10.0), field_samples=4)
    assert flat.tangential_mm == pytest.approx(-0.25, abs=1e-9) and flat.sagittal_mm == pytest.approx(-0.25, abs=1e-9)


def test_the_through_focus_mtf_peaks_at_the_tangential_and_sagittal_foci():
    """Where the plate makes the foci part (20°), the tangential MTF (along y) peaks near the tangential
    focus and the sagittal near the sagittal: the directions are what they say, from two routes (ray
    pairs, pupil autocorrelation), within 10 % of the foci's separation."""
    n, t = 1.5, 5.0
    lens = plate_lens(n=n, t=t)
    tangential, sagittal = (v[0] * 1e3 - t * (1 - 1 / n) * 1e3 for v in plate_foci(np.radians([20.0]), n, t))
    result = through_focus(
        lens, frequency_cy_mm=10.0, fields_deg=[20.0], focus_range_um=450.0, focus_steps=31, pupil_samples=96
    )
    best = result.best_focus_um()["20"]
    separation = abs(tangential - sagittal)
    assert abs(best["tangential"] - tangential) < 0.1 * separation
    assert abs(best["sagittal"] - sagittal) < 0.1 * separation


def test_an_ideal_lens_has_no_f_tan_distortion():
    """The chief ray through the ideal lens's centre lands at (f + δ) tan θ: no distortion against f tan θ
    (the scale taken on the image plane), and (tan θ − θ)/θ against f θ."""
    result = distortion(ideal_lens(50.0, 8.0, 0.3, field=30.0), field_samples=7)
    theta = np.radians(result.fields_deg)
    assert np.abs(result.f_tan_percent).max() < 1e-9
    assert result.f_theta_percent[1:] == pytest.approx((np.tan(theta[1:]) - theta[1:]) / theta[1:] * 100, abs=1e-9)
    assert result.projection == "rectilinear" and result.scale_mm == pytest.approx(50.3, rel=1e-12)


def bessel(order: int, x: np.ndarray) -> np.ndarray:
    """J_n(x) = (1/π) ∫₀^π cos(nτ − x sin τ) dτ (Gauss-Legendre)."""
    nodes, w = np.polynomial.legendre.leggauss(200)
    tau = (nodes + 1.0) * math.pi / 2.0
    return np.cos(order * tau[None, :] - np.asarray(x)[:, None] * np.sin(tau[None, :])) @ w / 2.0


def test_encircled_energy_of_a_diffraction_limited_lens_is_rayleighs():
    """EE(r) = 1 − J0(v)² − J1(v)², v = π r/(λN) (Lord Rayleigh, 1881), for an aberration-free f/16 lens
    about its centroid, within 3e-3."""
    result = encircled_energy(ideal_lens(100.0, 16.0), fields_deg=[0.0], pupil_samples=128)
    v = np.pi * result.radius_um / (WL * 1e-3 * 16.0)
    expected = 1 - bessel(0, v) ** 2 - bessel(1, v) ** 2
    assert np.abs(result.encircled[0, 0] - expected).max() < 3e-3


def test_noll_terms_are_orthonormal_and_fringe_terms_in_their_order():
    """Noll's first 21 terms have unit RMS and are orthogonal over the disc (polar Gauss quadrature);
    Fringe's first nine are piston, x and y tilt, defocus, astigmatism 0 and 45, coma x and y, spherical."""
    nodes, w = np.polynomial.legendre.leggauss(40)
    rho, w_rho = (nodes + 1) / 2, w / 2
    theta = np.arange(64) * 2 * np.pi / 64
    r, t = np.meshgrid(rho, theta)
    area = np.outer(np.full(64, 2 * np.pi / 64), w_rho * rho) / np.pi
    terms = [polynomial("noll", *noll_index(j), r, t) for j in range(1, 22)]
    gram = np.array([[np.sum(a * b * area) for b in terms] for a in terms])
    assert gram == pytest.approx(np.eye(21), abs=1e-9)
    assert [fringe_index(j) for j in range(1, 10)] == [
        (0, 0),
        (1, 1),
        (1, -1),
        (2, 0),
        (2, 2),
        (2, -2),
        (3, 1),
        (3, -1),
        (4, 0),
    ]
    # j = (1 + (n + |m|)/2)² − 2|m| + (1 − sign m)/2: Z37 is (6, 6), as optiland has it (Zemax puts ρ¹² there)
    assert [fringe_index(j) for j in (16, 25, 36, 37)] == [(6, 0), (8, 0), (10, 0), (6, 6)]
    for j in range(1, 50):
        n, m = fringe_index(j)
        assert (1 + (n + abs(m)) // 2) ** 2 - 2 * abs(m) + (1 - np.sign(m)) // 2 == j


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda lens: wavefront(lens, zernike="zemax"), "Zernike kind 'zemax' must be one of fringe, noll"),
        (lambda lens: wavefront(lens, zernike_terms=0), "Zernike terms 0"),
        (lambda lens: ray_fan(lens, fields_deg=[-21.0]), "field -21 deg is beyond"),
        (lambda lens: encircled_energy(lens, energy_reference="peak"), "energy reference 'peak'"),
        (lambda lens: field_curvature(lens, field_samples=1), "field samples 1"),
        (lambda lens: spot_diagram(lens, wavelengths_nm=[-5.0]), "wavelength -5.0 nm"),
    ],
)
def test_bad_inputs_are_refused_by_name(cooke, call, words):
    with pytest.raises(SolasError, match=words.replace("(", r"\(").replace(".", r"\.")):
        call(cooke)
