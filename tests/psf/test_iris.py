"""The iris: a stop of N straight blades (`blades`, `blade_rotation`) in the pupil function of every PSF
method. Against closed forms: the Fraunhofer PSF of a perfect lens behind a regular polygon equals the
polygon's analytic Fourier transform (a sum over its edges, computed here), its spikes number N for even
N and 2N for odd N, and the transmitted power is the polygon's share of the round stop's area."""

import math

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.psf.methods import psf

F_MM, STOP_MM, WAVELENGTH = 100.0, 2.0, 550.0  # an ideal f = 100 mm lens at f/50: no aberration at all


def perfect(blades=0, rotation=0.0, curvature=None):
    row = {"radius": 0.0, "thickness": F_MM, "diameter": STOP_MM, "stop": True, "focal_length": F_MM}
    if blades:
        row.update(blades=blades, blade_rotation=rotation)
    if curvature is not None:
        row["blade_curvature"] = curvature
    return Lens.from_dict({"name": "perfect", "wavelengths_nm": [WAVELENGTH], "surface": [row]})


def polygon_transform(kx, ky, corners):
    """∫ over the polygon of exp(−i k·r) d²r, by the divergence theorem: (i/|k|²) Σ_edges (k × d)
    e^{−i k·m} sinc(k·d / 2π), d an edge's vector, m its midpoint (corners counter-clockwise)."""
    k2 = kx * kx + ky * ky
    total = np.zeros_like(kx, dtype=np.complex128)
    for a, b in zip(corners, np.roll(corners, -1, axis=0)):
        d, m = b - a, 0.5 * (a + b)
        kd = kx * d[0] + ky * d[1]
        total += (kx * d[1] - ky * d[0]) * np.exp(-1j * (kx * m[0] + ky * m[1])) * np.sinc(kd / (2 * math.pi))
    area = 0.5 * abs(sum(a[0] * b[1] - a[1] * b[0] for a, b in zip(corners, np.roll(corners, -1, axis=0))))
    return np.where(k2 > 0, 1j * total / np.where(k2 > 0, k2, 1.0), area)


def corners(n, rotation_deg, radius):
    angle = math.radians(rotation_deg) + 2 * math.pi * np.arange(n) / n
    return np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)


def test_hexagonal_stop_equals_the_polygon_transform():
    """The issue's acceptance: within 1e-3 of the peak, RMS, of the analytic transform."""
    pitch, size = 2.0, 96
    got = psf(
        perfect(6, 10.0), (0.0, 0.0), WAVELENGTH, pitch_um=pitch, size=size, normalization="peak", pupil_samples=512
    ).data
    # the polygon in direction cosines: corners at the stop's radius over the distance to the focus
    offsets = (np.arange(size) - size // 2) * pitch * 1e-3  # mm; row 0 the top (+y)
    u, v = np.meshgrid(offsets, -offsets)
    k = 2 * math.pi / (WAVELENGTH * 1e-6)
    radius = 0.5 * STOP_MM / math.hypot(0.5 * STOP_MM, F_MM)
    expected = np.abs(polygon_transform(k * u, k * v, corners(6, 10.0, radius))) ** 2
    expected /= expected.max()
    rms = math.sqrt(np.mean((got - expected) ** 2))
    assert rms < 1e-3, rms
    assert got.max() == 1.0 and expected[size // 2, size // 2] == 1.0


def spikes(blades):
    """The number of maxima of the PSF's power by azimuth in a ring well outside the core."""
    pitch, size = 4.0, 256
    data = psf(
        perfect(blades, 0.0), (0.0, 0.0), WAVELENGTH, pitch_um=pitch, size=size, normalization="peak", pupil_samples=256
    ).data
    y, x = np.mgrid[:size, :size] - size // 2
    r, phi = np.hypot(x, y) * pitch, np.arctan2(-y, x)
    ring = (r > 150) & (r < 480)
    bins = 360
    power = np.bincount(((phi[ring] + math.pi) / (2 * math.pi) * bins).astype(int) % bins, data[ring], bins)
    smooth = np.convolve(np.r_[power[-3:], power, power[:3]], np.ones(7) / 7, "valid")
    high = 0.5 * (smooth.min() + smooth.max())  # a spike: a maximum above the profile's midway
    peaks = (smooth > np.roll(smooth, 1)) & (smooth >= np.roll(smooth, -1)) & (smooth > high)
    return int(peaks.sum())


@pytest.mark.parametrize("blades, expected", [(6, 6), (7, 14), (5, 10), (8, 8)])
def test_spikes_number_n_for_even_and_2n_for_odd_blades(blades, expected):
    assert spikes(blades) == expected


@pytest.mark.parametrize("method, options", [("fraunhofer", {"pupil_samples": 256}), ("geometric", {"rays": 512})])
def test_the_iris_passes_the_polygons_share_of_the_light(method, options):
    """Transmission of an N-gon inscribed in the round stop: (N / 2π) sin(2π / N) of the round stop's."""
    for n in (5, 6, 9):
        round_, iris = (
            psf(lens, (0.0, 0.0), WAVELENGTH, pitch_um=8.0, size=32, method=method, **options).meta["transmission"]
            for lens in (perfect(), perfect(n, 7.0))
        )
        share = n / (2 * math.pi) * math.sin(2 * math.pi / n)
        assert abs(iris / round_ - share) < (2e-3 if method == "fraunhofer" else 5e-3), (n, iris / round_, share)


def test_a_round_stop_is_the_default_and_bit_identical(doublet, doublet_spec):
    """`blades = 0` stated is the lens without it: same hash, same PSF to the bit."""
    doublet_spec["surface"][doublet.stop_index]["blades"] = 0
    stated = Lens.from_dict(doublet_spec)
    assert stated.hash == doublet.hash and stated.surfaces == doublet.surfaces
    a, b = (psf(lens, (0.0, 1.0), 531.0, size=32, pupil_samples=64).data for lens in (doublet, stated))
    assert np.array_equal(a, b)


def test_blades_round_trip_and_are_refused_where_they_cannot_be(doublet, doublet_spec, tmp_path):
    stop = doublet.stop_index
    doublet_spec["surface"][stop]["blades"] = 7
    doublet_spec["surface"][stop]["blade_rotation"] = 12.5
    lens = Lens.from_dict(doublet_spec)
    from solas_mi.optics import notes

    assert "7 straight blades, first corner at 12.5 deg" in notes.metadata(lens)["iris"]
    again = Lens.load(lens.save(tmp_path / "iris.toml"))
    assert again.surfaces == lens.surfaces and again.hash == lens.hash != Lens.load("solas-doublet").hash
    with pytest.raises(SolasError, match="holds no blades"):
        lens.save(tmp_path / "iris.zmx")
    for row, value in ((stop, 2), (stop, 3.0), (stop, True), (0, 6)):
        spec = {**doublet_spec, "surface": [dict(r) for r in doublet_spec["surface"]]}
        spec["surface"][stop].pop("blades")
        spec["surface"][row]["blades"] = value
        with pytest.raises(SolasError, match="on the stop surface only"):
            Lens.from_dict(spec)


def test_the_reversed_lens_keeps_the_iris_and_the_coatings(doublet_spec, doublet):
    """The lens camera traces the lens from the image side (`exit_pupil.reversed_lens`): x and y are kept,
    so the stop's polygon and every coating are the same there, and a ray through a corner region
    outside the polygon but inside the circle is blocked both ways."""
    from solas_mi.optics import tracer
    from solas_mi.optics.exit_pupil import reversed_lens

    doublet_spec["surface"][doublet.stop_index].update(blades=5, blade_rotation=90.0)
    doublet_spec["surface"][0]["coating"] = "quarter_wave"
    lens = Lens.from_dict(doublet_spec)
    back = reversed_lens(lens)
    stop = back.surfaces[back.stop_index]
    assert (stop.blades, stop.blade_rotation) == (5, 90.0) and back.surfaces[-1].coating == lens.surfaces[0].coating
    doublet_spec["surface"][doublet.stop_index]["blade_curvature"] = 0.3
    curved = reversed_lens(Lens.from_dict(doublet_spec))
    assert curved.surfaces[curved.stop_index].blade_curvature == 0.3
    # a ray from the film's centre through the stop just inside its circle, midway between two corners
    # (an edge's middle lies at the circle's radius × cos 36°): blocked by the iris, passed by a round stop
    radius = stop.semi_diameter
    angle = math.radians(90.0 + 36.0)
    z_stop = float(back.vertex_z[back.stop_index])
    for r, blocked in ((0.95 * radius, True), (0.75 * radius, False)):
        target = (r * math.cos(angle), r * math.sin(angle))
        rays = tracer.launch(
            back,
            tracer.F(0.0),
            tracer.F(0.0),
            tracer.F(target[0]),
            tracer.F(target[1]),
            object_point=(tracer.F(0.0), tracer.F(0.0)),
        )
        traced = tracer.trace(back, rays, tracer.F(0.531))
        sx, sy, clipped = tracer.to_numpy(traced.stop_x, traced.stop_y, traced.clipped_by)
        assert z_stop >= 0 and (clipped[0] == back.stop_index + 1) == blocked, (r, sx, sy, clipped)


def curved_share(n: int, kappa: float) -> float:
    """The area of N blades curved κ over the round stop's: the N-gon with corners on the unit circle and N circular
    segments of radius 1/κ on its sides, each (R²/2)(2α − sin 2α) with half-angle α, sin α = κ sin(π/N)."""
    polygon = n / 2 * math.sin(2 * math.pi / n)
    big, alpha = 1 / kappa, math.asin(kappa * math.sin(math.pi / n))
    return (polygon + n * big**2 / 2 * (2 * alpha - math.sin(2 * alpha))) / math.pi


@pytest.mark.parametrize("method, options", [("fraunhofer", {"pupil_samples": 256}), ("geometric", {"rays": 512})])
def test_curved_blades_pass_their_area_and_the_round_limit_is_the_round_stop(method, options):
    """Blades curved κ pass the closed-form share of the light (polygon + segments); κ = 1 is the round stop."""
    round_ = psf(perfect(), (0.0, 0.0), WAVELENGTH, pitch_um=8.0, size=32, method=method, **options)
    for n, kappa in ((5, 0.5), (6, 0.8), (9, 0.3)):
        lens = perfect(n, 7.0, kappa)
        iris = psf(lens, (0.0, 0.0), WAVELENGTH, pitch_um=8.0, size=32, method=method, **options).meta["transmission"]
        share = curved_share(n, kappa)
        assert lens.surfaces[0].iris_area() / (math.pi * (STOP_MM / 2) ** 2) == pytest.approx(share, rel=1e-12)
        assert abs(iris / round_.meta["transmission"] - share) < (2e-3 if method == "fraunhofer" else 5e-3), (n, kappa)
    circle = psf(perfect(6, 7.0, 1.0), (0.0, 0.0), WAVELENGTH, pitch_um=8.0, size=32, method=method, **options)
    assert np.abs(circle.data - round_.data).max() < 1e-5 * round_.data.max()


def test_the_curved_margin_is_the_distance_to_the_arc_and_tends_to_the_straight_side():
    """The margin of points on a sector's bisector is the apex's distance minus theirs; near κ = 0 it is the
    straight side's margin (no cancellation); inside the N-gon it is inside for every κ."""
    r = STOP_MM / 2
    straight, nearly, curved = (perfect(6, 0.0, k).surfaces[0] for k in (None, 1e-12, 0.5))
    x, y = np.linspace(-r, r, 41)[:, None] * np.ones(41), np.linspace(-r, r, 41)[None, :] * np.ones((41, 1))
    margin = [s.iris_margin(x, y, np.hypot, np.arctan2, np.cos, np.floor) for s in (straight, nearly, curved)]
    assert np.abs(margin[1] - margin[0]).max() < 1e-12
    assert (margin[2][margin[0] >= 0] >= 0).all()  # the arcs bulge outward: the polygon stays inside
    assert (margin[2][margin[0] < 0] > -1e-12).any()  # and they hold more: points outside the polygon
    bisector = math.pi / 6  # corners at 0, 60, ...: the first side's bisector at 30 deg
    _, apex, _ = curved.iris_arc()
    for t in (0.0, 0.3, 0.9):
        px, py = t * r * math.cos(bisector), t * r * math.sin(bisector)
        assert curved.iris_margin(px, py, math.hypot, math.atan2, math.cos, math.floor) == pytest.approx(
            apex - t * r, abs=1e-12
        )


def test_blade_curvature_round_trips_and_is_refused_by_name(tmp_path):
    lens = perfect(6, 7.0, 0.4)
    again = Lens.load(lens.save(tmp_path / "curved.toml"))
    assert again.surfaces == lens.surfaces and again.hash == lens.hash != perfect(6, 7.0).hash
    assert perfect(6, 7.0, 0.0).hash == perfect(6, 7.0).hash  # stated straight: the straight iris's hash
    from solas_mi.optics import notes

    assert "6 blades curved 0.4" in notes.metadata(lens)["iris"]
    for blades, value in ((6, 1.5), (6, -0.1), (6, True), (0, 0.5)):
        with pytest.raises(SolasError, match="blade_curvature"):
            perfect(blades, 0.0, value) if blades else Lens.from_dict(
                {"name": "p", "wavelengths_nm": [WAVELENGTH], "surface": [
                    {"radius": 0.0, "thickness": F_MM, "diameter": STOP_MM, "stop": True, "focal_length": F_MM,
                     "blade_curvature": value}]})  # fmt: skip
