"""Exit-pupil bounds per film radius (`optics.exit_pupil`): the table a sensor samples from must hold
every ray that leaves the lens, at every radius between its rows."""

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics.exit_pupil import PupilBounds, passes, pupil_bounds, reversed_lens


def test_a_radius_takes_its_row_and_the_next():
    """Between rows i and i + 1 (a radius on row i included) the bound is their union: taking rows
    i − 1 and i there under-sampled pupils that grow with the radius."""
    radius = np.array([0.0, 1.0, 2.0, 3.0])
    rows = np.array([[-1, 1, -1, 1], [-2, 2, -2, 2], [-3, 3, -3, 3], [-4, 4, -4, 4]], dtype=float)
    table = PupilBounds(radius, rows, np.ones(4, dtype=bool), 0.0)
    assert table.at(np.array(1.0))[:4].tolist() == [-3, 3, -3, 3]
    assert table.at(np.array(1.5))[:4].tolist() == [-3, 3, -3, 3]
    assert table.at(np.array(0.0))[:4].tolist() == [-2, 2, -2, 2]


@pytest.mark.parametrize("name", ["solas-doublet", "cooke-triplet", "double_gauss_50mm"])
def test_every_passing_ray_lies_inside_the_bound(name):
    """Rays from film points between the table's rows toward a fine grid on the last vertex plane: all
    that leave the lens fall inside the bound at that radius (inside its ellipse where it is one: the
    double Gauss's vignetted cat's eye included)."""
    lens = Lens.load(name)
    half = 0.5 * lens.image_diameter if lens.image_diameter else 3.0
    table = pupil_bounds(lens, half, wavelengths_nm=[lens.primary_wavelength], radii=16)
    rev = reversed_lens(lens)
    reach = 2.0 * lens.surfaces[-1].semi_diameter
    g = np.linspace(-reach, reach, 161)
    gx, gy = (a.ravel() for a in np.meshgrid(g, g))
    for r in (table.radius_mm[3] + 0.37 * (table.radius_mm[4] - table.radius_mm[3]), table.radius_mm[-2]):
        ok = passes(rev, np.full(len(gx), r), 0.0, gx, gy, lens.primary_wavelength)
        u0, u1, v0, v1, elliptical = table.at(np.array(r))
        assert ok.any()
        assert (gx[ok] >= u0).all() and (gx[ok] <= u1).all() and (gy[ok] >= v0).all() and (gy[ok] <= v1).all()
        if elliptical:
            e = ((2 * gx[ok] - u0 - u1) / (u1 - u0)) ** 2 + ((2 * gy[ok] - v0 - v1) / (v1 - v0)) ** 2
            assert e.max() <= 1.0, (r, e.max())


def test_the_ellipse_between_two_rows_holds_both():
    """Rows' ellipses with different centres: the bound between them is an ellipse holding both (the
    inscribed ellipse of their boxes' union would cut the first circle's top)."""
    table = PupilBounds(
        np.array([0.0, 1.0]), np.array([[-1.0, 1.0, -1.0, 1.0], [0.0, 2.0, -1.0, 1.0]]), np.ones(2, dtype=bool), 0.0
    )
    u0, u1, v0, v1, elliptical = table.at(np.array(0.5))
    assert elliptical == 1
    phi = np.linspace(0, 2 * np.pi, 721)
    for cu in (0.0, 1.0):
        u, v = cu + np.cos(phi), np.sin(phi)
        assert (((2 * u - u0 - u1) / (u1 - u0)) ** 2 + ((2 * v - v0 - v1) / (v1 - v0)) ** 2).max() <= 1 + 1e-12


def test_bounds_hold_a_thin_ring_the_march_steps_over(monkeypatch):
    """A pupil of a disc and a thin ring outside it (here drawn into `passes`: 2.56-2.59 mm about the
    axis, around the doublet's 2.5 mm disc): the march from outside (steps of 0.16 mm) steps over the
    ring and bisects onto the disc, so the sensors would lose the ring's light; the check on a grid of
    rays at build time finds it, widens the bounds and warns."""
    import numpy as np

    from solas_mi import Lens
    from solas_mi.optics import exit_pupil as E

    real = E.passes

    def with_ring(rev, x, y, ex, ey, w):
        d = np.hypot(ex, ey)
        return real(rev, x, y, ex, ey, w) | ((d > 2.56) & (d < 2.59))

    monkeypatch.setattr(E, "passes", with_ring)
    lens = Lens.load("solas-doublet")
    with pytest.warns(UserWarning, match="missed a thin part of the pupil"):
        b = E.pupil_bounds(lens, 1.0, [531.0], radii=8)
    g = np.linspace(-3.0, 3.0, 1201)
    gu, gv = (a.ravel() for a in np.meshgrid(g, g))
    for r in (0.0, 0.5, 1.0):
        ok = with_ring(E.reversed_lens(lens), r, 0.0, gu, gv, 531.0)
        u0, u1, v0, v1, _ = b.at(np.array(r))
        assert ok.any() and np.all((gu[ok] >= u0) & (gu[ok] <= u1) & (gv[ok] >= v0) & (gv[ok] <= v1))


def test_bounds_hold_the_ring_of_a_real_disc_and_ring_pupil(monkeypatch):
    """A lens whose pupil is a disc and a ring (tests/data/ring_pupil.toml: a stop before a ball lens;
    rays near the ball's rim cross the axis and pass the stop on the far side): the on-axis irradiance
    that the sensors integrate inside the bounds equals a brute-force integral over the whole last
    vertex plane (1500² rays, cos⁴ weights) within 0.5 %; the march alone steps over the ring and
    keeps 70 % of it, so the build-time check is what holds it (with a warning)."""
    from pathlib import Path

    import numpy as np

    from solas_mi import Lens
    from solas_mi.optics import exit_pupil as E

    lens = Lens.load(Path(__file__).parents[1] / "data" / "ring_pupil.toml")
    reach = E.exit_reach(lens, 1.0)
    g = -reach + (np.arange(1500) + 0.5) * (2 * reach / 1500)
    gu, gv = (a.ravel() for a in np.meshgrid(g, g))
    ok = E.passes(E.reversed_lens(lens), 0.0, 0.0, gu, gv, 587.5618)
    h = lens.surfaces[-1].thickness  # the film lies this far behind the last vertex plane
    weight = ok * (h * h / (h * h + gu**2 + gv**2)) ** 2
    d = np.hypot(gu, gv)
    assert weight[(d > 1.9) & (d < 2.2)].sum() > 0.25 * weight.sum() and not ok[(d > 0.4) & (d < 1.9)].any()

    def held(bounds) -> float:
        u0, u1, v0, v1, ellipse = bounds.at(np.array(0.0))
        if ellipse:
            inside = ((2 * gu - u0 - u1) / (u1 - u0)) ** 2 + ((2 * gv - v0 - v1) / (v1 - v0)) ** 2 <= 1
        else:
            inside = (gu >= u0) & (gu <= u1) & (gv >= v0) & (gv <= v1)
        return float((weight * inside).sum() / weight.sum())

    with pytest.warns(UserWarning, match="missed a thin part of the pupil"):
        assert held(E.pupil_bounds(lens, 1.0, radii=8)) > 0.995
    monkeypatch.setattr(E, "_check", lambda rev, radius, bounds, elliptical, reach, w: (np.zeros(4), 1.0, 1.0))
    assert held(E.pupil_bounds(lens, 1.0, radii=8)) < 0.8
