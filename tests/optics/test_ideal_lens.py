"""The ideal thin lens (`focal_length`, Zemax's TYPE PARAXIAL) against first-order optics worked by hand:
EFL and BFD of one lens, of two (Gullstrand) and of one before a real singlet, real rays that land at
f·tan θ and at the conjugate 1/s' = 1/f − 1/s with its magnification, a wavefront without aberration
(Airy PSF), the TOML and .zmx round trips, and the refusals."""

import math

import numpy as np
import pytest
from scipy.special import j1

from solas_mi import Lens, SolasError
from solas_mi.optics import pupil as P
from solas_mi.optics import tracer as T
from solas_mi.optics.exit_pupil import reversed_lens
from solas_mi.optics.paraxial import paraxial
from solas_mi.psf import psf

WL = 550.0


def _ideal(f, *, distance="infinity", image=None, diameter=20.0, material="AIR", field=10.0):
    """One ideal lens of focal length `f` (mm) as the stop, image plane `image` mm behind it (default f)."""
    return Lens.from_dict(
        {
            "field_deg": field,
            "wavelengths_nm": [WL],
            "object": {"distance": distance},
            "surface": [
                {
                    "radius": 0.0,
                    "thickness": image or abs(f),
                    "diameter": diameter,
                    "stop": True,
                    "focal_length": f,
                    "material": material,
                }
            ],
        }
    )


@pytest.mark.parametrize("f", [50.0, -80.0, 1234.5])
def test_one_ideal_lens_has_efl_and_bfd_f(f):
    p = paraxial(_ideal(f))
    assert p.efl_mm == pytest.approx(f, rel=1e-14)
    assert p.bfd_mm == pytest.approx(f, rel=1e-14)


def test_an_ideal_lens_into_glass_focuses_at_n_prime_f():
    """n'u' = nu − h/f: EFL f (1/power), the focus n'·f behind it."""
    lens = _ideal(40.0, material="N-BK7", image=70.0)
    n2 = lens.surfaces[0].glass.index(WL)
    p = paraxial(lens, WL)
    assert p.efl_mm == pytest.approx(40.0, rel=1e-14)
    assert p.bfd_mm == pytest.approx(n2 * 40.0, rel=1e-13)


@pytest.mark.parametrize("f1, f2, d", [(50.0, 80.0, 20.0), (-30.0, 25.0, 12.0), (100.0, 100.0, 150.0)])
def test_two_ideal_lenses_follow_gullstrand(f1, f2, d):
    """1/F = 1/f1 + 1/f2 − d/(f1 f2); the back focus F (1 − d/f1) behind the second lens."""
    lens = Lens.from_dict(
        {
            "surface": [
                {"radius": 0.0, "thickness": d, "diameter": 10.0, "stop": True, "focal_length": f1},
                {"radius": 0.0, "thickness": 30.0, "diameter": 60.0, "focal_length": f2},
            ]
        }
    )
    efl = 1.0 / (1.0 / f1 + 1.0 / f2 - d / (f1 * f2))
    p = paraxial(lens, 550.0)
    assert p.efl_mm == pytest.approx(efl, rel=1e-13)
    assert p.bfd_mm == pytest.approx(efl * (1.0 - d / f1), rel=1e-12)


def test_ideal_lens_before_a_real_singlet_follows_the_thick_lens_formulas():
    """An ideal lens f = 120 mm, d = 15 mm before a convex-plano N-BK7 singlet (R = 40 mm, t = 6 mm):
    the singlet's power (n − 1)/R, its principal planes at its curved vertex and t/n before its flat back,
    combined by Gullstrand's formula with the ideal lens."""
    f, d, radius, t = 120.0, 15.0, 40.0, 6.0
    lens = Lens.from_dict(
        {
            "surface": [
                {"radius": 0.0, "thickness": d, "diameter": 10.0, "stop": True, "focal_length": f},
                {"radius": radius, "thickness": t, "diameter": 20.0, "material": "N-BK7"},
                {"radius": 0.0, "thickness": 30.0, "diameter": 20.0},
            ]
        }
    )
    n = lens.surfaces[1].glass.index(WL)
    phi_b = (n - 1.0) / radius
    efl = 1.0 / (1.0 / f + phi_b - d * phi_b / f)
    p = paraxial(lens, WL)
    assert p.efl_mm == pytest.approx(efl, rel=1e-13)
    assert p.bfd_mm == pytest.approx(efl * (1.0 - d / f) - t / n, rel=1e-12)


def _pencil(lens, tan_y, object_point=None, wavelength_um=WL / 1000.0):
    """A 15 x 15 grid of rays over the ideal lens's aperture at field tangent `tan_y`, traced to the image."""
    g = np.linspace(-6.0, 6.0, 15)
    ex, ey = (a.ravel() for a in np.meshgrid(g, g))
    F = T.F
    if object_point is None:
        rays = T.launch(lens, F(0.0 * ex), F(tan_y + 0.0 * ex), F(ex), F(ey))
    else:
        rays = T.launch(lens, F(0.0 * ex), F(0.0 * ex), F(ex), F(ey), (F(object_point[0]), F(object_point[1])))
    traced = T.trace(lens, rays, F(wavelength_um))
    x, y, opl = T.to_numpy(*T.to_plane(traced, lens.image_z))
    (ok,) = T.to_numpy(traced.ok)
    return x, y, opl, ok


@pytest.mark.parametrize("theta", [0.0, 5.0, 30.0, 60.0])
def test_real_rays_from_infinity_land_at_f_tan_theta(theta):
    """Every ray of a collimated pencil at θ meets the focal plane at f·tan θ (not only the chief ray)."""
    lens = _ideal(50.0, diameter=20.0)
    x, y, _, ok = _pencil(lens, math.tan(math.radians(theta)))
    assert ok.all()
    assert np.abs(y - 50.0 * math.tan(math.radians(theta))).max() < 1e-12
    assert np.abs(x).max() < 1e-12
    chief = P.chief_rays(lens, np.array([[0.0, theta]]), np.array([WL])).image_xy[0]
    assert chief[1] == pytest.approx(50.0 * math.tan(math.radians(theta)), abs=1e-12)


def test_finite_conjugate_images_at_the_thin_lens_distance_and_magnification():
    """Object 150 mm before f = 50: 1/s' = 1/f − 1/s gives s' = 75 mm, magnification −s'/s = −0.5;
    every ray from the point (2, 7) mm lands at (−1, −3.5) mm."""
    f, s = 50.0, 150.0
    s2 = 1.0 / (1.0 / f - 1.0 / s)
    lens = _ideal(f, distance=s, image=s2)
    assert paraxial(lens).image_offset_mm == pytest.approx(0.0, abs=1e-12)
    x, y, opl, ok = _pencil(lens, 0.0, object_point=(2.0, 7.0))
    assert ok.all()
    assert np.abs(x - (-s2 / s) * 2.0).max() < 1e-12
    assert np.abs(y - (-s2 / s) * 7.0).max() < 1e-12
    assert np.ptp(opl) < 1e-11  # every ray of the pencil has the same optical path: a perfect image


def test_a_pencil_through_diverging_and_converging_ideal_lenses_is_stigmatic():
    """f = −50 then f = +40, 20 mm apart (Gullstrand: EFL 66.7 mm, BFD 93.3 mm), at 8° off axis: the rays
    meet in one point with one optical path, at the EFL's image height."""
    efl = 1.0 / (1.0 / -50.0 + 1.0 / 40.0 - 20.0 / (-50.0 * 40.0))
    bfd = efl * (1.0 + 20.0 / 50.0)
    lens = Lens.from_dict(
        {
            "wavelengths_nm": [WL],
            "surface": [
                {"radius": 0.0, "thickness": 20.0, "diameter": 14.0, "stop": True, "focal_length": -50.0},
                {"radius": 0.0, "thickness": bfd, "diameter": 60.0, "focal_length": 40.0},
            ],
        }
    )
    tan = math.tan(math.radians(8.0))
    _x, y, opl, ok = _pencil(lens, tan)
    assert ok.all()
    assert np.abs(y - efl * tan).max() < 1e-11
    assert np.ptp(opl) < 1e-11


@pytest.mark.parametrize("distance", ["infinity", 400.0])
def test_wavefront_of_an_ideal_lens_is_perfect(distance):
    """OPD to the reference sphere below 1e-12 mm at 0°, 6° and (3°, 8°); without the ideal lens's own path
    (δ = 0) the f/2.5 beam would carry h⁴/(8f³) ≈ 1.6 µm of spherical aberration."""
    f = 50.0
    image = f if distance == "infinity" else 1.0 / (1.0 / f - 1.0 / distance)
    lens = _ideal(f, distance=distance, image=image)
    fields = np.array([[0.0, 0.0], [0.0, 6.0], [3.0, 8.0]])
    pf = P.pupil_function(lens, fields, np.full(3, WL), 64)
    assert (pf.coverage > 0).sum() > 3 * 2000
    assert np.abs(np.where(pf.coverage > 0, pf.opd_mm, 0.0)).max() < 1e-12


def test_psf_of_an_ideal_lens_is_the_airy_pattern():
    """f = 100 mm stopped to 2 mm (f/50) at the focus: the Fraunhofer PSF is the Airy pattern of NA = sin u'
    (RMSE below 1e-3 of the peak), first dark ring at 1.22 λ/(2 NA) = 33.6 µm."""
    lens = _ideal(100.0, diameter=2.0)
    na = 1.0 / math.hypot(1.0, 100.0)
    p = psf(lens, (0.0, 0.0), WL, pitch_um=1.0, size=121, normalization="peak")
    x, y = np.meshgrid(p.x_um, p.y_um)
    arg = 2 * math.pi / (WL / 1000.0) * na * np.hypot(x, y)
    airy = np.where(arg > 0, (2 * j1(arg) / np.where(arg > 0, arg, 1)) ** 2, 1.0)
    assert np.sqrt(np.mean((p.data - airy) ** 2)) < 1e-3
    assert 1.22 * WL / 1000.0 / (2 * na) == pytest.approx(33.6, rel=0.01)


def test_toml_round_trip_keeps_the_focal_length(tmp_path):
    lens = _ideal(-37.5, image=20.0)
    back = Lens.load(lens.save(tmp_path / "ideal.toml"))
    assert back.surfaces[0].focal_length == -37.5
    assert back.hash == lens.hash
    assert _ideal(-37.6, image=20.0).hash != lens.hash  # the focal length is part of the prescription


def test_zmx_round_trip_and_reading_paraxial(tmp_path):
    lens = Lens.from_dict(
        {
            "surface": [
                {"radius": 0.0, "thickness": 10.0, "diameter": 12.0, "stop": True, "focal_length": 80.0},
                {"radius": 30.0, "thickness": 4.0, "diameter": 16.0, "material": "N-BK7"},
                {"radius": 0.0, "thickness": 40.0, "diameter": 16.0},
            ]
        }
    )
    path = lens.save(tmp_path / "ideal.zmx")
    text = path.read_text()
    assert "TYPE PARAXIAL" in text and "PARM 1 80.0" in text and "PARM 2 1" in text
    back = Lens.load(path)
    assert back.surfaces[0].focal_length == 80.0
    assert paraxial(back).efl_mm == pytest.approx(paraxial(lens).efl_mm, rel=1e-14)


def test_zmx_paraxial_in_cm_with_integrate_mode_says_its_opd_is_taken_perfect(tmp_path):
    """UNIT CM scales PARM 1 (the focal length); OPD mode 0 (integrate) is read as perfect, and the lens's
    description says so; a nonzero CURV on a PARAXIAL surface is ignored, as Zemax does."""
    text = (
        "\n".join(
            [
                "UNIT CM X W X CM MR CPMM",
                "ENPD 1",
                "WAVM 1 0.55 1",
                "SURF 0",
                "  DISZ INFINITY",
                "SURF 1",
                "  TYPE PARAXIAL",
                "  CURV 0.5",
                "  STOP",
                "  PARM 1 5",
                "  PARM 2 0",
                "  DISZ 5",
                '  DIAM 1 1 0 0 1 ""',
                "SURF 2",
                "  TYPE STANDARD",
                "  DISZ 0",
            ]
        )
        + "\n"
    )
    (tmp_path / "cm.zmx").write_text(text)
    lens = Lens.load(tmp_path / "cm.zmx")
    assert lens.surfaces[0].focal_length == 50.0 and lens.surfaces[0].radius == 0.0
    assert paraxial(lens).efl_mm == pytest.approx(50.0, rel=1e-14)
    assert "OPD mode integrate" in lens.description and "perfect" in lens.description
    (tmp_path / "zero.zmx").write_text(text.replace("PARM 1 5", "PARM 1 0"))
    with pytest.raises(SolasError, match=r"PARAXIAL focal length \(PARM 1\) 0 must be nonzero"):
        Lens.load(tmp_path / "zero.zmx")


def test_reversed_lens_keeps_the_ideal_lens():
    lens = Lens.from_dict(
        {
            "surface": [
                {"radius": 0.0, "thickness": 10.0, "diameter": 12.0, "stop": True, "focal_length": 80.0},
                {"radius": 0.0, "thickness": 40.0, "diameter": 20.0, "focal_length": -120.0},
            ]
        }
    )
    rev = reversed_lens(lens)
    assert [s.focal_length for s in rev.surfaces] == [-120.0, 80.0]
    assert paraxial(rev).efl_mm == pytest.approx(paraxial(lens).efl_mm, rel=1e-13)


@pytest.mark.parametrize(
    "row, match",
    [
        ({"focal_length": 0.0}, "focal_length = 0.0 must be a finite nonzero number"),
        ({"focal_length": "50"}, "focal_length = '50' must be a finite nonzero number"),
        ({"focal_length": float("nan")}, "focal_length = nan must be a finite nonzero number"),
        ({"focal_length": 50.0, "radius": 100.0}, "an ideal thin lens \\(focal_length\\) is flat"),
        ({"focal_length": 50.0, "conic": -1.0}, "an ideal thin lens \\(focal_length\\) is flat"),
    ],
)
def test_bad_ideal_lens_rows_are_refused(row, match):
    base = {"radius": 0.0, "thickness": 50.0, "diameter": 10.0, "stop": True}
    with pytest.raises(SolasError, match=match):
        Lens.from_dict({"surface": [{**base, **row}]})


def test_writers_that_cannot_hold_it_refuse(tmp_path):
    lens = _ideal(50.0)
    with pytest.raises(SolasError, match="surface 1 is an ideal thin lens .* save it as .toml or .zmx"):
        lens.save(tmp_path / "ideal.dat")
    assert not (tmp_path / "ideal.dat").exists()


def test_a_virtual_object_before_an_ideal_lens_loads():
    """Once refused, now traced (test_virtual_object): an object 53.4 mm behind the lens, 1/s' = 1/53.4 + 1/50."""
    lens = Lens.from_dict(
        {
            "object": {"distance": -53.4},
            "surface": [{"radius": 0.0, "thickness": 50.0, "diameter": 10.0, "stop": True, "focal_length": 50.0}],
        }
    )
    assert lens.virtual_object
    assert paraxial(lens, WL).focus_z_mm == pytest.approx(1.0 / (1.0 / 53.4 + 1.0 / 50.0), rel=1e-14)


def test_metadata_says_where_the_ideal_lens_path_is_exact():
    """Exact for an ideal lens with only ideal lenses and air before it; approximate behind a real singlet
    (the pencil it meets is aberrated); in the PSF metadata, absent for a lens without one."""
    exact = psf(_ideal(50.0, diameter=4.0), (0.0, 0.0), WL, size=32).meta["ideal_lens_path"]
    assert exact.startswith("surface 1: ideal thin lens") and exact.endswith("exact")
    behind = Lens.from_dict(
        {
            "surface": [
                {"radius": 40.0, "thickness": 6.0, "diameter": 20.0, "material": "N-BK7"},
                {"radius": 0.0, "thickness": 5.0, "diameter": 20.0},
                {"radius": 0.0, "thickness": 30.0, "diameter": 10.0, "stop": True, "focal_length": 120.0},
            ]
        }
    )
    assert "approximate at surface 3" in psf(behind, (0.0, 0.0), 550.0, size=32).meta["ideal_lens_path"]
    singlet = Lens.from_dict(
        {
            "surface": [
                {"radius": 40.0, "thickness": 6.0, "diameter": 20.0, "material": "N-BK7", "stop": True},
                {"radius": 0.0, "thickness": 60.0, "diameter": 20.0},
            ]
        }
    )
    assert "ideal_lens_path" not in psf(singlet, (0.0, 0.0), 550.0, size=32).meta


def test_a_scaled_lens_scales_its_ideal_lens():
    from solas_mi.optics.scale import scaled

    lens = _ideal(50.0, field=5.0)
    assert scaled(lens, 2.0).surfaces[0].focal_length == 100.0
    assert paraxial(scaled(lens, 2.0)).efl_mm == pytest.approx(100.0, rel=1e-14)
