"""Surface shapes as geometry objects (`optics.shapes`): the registry of kinds, each kind's sag and normal
against an independent closed form (the toroid against the implicit torus equation and the other root's
formula, the biconic against its implicit quartic, the cylinder against the conic profile, the rotational
kinds against `sag.sag`), and every kind's ray intersection landing on its sag."""

import numpy as np
import pytest

from solas_mi.optics import shapes
from solas_mi.optics.sag import sag, sag_slope
from solas_mi.optics.shapes import Shape

RNG = np.random.default_rng(40)
X, Y = RNG.uniform(-6.0, 6.0, (2, 400))


def _conic_profile(y, c, k, terms=()):
    """The conic's other closed form, (1 − √(1 − (1 + k) c² y²)) / ((1 + k) c), plus Σ α_i y^2i, and its
    derivative, written out here."""
    root = np.sqrt(1.0 - (1.0 + k) * c * c * y * y)
    z = (1.0 - root) / ((1.0 + k) * c) + sum(a * y ** (2 * i) for i, a in enumerate(terms, start=1))
    dz = c * y / root + sum(2 * i * a * y ** (2 * i - 1) for i, a in enumerate(terms, start=1))
    return z, dz


def _unit(vx, vy, vz):
    norm = np.sqrt(vx * vx + vy * vy + vz * vz) * np.sign(vz)
    return vx / norm, vy / norm, vz / norm


def _close(a, b, tol=1e-12):
    return max(np.abs(np.asarray(u) - np.asarray(v)).max() for u, v in zip(a, b)) < tol


def test_registry_holds_every_kind_once_with_its_lens_file_keys():
    for name, entry in shapes.KINDS.items():
        assert issubclass(entry.function, Shape) and entry.function.kind == name
        assert entry.extra["symmetric"] == (name not in shapes.NAMED) == entry.function.symmetric
        assert set(entry.extra["keys"]) <= set(shapes.KEYS)


@pytest.mark.parametrize("radius_rotation", [-35.0, 18.0])
def test_toroid_sag_and_normal_satisfy_the_torus_equation(radius_rotation):
    """(R − z)² + x² = (R − z_y)²: the sag from the equation's direct root R − sgn(a)√(a² − x²), the normal
    along the equation's gradient (2x, 2(R − z_y) z_y′, −2(R − z))."""
    c, k, terms, big_r = 1 / 25.0, -0.4, (2e-4, -1e-6), radius_rotation
    toroid = shapes.KINDS["toroid"].function(25.0, k, terms, big_r)
    zy, dzy = _conic_profile(Y, c, k, terms)
    a = big_r - zy
    direct = big_r - np.sign(a) * np.sqrt(a * a - X * X)
    assert np.abs(toroid.sag(X, Y) - direct).max() < 1e-12
    z = toroid.sag(X, Y)
    assert _close(toroid.normal(X, Y), _unit(-2 * X, -2 * a * dzy, 2 * (big_r - z)))
    assert toroid.section_curvatures == (1 / big_r, c + 2 * terms[0])
    assert toroid.paraxial_curvature is None


def test_a_toroid_rotated_at_its_own_radius_is_the_sphere():
    sphere, toroid = shapes.KINDS["conic"].function(25.0), shapes.KINDS["toroid"].function(25.0, 0.0, (), 25.0)
    assert np.abs(toroid.sag(X, Y) - sphere.sag(X, Y)).max() < 1e-13
    assert _close(toroid.normal(X, Y), sphere.normal(X, Y), 1e-13)


def test_biconic_sag_and_normal_satisfy_its_implicit_equation():
    """z (1 + √(1 − B)) = A is z = A (1 − √(1 − B)) / B, the sag's other closed form, and F = A² − 2Az + z²B = 0,
    whose gradient gives the normal (A = c_x x² + c_y y², B = (1 + k_x) c_x² x² + (1 + k_y) c_y² y²)."""
    cx, kx, cy, ky = 1 / 40.0, 0.6, -1 / 22.0, -1.8
    biconic = shapes.KINDS["biconic"].function(1 / cy, ky, 1 / cx, kx)
    a = cx * X * X + cy * Y * Y
    b = (1 + kx) * cx * cx * X * X + (1 + ky) * cy * cy * Y * Y
    z = a * (1 - np.sqrt(1 - b)) / b
    assert np.abs(biconic.sag(X, Y) - z).max() < 1e-12
    fx = 2 * a * 2 * cx * X - 2 * 2 * cx * X * z + z * z * 2 * (1 + kx) * cx * cx * X
    fy = 2 * a * 2 * cy * Y - 2 * 2 * cy * Y * z + z * z * 2 * (1 + ky) * cy * cy * Y
    fz = -2 * a + 2 * z * b
    assert _close(biconic.normal(X, Y), _unit(fx, fy, fz))
    assert biconic.section_curvatures == (cx, cy) and biconic.paraxial_curvature is None


def test_a_biconic_of_equal_sections_is_the_conic_and_a_cylinder_its_profile():
    conic, biconic = (
        shapes.KINDS["conic"].function(30.0, -0.5),
        shapes.KINDS["biconic"].function(30.0, -0.5, 30.0, -0.5),
    )
    assert np.abs(biconic.sag(X, Y) - conic.sag(X, Y)).max() < 1e-13
    assert _close(biconic.normal(X, Y), conic.normal(X, Y), 1e-13)
    cylinder = shapes.KINDS["cylinder"].function(-20.0, 0.3)
    zy, dzy = _conic_profile(Y, -1 / 20.0, 0.3)
    assert np.abs(cylinder.sag(X, Y) - zy).max() < 1e-12
    assert _close(cylinder.normal(X, Y), _unit(0 * X, -dzy, 1 + 0 * X))


def test_rotational_kinds_are_the_tracers_sag():
    """The rotational kinds evaluate `sag.sag` and its slope, bit for bit."""
    qbfs = shapes.KINDS["qbfs"].function(30.0, -0.7, (1e-5,), (0.05, -0.02), 9.0)
    terms = dict(curvature=1 / 30.0, conic=-0.7, aspheric=(1e-5,), qbfs=(0.05, -0.02), norm_radius=9.0)
    r2 = X * X + Y * Y
    assert np.array_equal(qbfs.sag(X, Y), sag(r2, **terms))
    assert np.array_equal(qbfs.gradient(X, Y)[1], 2.0 * sag_slope(r2, **terms) * Y)


@pytest.mark.parametrize(
    "kind, values",
    [
        ("plane", ()),
        ("conic", (30.0, -0.7)),
        ("asphere", (-25.0, 0.0, (2e-5, -1e-8))),
        ("qbfs", (30.0, -0.7, (), (0.05, -0.02), 9.0)),
        ("toroid", (25.0, -0.4, (2e-4,), -35.0)),
        ("cylinder", (-20.0, 0.3)),
        ("biconic", (-22.0, -1.8, 40.0, 0.6)),
    ],
)
def test_each_kind_intersects_rays_on_its_sag(kind, values):
    shape = shapes.KINDS[kind].function(*values)
    d = np.stack([RNG.uniform(-0.3, 0.3, X.size), RNG.uniform(-0.3, 0.3, X.size), np.ones(X.size)])
    dx, dy, dz = d / np.linalg.norm(d, axis=0)
    t, hit = shape.intersect(X, Y, dx, dy, dz)
    assert hit.all()
    assert np.abs(t * dz - shape.sag(X + t * dx, Y + t * dy)).max() < 1e-12


def test_a_toroid_refuses_an_aperture_it_does_not_reach():
    from solas_mi import SolasError

    with pytest.raises(SolasError, match="toroid closes before the clear semi-diameter 12"):
        shapes.KINDS["toroid"].function(25.0, 0.0, (), 10.0).check_aperture(12.0, "lens: surface 1")


@pytest.mark.parametrize("kind", shapes.NAMED)
def test_a_shape_grown_by_s_is_s_times_its_sag_at_x_over_s(kind):
    values = {
        "toroid": (25.0, -0.4, (2e-4, 3e-7), -35.0),
        "cylinder": (-20.0, 0.3),
        "biconic": (-22.0, -1.8, 40.0, 0.6),
    }
    shape, s = shapes.KINDS[kind].function(*values[kind]), 1.7
    assert np.abs(shape.scaled(s).sag(X, Y) - s * shape.sag(X / s, Y / s)).max() < 1e-12
