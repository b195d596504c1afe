"""Paraxial data against DESIGN.md anchors and thin-lens / imaging-equation limits."""

import numpy as np
import pytest

from solas_mi import Lens, paraxial, spot

# DESIGN.md: facts about the SOLAS doublet that independent tools agree on.


EFL = {486: 99.9395, 531: 99.9468, 656: 100.0882}


FNO = {486: 7.991, 531: 7.991, 656: 8.016}


@pytest.mark.parametrize("wavelength", sorted(EFL))
def test_efl_and_f_number(doublet, wavelength):
    p = paraxial(doublet, wavelength)
    assert p.efl_mm == pytest.approx(EFL[wavelength], abs=1e-3)
    assert p.f_number == pytest.approx(FNO[wavelength], abs=1e-3)


def test_pupils_and_focus(doublet):
    p = paraxial(doublet, 531)
    assert p.entrance_pupil_diameter_mm == pytest.approx(12.51, abs=0.01)
    assert p.entrance_pupil_z_mm == pytest.approx(153.4, abs=0.1)  # virtual, behind surface 1
    assert p.exit_pupil_z_mm == pytest.approx(66.376)  # the stop
    assert p.exit_pupil_diameter_mm == pytest.approx(5.0)
    assert p.exit_pupil_f_number == pytest.approx(39.496 / 5.0)
    assert p.image_offset_mm == pytest.approx(-0.46, abs=0.01)  # image plane inside paraxial focus


def test_thin_lens_limit():
    """A thin singlet in air: EFL = 1 / ((n − 1)(1/R1 − 1/R2))."""
    from solas_mi import Lens

    spec = {
        "surface": [
            {"radius": 200.0, "thickness": 0.01, "diameter": 1.0, "material": "N-BK7", "stop": True},
            {"radius": -200.0, "thickness": 200.0, "diameter": 1.0, "material": "AIR"},
        ]
    }
    lens = Lens.from_dict(spec)
    n = lens.surfaces[0].glass.index(587.5618)
    assert paraxial(lens, 587.5618).efl_mm == pytest.approx(1.0 / ((n - 1) * (2 / 200.0)), rel=1e-4)


def test_real_chief_ray_height(doublet):
    from solas_mi.optics.pupil import chief_rays

    cr = chief_rays(doublet, [[0.0, 2.0], [0.0, -2.0], [2.0, 0.0]], [531.0] * 3)
    assert cr.image_xy[0, 1] == pytest.approx(3.4745, abs=1e-3)
    assert cr.image_xy[1, 1] == pytest.approx(-cr.image_xy[0, 1], abs=1e-12)
    assert cr.image_xy[2, 0] == pytest.approx(cr.image_xy[0, 1], abs=1e-12)
    assert not cr.vignetted.any()


def test_finite_object_imaging_equation():
    """A thin singlet images an object at 2f to 2f behind it."""
    from solas_mi import Lens

    surfaces = [
        {"radius": 200.0, "thickness": 0.01, "diameter": 1.0, "material": "N-BK7", "stop": True},
        {"radius": -200.0, "thickness": 200.0, "diameter": 1.0, "material": "AIR"},
    ]
    f = paraxial(Lens.from_dict({"surface": surfaces}), 587.5618).efl_mm
    lens = Lens.from_dict({"surface": surfaces, "object": {"distance": 2 * f}})
    assert paraxial(lens, 587.5618).focus_z_mm == pytest.approx(2 * f, rel=1e-4)


def test_far_finite_object_approaches_infinity(doublet_spec):
    """Fields at a finite distance are angles toward the entrance pupil; far away they match infinity."""
    from solas_mi import Lens
    from solas_mi.optics.pupil import chief_rays, pupil_function

    doublet_spec["object"]["distance"] = 1e7
    far = Lens.from_dict(doublet_spec)
    inf = Lens.from_dict({**doublet_spec, "object": {"distance": "infinity"}})
    fields = [[0.0, 2.0]]
    assert chief_rays(far, fields, [531.0]).image_xy == pytest.approx(
        chief_rays(inf, fields, [531.0]).image_xy, abs=2e-5
    )
    # spot patterns lie in the aim plane z = 0 (tilted 2° to the beam), so rim sampling differs slightly
    assert spot(far, (0, 2), 531.0).rms_radius_um() == pytest.approx(spot(inf, (0, 2), 531.0).rms_radius_um(), rel=1e-2)
    t_far = pupil_function(far, [[0.0, 0.0], [0.0, 2.0]], [531.0] * 2, 64).transmission
    t_inf = pupil_function(inf, [[0.0, 0.0], [0.0, 2.0]], [531.0] * 2, 64).transmission
    # a point source on the object plane sends cos²θ less to the pupil than an on-axis one at the
    # same intensity; a collimated beam of the same irradiance does not lose it
    cos2 = np.cos(np.radians([0.0, 2.0])) ** 2
    assert t_far == pytest.approx(t_inf * cos2, rel=2e-4)


def test_exit_pupil_f_number_of_a_lens_telecentric_in_image_space():
    """The stop in the front focal plane of a plano-convex lens (f = R/(n − 1) = 100 mm, its principal
    plane on the curved vertex) puts the exit pupil at infinity: (image − pupil)/D was ∞/∞, NaN in `lens
    info`. The beam toward the image then has slope r_stop/f, f-number f/(2 r_stop) = 10; and a stop 1 µm
    nearer, whose pupil is at a finite distance, gives the same in the plain ratio."""
    from solas_mi import Lens

    def lens(stop_gap):
        return Lens.from_dict(
            {
                "surface": [
                    {"radius": 0.0, "thickness": stop_gap, "diameter": 10.0, "material": "AIR", "stop": True},
                    {"radius": 50.0, "thickness": 3.0, "diameter": 20.0, "material": "model:1.5"},
                    {"radius": 0.0, "thickness": 100.0, "diameter": 20.0, "material": "AIR"},
                ]
            }
        )

    p = paraxial(lens(100.0), 587.5618)
    assert p.exit_pupil_f_number == pytest.approx(10.0, rel=1e-12)
    near = paraxial(lens(100.0 - 1e-3), 587.5618)
    plain = (near.image_z_mm - near.exit_pupil_z_mm) / near.exit_pupil_diameter_mm
    assert abs(near.exit_pupil_z_mm) > 1e6 and plain == pytest.approx(10.0, rel=1e-6)
    assert near.exit_pupil_f_number == pytest.approx(plain, rel=1e-9)


def test_a_lens_telecentric_in_object_space_is_refused_saying_so():
    """The stop in the rear focal plane (98 mm behind the plano-convex lens above) puts the entrance pupil
    at infinity: the pupil and ray aiming divided by zero and the lens was refused as imaging no field."""
    from solas_mi import Lens
    from solas_mi.errors import SolasError

    lens = Lens.from_dict(
        {
            "surface": [
                {"radius": 50.0, "thickness": 3.0, "diameter": 30.0, "material": "model:1.5"},
                {"radius": 0.0, "thickness": 98.0, "diameter": 30.0, "material": "AIR"},
                {"radius": 0.0, "thickness": 60.0, "diameter": 4.0, "material": "AIR", "stop": True},
            ],
            "object": {"distance": 300.0},
        }
    )
    with pytest.raises(
        SolasError,
        match=r"stop \(surface 3\) lies in the rear focal plane .* entrance pupil is at "
        r"infinity \(telecentric in object space\)",
    ):
        paraxial(lens, 587.5618)


def test_efl_in_image_space_is_the_rear_focal_length_in_the_image_medium():
    """A singlet focusing into water (a constant index n' = 1.333, as a lens on a sensor under a liquid):
    power φ = (n − 1) c1 + (n' − n) c2 − (n − 1)(n' − n) c1 c2 t / n, EFL in air 1/φ, in image space n'/φ
    (Zemax's "in image space", optiland's f2); `lens info` shows the row only where they differ."""
    n, n_img, c1, c2, t = 1.5, 1.333, 1 / 30.0, -1 / 80.0, 5.0
    phi = (n - 1) * c1 + (n_img - n) * c2 - (n - 1) * (n_img - n) * c1 * c2 * t / n
    lens = Lens.from_dict(
        {
            "surface": [
                {"radius": 30.0, "thickness": t, "diameter": 12.0, "material": "model:1.5", "stop": True},
                {"radius": -80.0, "thickness": 40.0, "diameter": 12.0, "material": "model:1.333"},
            ]
        }
    )
    p = paraxial(lens, 550.0)
    assert p.efl_mm == pytest.approx(1 / phi, rel=1e-12)
    assert p.efl_image_space_mm == pytest.approx(n_img / phi, rel=1e-12)
    air = Lens.load("solas-doublet")
    assert paraxial(air, 550.0).efl_image_space_mm == paraxial(air, 550.0).efl_mm
