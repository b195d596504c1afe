"""The stages of the optics' longer computations, each against a fact derivable on its own."""

import math

import numpy as np
import pytest

from solas_mi.errors import SolasError
from solas_mi.optics import tracer as T
from solas_mi.optics import zemax
from solas_mi.optics.exit_pupil import _box, exit_reach
from solas_mi.optics.lens import Lens
from solas_mi.optics.paraxial import _chief_height, _marginal_ray, _pupils, paraxial, ynu_trace


def singlet(stop_first: bool = True, distance="infinity") -> Lens:
    return Lens.from_dict(
        {
            "object": {"distance": distance},
            "surface": [
                {"radius": 60.0, "thickness": 5.0, "diameter": 20.0, "material": "N-BK7", "stop": stop_first},
                {"radius": 0.0, "thickness": 1.0, "diameter": 20.0},
                {"radius": 0.0, "thickness": 100.0, "diameter": 10.0, "stop": not stop_first},
            ],
        }
    )


def test_pupils_of_a_stop_on_surface_1_are_the_stop():
    lens = singlet()
    w = lens.primary_wavelength
    ya, _ = ynu_trace(lens, w, 1.0, 0.0)
    yb, _ = ynu_trace(lens, w, 0.0, 1.0)
    ep_z, ep_radius, _, _, _ = _pupils(lens, w, ya, yb)
    assert ep_z == 0.0 and ep_radius == 10.0


def test_pupils_of_a_last_stop_are_its_exit_pupil():
    lens = singlet(stop_first=False)
    w = lens.primary_wavelength
    ya, _ = ynu_trace(lens, w, 1.0, 0.0)
    yb, _ = ynu_trace(lens, w, 0.0, 1.0)
    _, _, xp_z, xp_radius, xp_f_number = _pupils(lens, w, ya, yb)
    assert xp_z == lens.vertex_z[-1] and xp_radius == 5.0
    assert xp_f_number == (lens.image_z - xp_z) / 10.0


@pytest.mark.parametrize("distance", ["infinity", 400.0])
def test_the_marginal_ray_meets_the_stop_rim(distance):
    lens = singlet(distance=distance)
    ym, _um, obj_z = _marginal_ray(lens, lens.primary_wavelength, *ynu_trace(lens, lens.primary_wavelength, 1.0, 0.0))
    assert ym[lens.stop_index] == pytest.approx(10.0, rel=1e-12)
    assert obj_z == (-math.inf if distance == "infinity" else -400.0)


def test_chief_heights_are_odd_in_the_field(doublet):
    w, p = doublet.primary_wavelength, paraxial(doublet)
    h = [_chief_height(doublet, w, f, p.entrance_pupil_z_mm, -math.inf) for f in (0.0, 2.0, -2.0, 95.0)]
    assert h[0] == 0.0 and h[1] == -h[2] and h[3] == math.inf


def test_refraction_at_a_flat_surface_is_snell():
    flat = Lens.from_dict(
        {
            "surface": [
                {"radius": 0.0, "thickness": 10.0, "diameter": 20.0, "material": "N-BK7", "stop": True},
                {"radius": 0.0, "thickness": 10.0, "diameter": 20.0},
            ]
        }
    )
    theta = np.radians([0.0, 10.0, 40.0])
    d = (T.F(np.sin(theta)), T.F(0.0 * theta), T.F(np.cos(theta)))
    zero = T.F(0.0 * theta)
    mu = 1.0 / 1.5
    normal = T.surface_normal(flat.surfaces[0], zero, zero, zero, zero, T.F)
    (dx, _dy, dz), _k2, factor = T._refract(normal, d, mu, True)
    dx, dz, factor = T.to_numpy(dx, dz, factor)
    assert np.allclose(dx, mu * np.sin(theta), rtol=0, atol=1e-15) and np.allclose(dx**2 + dz**2, 1.0)
    assert factor[0] == pytest.approx(1.0 - ((1.5 - 1.0) / 2.5) ** 2, rel=1e-12)  # normal incidence: 1 − R


def test_rays_move_to_a_flat_surface_s_vertex_plane():
    flat = Lens.from_dict(
        {
            "surface": [
                {"radius": 0.0, "thickness": 10.0, "diameter": 20.0, "stop": True},
                {"radius": 0.0, "thickness": 10.0, "diameter": 20.0},
            ]
        }
    )
    rays = T.launch(flat, T.F([0.0, 0.1]), T.F([0.0, -0.2]), T.F([1.0, 2.0]), T.F([0.0, 3.0]))
    x, y, _lz, t, opl, hit = T._to_surface(flat.surfaces[1], 10.0, rays, T.F(1.0), False, T.F)
    rz, rdz = T.to_numpy(rays.z, rays.dz)
    t0 = (10.0 - rz) / rdz
    x, y, opl, t, hit, rx, rdx = T.to_numpy(x, y, opl, t, hit, rays.x, rays.dx)
    assert hit.all() and (t == 0.0).all() and np.allclose(x, rx + t0 * rdx, rtol=0, atol=1e-12)
    assert np.allclose(opl, t0, rtol=0, atol=1e-12)


def test_aspheric_terms_scale_with_the_unit():
    block = {"PARM": [["2", "1e-5"], ["3", "0"], ["4", "2e-9"], ["5", "0"]]}
    assert zemax._aspheric(block, 1.0, "SURF 1") == [1e-5, 0.0, 2e-9]
    assert zemax._aspheric(block, 10.0, "SURF 1") == pytest.approx([1e-5 * 10**-3, 0.0, 2e-9 * 10**-7])
    with pytest.raises(SolasError, match="PARM 1"):
        zemax._aspheric({"PARM": [["1", "0.1"]]}, 1.0, "SURF 1")


def test_the_reach_of_a_flat_last_surface_is_its_aperture():
    lens = singlet()
    assert exit_reach(lens, 3.0) == pytest.approx(1.05 * lens.surfaces[-1].semi_diameter, rel=1e-15)


def test_the_box_of_a_circular_rim_is_elliptical_and_of_a_square_one_is_not():
    phi = 2.0 * np.pi * np.arange(64) / 64
    circle = (2.0 * np.cos(phi))[None, None, :], (2.0 * np.sin(phi) + 1.0)[None, None, :]
    bounds, elliptical = _box(*circle, 64)
    assert elliptical.all() and bounds[0, 0] < -2.0 and bounds[0, 3] > 3.0
    assert np.allclose(bounds[0], [-2.0, 2.0, -1.0, 3.0], atol=0.01)
    square = np.clip(circle[0] * 2, -2.0, 2.0), np.clip((circle[1] - 1.0) * 2, -2.0, 2.0)
    assert not _box(*square, 64)[1].any()
