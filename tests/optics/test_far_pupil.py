"""Finite objects whose entrance pupil lies far behind the first surface (a collimator in front of a
camera lens, the object in its focal plane, as on an MTF bench): the transmitted power of wave optics
(`pupil_function`) and of ray optics (`geometric`) against a brute-force count of rays from the object
point over the whole first surface, and the relative illumination against the cos⁴ law's integral."""

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics import pupil as P
from solas_mi.optics import tracer as T
from solas_mi.optics.paraxial import paraxial
from solas_mi.psf import psf
from solas_mi.psf.geometric import geometric

STIFF = Path(__file__).parents[1] / "data" / "stiff"


def counted_transmission(lens, field_deg, wavelength_nm, samples=1000):
    """Power from the object point that passes every aperture, as a fraction of the paraxial on-axis
    entrance pupil's: rays on a samples² grid over the whole first surface, each weighted by the cos³ of
    its angle to the axis (a point source's power per area of the plane z = 0), no aim."""
    d = lens.object_distance
    p = paraxial(lens, wavelength_nm)
    reach = 1.02 * lens.surfaces[0].semi_diameter
    step = 2.0 * reach / samples
    g = -reach + (np.arange(samples) + 0.5) * step
    ex, ey = (a.ravel() for a in np.meshgrid(g, g))
    point = -np.tan(np.radians(field_deg)) * (p.entrance_pupil_z_mm + d)
    b = P.Bundle(lens, np.array([[0.0, field_deg]]), np.array([wavelength_nm]), len(ex))
    tr = b.trace(T.F(ex), T.F(ey))
    ok, clipped = T.to_numpy(tr.ok, tr.clipped_by)
    cos3 = d**3 / (ex**2 + (ey - point) ** 2 + d * d) ** 1.5
    power = float(np.sum(cos3[ok & (clipped == 0)])) * step * step / (d * d)
    half = math.atan(0.5 * p.entrance_pupil_diameter_mm / (p.entrance_pupil_z_mm + d))
    return power / (2.0 * math.pi * (1.0 - math.cos(half)))


def counted_from_infinity(lens, field_deg, wavelength_nm, samples=1000):
    """The same for an object at infinity: rays on a samples² grid of entrance coordinates (the plane across
    the beam) wider than the first surface, each carrying its area, over the paraxial entrance pupil's."""
    reach = 1.1 * lens.surfaces[0].semi_diameter
    step = 2.0 * reach / samples
    g = -reach + (np.arange(samples) + 0.5) * step
    ex, ey = (a.ravel() for a in np.meshgrid(g, g))
    b = P.Bundle(lens, np.array([[0.0, field_deg]]), np.array([wavelength_nm]), len(ex))
    tr = b.trace(T.F(ex), T.F(ey))
    ok, clipped = T.to_numpy(tr.ok, tr.clipped_by)
    passed = (ok & (clipped == 0)).reshape(samples, samples)
    assert not passed[[0, -1]].any() and not passed[:, [0, -1]].any()  # the grid holds the whole beam
    pupil_area = math.pi * (0.5 * paraxial(lens, wavelength_nm).entrance_pupil_diameter_mm) ** 2
    return float(passed.sum()) * step * step / pupil_area


def test_wave_and_ray_transmission_of_a_far_entrance_pupil_match_a_ray_count():
    """The double Gauss behind an ideal collimator: its entrance pupil is imaged 395 mm behind the
    collimator, 124 mm wide, while the beam crosses the first surface 25 mm wide. The pupil's rim was
    aimed from the entrance pupil's size, outside the front lens, and settled far inside the stop: wave
    0.142 / 0.122 / 0.116 and rays 0.139 / 0.138 / 0.137 at 0°, 2.1°, 3° where a count over the whole
    collimator gives 0.983 / 0.717 / 0.565."""
    lens = Lens.load(STIFF / "collimated_double_gauss.toml")
    wl = lens.primary_wavelength
    fields = np.array([[0.0, 0.0], [0.0, 2.1], [0.0, 3.0]])
    waves = np.full(3, wl)
    counted = np.array([counted_transmission(lens, f, wl) for f in fields[:, 1]])
    assert 0.5 < counted[-1] < counted[1] < counted[0] < 1.0  # the front lens vignettes the field
    # wave optics clips whole cells at the apertures that vignette: 0.3 % at 3° with 128 samples
    assert P.pupil_function(lens, fields, waves, 128).transmission == pytest.approx(counted, rel=5e-3)
    assert geometric(lens, fields, waves, 2.0, 32, rays=400)[2] == pytest.approx(counted, rel=2e-3)


def test_the_rim_aim_starts_from_the_beam_on_the_first_surface():
    """The rim of the stop is aimed from the paraxial beam's footprint in entrance coordinates: the
    entrance pupil's radius at infinity, its cone from the object point cut by z = 0 for a finite object."""
    lens = Lens.load(STIFF / "collimated_double_gauss.toml")
    p = paraxial(lens)
    footprint = (
        0.5 * p.entrance_pupil_diameter_mm * lens.object_distance / (p.entrance_pupil_z_mm + lens.object_distance)
    )
    assert P.entrance_pupil_footprint(lens) == pytest.approx(footprint, rel=1e-12)
    assert footprint == pytest.approx(12.5, rel=0.01)  # the collimated beam fills the double Gauss's 25 mm pupil
    far = Lens.load("double-gauss-50mm")
    assert P.entrance_pupil_footprint(far) == pytest.approx(0.5 * paraxial(far).entrance_pupil_diameter_mm, rel=1e-12)


def test_a_real_collimator_s_far_pupil_matches_a_ray_count_and_its_fold_is_named():
    """The same with an N-BK7 plano-convex collimator: wave transmission was 17.1 on the axis and NaN at
    3° (128 samples). Its spherical aberration folds the pupil at 3° (the map from pupil to reference
    sphere turns back within the passing beam): the Fraunhofer PSF says so and takes the ray count's
    transmission (1.10: more light than the paraxial on-axis pupil, the aberrated collimator gathers it)."""
    lens = Lens.load(STIFF.parent / "collimated_double_gauss_real.toml")
    wl = lens.primary_wavelength
    fields = np.array([[0.0, 0.0], [0.0, 2.1], [0.0, 3.0]])
    waves = np.full(3, wl)
    counted = np.array([counted_transmission(lens, f, wl) for f in fields[:, 1]])
    assert counted[-1] > 1.05  # the folded pupil's field passes more than the paraxial pupil
    assert P.pupil_function(lens, fields[:2], waves[:2], 128).transmission == pytest.approx(counted[:2], rel=5e-3)
    # the ray grid's square about the stop rim's image misses a sliver of the folded beam: 0.25 % at 3°
    assert geometric(lens, fields, waves, 2.0, 32, rays=400)[2] == pytest.approx(counted, rel=4e-3)
    edge = psf(lens, (0.0, 3.0), wl, size=32)
    assert edge.meta["transmission"] == pytest.approx(counted[-1], rel=4e-3)
    assert any("folds over a caustic" in w for w in edge.meta["warnings"])


def test_light_from_infinity_through_the_real_collimator_is_counted_not_refused():
    """The real collimator focuses an object at infinity inside the double Gauss; past that focus the light
    spreads over the image, and at 2.1° 0.379 of the paraxial pupil's power still arrives (a count over the
    whole collimator). A cell of the pupil grid beside a lost ray took its size at the stop from that ray's
    NaN stop crossing: its coverage was NaN, the transmission NaN, and the PSF refused as "every ray is
    blocked" (while the object at 1e10 mm, whose grid happened to hold no such cell, found the light)."""
    lens = replace(Lens.load(STIFF.parent / "collimated_double_gauss_real.toml"), object_distance=math.inf)
    wl = lens.primary_wavelength
    pf = P.pupil_function(lens, [[0.0, 2.1]], [wl], 128)
    assert np.isfinite(pf.coverage).all() and np.isfinite(pf.transmission).all()
    counted = counted_from_infinity(lens, 2.1, wl)
    assert 0.3 < counted < 0.5
    # the folded pupil hands the PSF to the geometric method, whose square about the rim misses a sliver
    assert psf(lens, (0.0, 2.1), wl, size=32).meta["transmission"] == pytest.approx(counted, rel=5e-3)
