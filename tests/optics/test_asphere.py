"""Even aspheres (conic + polynomial) in the lens file, the tracer, the reversed lens and the mesh
scene, checked against the sag formula, Snell's law with a finite-difference normal, and a conic
singlet that is stigmatic on axis."""

import numpy as np
import pytest

from solas_mi import Lens, SolasError, spot
from solas_mi.optics import tracer as T
from solas_mi.optics.exit_pupil import reversed_lens
from solas_mi.optics.lens import sag

ASPHERE = {"radius": 40.0, "conic": -0.6, "aspheric": [-2e-6, 3e-9]}


def single_surface(**surface) -> Lens:
    """One refracting surface into N-BK7, stop on it: traced rays end on the surface itself."""
    return Lens.from_dict(
        {"surface": [{"thickness": 10.0, "diameter": 20.0, "material": "N-BK7", "stop": True, **surface}]}
    )


def test_sag_follows_the_formula():
    r = np.linspace(0.0, 9.0, 10)
    assert np.allclose(sag(r * r, 1 / 30.0, -1.0), r * r / 60.0, rtol=0, atol=1e-15)  # paraboloid: c r² / 2
    assert np.allclose(sag(r * r, 0.0, 0.0, (1e-4, -2e-7)), 1e-4 * r**4 - 2e-7 * r**6, rtol=0, atol=1e-15)
    c, k = 1 / 30.0, 0.7  # oblate ellipsoid: (1 + k) z² − 2 R z + r² = 0, solved for the near root
    R = 30.0
    direct = (R - np.sqrt(R * R - (1 + k) * r * r)) / (1 + k)
    assert np.allclose(sag(r * r, c, k), direct, rtol=0, atol=1e-13)


def test_trace_lands_on_the_asphere_and_obeys_snell():
    lens = single_surface(**ASPHERE)
    s = lens.surfaces[0]
    rng = np.random.default_rng(1)
    ex, ey = rng.uniform(-6, 6, 200), rng.uniform(-6, 6, 200)
    tx, ty = np.tan(np.radians(rng.uniform(-15, 15, 200))), np.tan(np.radians(rng.uniform(-15, 15, 200)))
    rays = T.launch(lens, T.F(tx), T.F(ty), T.F(ex), T.F(ey))
    d_in = np.stack(T.to_numpy(rays.dx, rays.dy, rays.dz), -1)
    tr = T.trace(lens, rays, T.F(0.5876))
    x, y, z, dx, dy, dz, ok = T.to_numpy(tr.rays.x, tr.rays.y, tr.rays.z, tr.rays.dx, tr.rays.dy, tr.rays.dz, tr.ok)
    assert ok.all()
    assert np.abs(z - s.sag(np.hypot(x, y))).max() < 1e-12
    h = 1e-6  # the normal from central differences of the sag: independent of the tracer's slope formula
    gx = (s.sag(np.hypot(x + h, y)) - s.sag(np.hypot(x - h, y))) / (2 * h)
    gy = (s.sag(np.hypot(x, y + h)) - s.sag(np.hypot(x, y - h))) / (2 * h)
    normal = np.stack([-gx, -gy, np.ones_like(gx)], -1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    n1, n2 = lens.indices(587.6)
    d_out = np.stack([dx, dy, dz], -1)
    assert np.abs(n1 * np.cross(d_in, normal) - n2 * np.cross(d_out, normal)).max() < 1e-8


def plano_hyperbolic(conic: float) -> Lens:
    """Flat front (the stop), hyperbolic rear face in a glass of n_d = 1.5: for k = −n² a collimated
    axial beam meets in one point at |R| / (n − 1) behind the rear vertex."""
    return Lens.from_dict(
        {
            "wavelengths_nm": [587.5618],
            "surface": [
                {"radius": 0.0, "thickness": 5.0, "diameter": 20.0, "material": "model:1.5/60", "stop": True},
                {"radius": -25.0, "conic": conic, "thickness": 50.0, "diameter": 20.0, "material": "AIR"},
            ],
        }
    )


def test_the_plano_hyperbolic_lens_is_stigmatic_on_axis():
    perfect = spot(plano_hyperbolic(-2.25), (0, 0), 587.5618, density=24)
    sphere = spot(plano_hyperbolic(0.0), (0, 0), 587.5618, density=24)
    assert perfect.vignetted == 0
    assert perfect.rms_radius_um() < 1e-6
    assert sphere.rms_radius_um() > 100.0  # the same lens with a spherical face is far from perfect


def test_reversed_asphere_retraces_the_ray():
    """A ray traced through the lens, then back through the reversed lens from its image point,
    leaves along the reversed incoming direction: the reversed lens holds the same surfaces."""
    lens = Lens.from_dict(
        {
            "object": {"distance": 200.0},
            "surface": [
                {"thickness": 4.0, "diameter": 20.0, "material": "N-BK7", **ASPHERE},
                {"radius": -60.0, "conic": -3.0, "aspheric": [1e-5], "thickness": 60.0, "diameter": 20.0, "stop": True},
            ],
        }
    )
    obj = (T.F([0.0, 3.0]), T.F([0.0, -5.0]))
    tr = T.trace(lens, T.launch(lens, None, None, T.F([4.0, 2.0]), T.F([1.0, -3.0]), obj), T.F(0.55))
    ix, iy, _ = T.to_plane(tr, lens.image_z)
    rev = reversed_lens(lens)
    back = T.Rays(
        ix,
        iy,
        T.F([0.0, 0.0]) - lens.surfaces[-1].thickness + 0.0 * ix,
        -tr.rays.dx,
        -tr.rays.dy,
        tr.rays.dz,
        T.F([0.0, 0.0]),
    )
    out = T.trace(rev, back, T.F(0.55))
    dx, dy, ok = T.to_numpy(out.rays.dx, out.rays.dy, out.ok)
    assert ok.all()
    v = np.array([[4.0, 1.0, 200.0], [-1.0, 2.0, 200.0]])
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    assert np.allclose(dx, -v[:, 0], atol=1e-10) and np.allclose(dy, -v[:, 1], atol=1e-10)  # mirrored in z only


@pytest.mark.parametrize(
    "surface, match",
    [
        ({"conic": "x"}, r"conic = 'x' must be a finite number"),
        ({"aspheric": [1e-5, "a"]}, r"aspheric = \[1e-05, 'a'\] must be a list of at most 12 finite numbers"),
        (
            {"radius": 5.0, "conic": 1.0, "diameter": 9.0},
            r"conic 1 with radius 5 mm closes before the clear semi-diameter",
        ),
    ],
)
def test_bad_asphere_keys_are_named(surface, match):
    with pytest.raises(SolasError, match=match):
        single_surface(**{"radius": 40.0, **surface})
