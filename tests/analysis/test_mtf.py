"""The MTF analyses against closed forms and independent routes: the diffraction-limited MTF of an
ideal lens, the defocused MTF (Hopkins' integral for a pure defocus), the geometric MTF of a
defocused ideal lens (a uniform disc), the OTF against the Fourier transform of the package's
Fraunhofer PSF, the pixel's sinc; bad inputs refused by name."""

import math

import numpy as np
import pytest
from ideal_lenses import WL, ideal_lens, numerical_aperture

from solas_mi.analysis.mtf import geometric_otf, lens_otf, mtf
from solas_mi.analysis.mtf_field import mtf50_field, mtf_field
from solas_mi.analysis.through_focus import through_focus
from solas_mi.errors import SolasError
from solas_mi.metrics.mtf import pixel_mtf
from solas_mi.psf import psf


def diffraction_limited(nu, cutoff):
    """(2/π)(φ − cos φ sin φ), cos φ = ν/ν_c: the MTF of an aberration-free circular pupil."""
    phi = np.arccos(np.clip(np.asarray(nu) / cutoff, 0.0, 1.0))
    return 2.0 / np.pi * (phi - np.cos(phi) * np.sin(phi))


@pytest.mark.parametrize("f_number", [32.0, 50.0])
def test_the_mtf_of_an_ideal_lens_is_the_closed_form(f_number):
    """An ideal lens of f/N (N = 1/(2 sin U'), U' the rim ray's angle) has MTF (2/π)(φ − cos φ sin φ) with
    cos φ = ν λ N, within 1e-4 at every frequency to the cut-off, both directions. (Slow lenses: an ideal
    thin lens maps heights to tangents, so its pupil is not uniform in direction cosines; at f/5 that
    changes the MTF by 1.2e-3, a physical difference, not the computation's.)"""
    lens = ideal_lens(f_number=f_number)
    cutoff = 2.0 * numerical_aperture(100.0, f_number) / (WL * 1e-6)
    nu = np.linspace(0.0, cutoff, 301)
    otf, warnings = lens_otf(lens, (0.0,), (WL,), (1.0,), nu, 256)
    assert not warnings
    for direction in (0, 1):
        assert np.abs(np.abs(otf[0, direction]) - diffraction_limited(nu, cutoff)).max() < 1e-4


def hopkins_defocus(s: np.ndarray, a_waves: float) -> np.ndarray:
    """OTF of a circular pupil (radius 1) with the wavefront W = a ρ² (waves) at normalised shift s ∈ [0, 2]:
    (1/π) ∫ 2 sin(β X(y))/β dy over |y| < √(1 − s²/4), X = √(1 − y²) − s/2, β = 4π a s (H. H. Hopkins,
    Proc. R. Soc. A 231 (1955) 91), by Gauss-Legendre quadrature."""
    nodes, w = np.polynomial.legendre.leggauss(4000)
    out = []
    for si in s:
        half = math.sqrt(max(0.0, 1.0 - si * si / 4.0))
        y = nodes * half
        x = np.sqrt(1.0 - y * y) - si / 2.0
        beta = 4.0 * math.pi * a_waves * si
        integrand = 2.0 * x if beta == 0 else 2.0 * np.sin(beta * x) / beta
        out.append(half * np.dot(w, integrand) / math.pi)
    return np.array(out)


@pytest.mark.parametrize("defocus_mm", [2.0, 6.0])  # about 0.45 and 1.35 waves at the rim
def test_a_defocused_ideal_lens_has_hopkins_mtf(defocus_mm):
    """The image plane δ behind the focus of an ideal f/32 lens: the wavefront on the reference sphere about
    the new image point is a defocus whose rim value and pupil radius follow from the geometry (the sphere
    of radius R = f + δ through the lens centre; the rim ray from height r to the focus F); its MTF is
    Hopkins' integral, to 2e-4."""
    f, n = 100.0, 32.0
    r, big_r = f / n / 2.0, f + defocus_mm
    u = np.array([-r, f]) / math.hypot(r, f)  # the rim ray (height, z) from (r, 0) toward F = (0, f)
    d = np.array([r, -big_r])  # (r, 0) − the sphere's centre (0, R)
    t = -(d @ u) - math.sqrt((d @ u) ** 2 - r * r)  # where it meets the sphere, near the lens
    q = np.array([r, 0.0]) + t * u
    rim_waves = -(math.hypot(q[0], q[1] - f) - f) / (WL * 1e-6)
    pupil_radius = q[0] / big_r  # direction cosine from the image point
    nu = np.linspace(0.0, 0.98 * 2 * pupil_radius / (WL * 1e-6), 60)
    otf, _ = lens_otf(ideal_lens(f, n, defocus_mm), (0.0,), (WL,), (1.0,), nu, 256)
    expected = np.abs(hopkins_defocus(nu * WL * 1e-6 / pupil_radius, rim_waves))
    assert abs(rim_waves) > 0.4
    assert np.abs(np.abs(otf[0, 0]) - expected).max() < 2e-4


def bessel_j1(x: np.ndarray) -> np.ndarray:
    """J1(x) = (1/π) ∫₀^π cos(τ − x sin τ) dτ, by Gauss-Legendre quadrature."""
    nodes, w = np.polynomial.legendre.leggauss(200)
    tau = (nodes + 1.0) * math.pi / 2.0
    return np.cos(tau[None, :] - np.asarray(x)[:, None] * np.sin(tau[None, :])) @ w / 2.0


def test_the_geometric_mtf_of_a_defocused_ideal_lens_is_a_uniform_disc():
    """Far from focus an ideal lens's rays fill a uniform disc of radius b = δ r / f: its geometric MTF is
    |2 J1(2πνb)/(2πνb)|, to 3e-3 with 128 × 128 rays."""
    f, n, delta = 100.0, 8.0, 2.0
    b = delta * (f / n / 2.0) / f
    nu = np.linspace(1e-3, 3.0 / b, 40)
    otf = geometric_otf(ideal_lens(f, n, delta), (0.0,), (WL,), (1.0,), nu, 128)
    x = 2.0 * math.pi * nu * b
    assert np.abs(np.abs(otf[0]) - np.abs(2.0 * bessel_j1(x) / x)).max() < 3e-3


@pytest.mark.parametrize("field", [0.0, 14.0])
def test_the_otf_is_the_fourier_transform_of_the_fraunhofer_psf(cooke, field):
    """The pupil-autocorrelation OTF (complex: its phase places each wavelength's PSF, so the weighted sum
    carries lateral colour) equals the Fourier transform of the package's polychromatic Fraunhofer PSF
    along y and x, within the light the PSF's window leaves out plus 5e-4."""
    wl, weights = cooke.wavelengths_nm, (0.25, 0.5, 0.25)
    p = psf(
        cooke,
        (0.0, field),
        list(wl),
        weights=list(weights),
        pitch_um=0.5,
        size=480,
        pupil_samples=256,
        normalization="none",
    )
    nu = np.linspace(0.0, 200.0, 21)
    otf, _ = lens_otf(cooke, (field,), wl, weights, nu, 256)
    for axis, coordinate, direction in ((1, p.y_um, 0), (0, p.x_um, 1)):
        lsf = p.data.sum(axis=axis)
        transform = np.exp(-2j * np.pi * np.outer(nu, coordinate * 1e-3)) @ lsf / lsf.sum()
        bound = 1.0 - p.meta["energy_in_grid"] + 5e-4
        assert np.abs(transform - otf[0, direction]).max() < bound


def test_mtf_with_pixels_is_the_lens_times_the_sinc(cooke):
    result = mtf(
        cooke,
        fields_deg=[0.0],
        max_frequency_cy_mm=100.0,
        pupil_samples=64,
        rays=32,
        pixel_pitch_um=4.0,
        fill_factor=0.81,
    )
    a_mm = 4.0e-3 * 0.9
    assert result.pixel == pytest.approx(np.abs(np.sinc(result.frequency_cy_mm * a_mm)), abs=1e-15)
    table = result.table()
    row = table.rows[50]
    assert row[table.columns.index("tangential_with_pixel")] == pytest.approx(
        row[table.columns.index("tangential")] * row[table.columns.index("pixel")]
    )


def test_pixel_mtf_along_the_diagonal_is_a_product_of_sincs():
    nu = np.linspace(0.0, 300.0, 7)
    expected = np.abs(np.sinc(nu * 3e-3 / math.sqrt(2)) ** 2)
    assert pixel_mtf(nu, 3.0, 1.0, 45.0) == pytest.approx(expected, abs=1e-12)


def test_through_focus_of_an_ideal_lens_peaks_at_its_focus():
    """An ideal lens's through-focus MTF peaks at its focus (the parabola through the samples about the
    largest, within a hundredth of the 50 um step; the curve is not quite symmetric: the reference sphere's
    radius changes with the plane)."""
    result = through_focus(
        ideal_lens(f_number=8.0),
        frequency_cy_mm=60.0,
        fields_deg=[0.0],
        focus_range_um=200.0,
        focus_steps=9,
        pupil_samples=64,
    )
    best = result.best_focus_um()["0"]
    assert abs(best["tangential"]) < 0.5 and abs(best["sagittal"]) < 0.5


def test_mtf50_of_an_ideal_lens_is_where_the_closed_form_is_one_half():
    """MTF50 of the diffraction-limited MTF: (2/π)(φ − cos φ sin φ) = 1/2 at ν/ν_c = 0.4040 (bisection)."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if diffraction_limited(mid, 1.0) > 0.5 else (lo, mid)
    lens = ideal_lens(f_number=32.0, field=1.0)
    result = mtf50_field(lens, field_samples=2, pupil_samples=128)
    cutoff = 2.0 * numerical_aperture(100.0, 32.0) / (WL * 1e-6)
    assert result.mtf50_cy_mm[0] == pytest.approx([lo * cutoff] * 2, rel=2e-4)


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda lens: mtf(lens, fields_deg=[25.0]), "field 25 deg is beyond"),
        (lambda lens: mtf(lens, max_frequency_cy_mm=1000.0), "at most the diffraction cut-off"),
        (lambda lens: mtf_field(lens, frequencies_cy_mm=[50.0, 500.0]), "frequency 500.0 cycles/mm"),
        (lambda lens: through_focus(lens, focus_range_um=-5.0), "focus range -5.0 um must be a positive"),
        (lambda lens: through_focus(lens, focus_range_um=1e6), "before lens cooke-triplet's last surface"),
        (lambda lens: mtf(lens, fill_factor=0.5), "fill factor 0.5 needs a pixel pitch"),
        (lambda lens: mtf(lens, pixel_pitch_um=-3.0), "pixel pitch -3.0 um"),
        (lambda lens: mtf(lens, pupil_samples=4), "pupil samples 4 must be"),
        (lambda lens: mtf(lens, wavelengths_nm=[550.0], weights=[1.0, 2.0]), "weights"),
    ],
)
def test_bad_inputs_are_refused_by_name(cooke, call, words):
    with pytest.raises(SolasError, match=words.replace(".", r"\.").replace("(", r"\(")):
        call(cooke)


@pytest.mark.slow
def test_the_default_pupil_grid_grows_where_the_wavefront_needs_it():
    """An ideal f/8 lens 12 mm out of focus (about 40 waves of defocus at the rim): 256 samples a side
    leave phase steps of 4 rad a cell, which the default grid (None) refines to π/4; its MTF then follows
    Hopkins' integral, and a fixed 256 says it may under-resolve."""
    f, n, defocus = 100.0, 8.0, 12.0
    r, big_r = f / n / 2.0, f + defocus
    u = np.array([-r, f]) / math.hypot(r, f)
    d = np.array([r, -big_r])
    t = -(d @ u) - math.sqrt((d @ u) ** 2 - r * r)
    q = np.array([r, 0.0]) + t * u
    rim_waves = -(math.hypot(q[0], q[1] - f) - f) / (WL * 1e-6)
    pupil_radius = q[0] / big_r
    nu = np.linspace(0.0, 0.3 * 2 * pupil_radius / (WL * 1e-6), 25)
    lens = ideal_lens(f, n, defocus)
    refined, warnings = lens_otf(lens, (0.0,), (WL,), (1.0,), nu, None)
    expected = np.abs(hopkins_defocus(nu * WL * 1e-6 / pupil_radius, rim_waves))
    assert abs(rim_waves) > 35 and not warnings
    assert np.abs(np.abs(refined[0, 0]) - expected).max() < 2e-3
    assert "may under-resolve" in lens_otf(lens, (0.0,), (WL,), (1.0,), nu, 256)[1][0]
