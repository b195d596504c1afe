"""The Dr.Jit tracer in each surface's frame (`optics.tracer_local`) against the NumPy tracer of the lens as
built (`optics.local_trace`, itself compared with optiland: benchmarks/asbuilt_optiland.py), and against the
Dr.Jit tracer of a lens on one axis (`optics.tracer`), which a symmetric lens still goes to bit for bit."""

from dataclasses import replace

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics import local_trace, tracer, tracer_local
from solas_mi.optics.placement import Placement

FIELDS_DEG = [(0.0, 0.0), (0.0, 14.0), (0.0, -14.0), (10.0, 10.0), (-12.0, 5.0)]  # five fields in two dimensions


def _rays(fields_deg, half_width: float = 1.5, n: int = 7):
    """n×n collimated rays per field, crossing z = 10 mm on a square of `half_width` mm, starting 30 mm before:
    their points and unit directions (NumPy) and the Dr.Jit `tracer.Rays`."""
    grid = np.linspace(-half_width, half_width, n)
    px, py = (a.ravel() for a in np.meshgrid(grid, grid))
    points, directions = [], []
    for fx, fy in fields_deg:
        d = np.array([np.tan(np.radians(fx)), np.tan(np.radians(fy)), 1.0])
        d /= np.linalg.norm(d)
        points.append(np.stack([px, py, np.full(n * n, 10.0)], 1) - 30.0 * d)
        directions.append(np.broadcast_to(d, (n * n, 3)))
    p, d = np.concatenate(points), np.concatenate(directions)
    rays = tracer.Rays(*(tracer.F(np.ascontiguousarray(a)) for a in (*p.T, *d.T)), tracer.F(np.zeros(len(p))))
    return p, d, rays


def _drjit(lens, rays, count: int, **options):
    """`tracer_local.trace` of `rays` at the primary wavelength, to the image plane: (x, y, OPL, passed)."""
    wl = tracer.F(np.full(count, lens.primary_wavelength * 1e-3))
    traced = tracer_local.trace(lens, rays, wl, **options)
    x, y, opl = tracer.to_numpy(*tracer.to_plane(traced, lens.image_z))
    return x, y, opl, tracer.to_numpy(traced.ok & (traced.clipped_by == 0))[0], traced


@pytest.mark.parametrize(
    "toroid, sensor_tilt", [(False, 0.0), (True, 0.0), (True, 1.5)], ids=["decentred", "toroid", "tilted-sensor"]
)
def test_the_drjit_tracer_traces_a_lens_as_built_as_the_numpy_tracer(cooke_as_built, toroid, sensor_tilt):
    """The triplet with a decentred and tilted middle element (then also a toroid and a tilted sensor): 49 real
    rays at each of five fields in two dimensions land on the image plane within 1e-9 mm of the NumPy tracer's,
    the same rays passing, their optical paths within 1e-9 mm."""
    lens = cooke_as_built(toroid, sensor_tilt)
    p, d, rays = _rays(FIELDS_DEG)
    x, y, opl, passed, _ = _drjit(lens, rays, len(p))
    ours = local_trace.trace(lens, local_trace.bundle(p, d), lens.primary_wavelength)
    assert passed.sum() > 200 and np.array_equal(ours.ok, passed)
    for a, b in ((ours.image_x, x), (ours.image_y, y), (ours.opl, opl)):
        assert np.abs(a - b)[passed].max() < 1e-9


def test_the_drjit_tracer_meets_toroids_biconics_and_cylinders_as_the_numpy_tracer():
    """Every kind without rotational symmetry, decentred, tilted and turned, and a decentred, tilted sensor."""
    lens = Lens.from_dict(
        {
            "name": "kinds",
            "surface": [
                {"kind": "toroid", "radius": 40.0, "conic": -0.3, "terms_y": [1e-5], "radius_rotation": -80.0,
                 "thickness": 4.0, "diameter": 16.0, "material": "N-BK7", "stop": True},
                {"kind": "biconic", "radius": -50.0, "radius_x": -70.0, "conic_x": 0.5, "thickness": 2.0,
                 "diameter": 16.0, "decentre_x": 0.1, "tilt_y": 0.5},
                {"kind": "cylinder", "radius": 60.0, "thickness": 3.0, "diameter": 16.0, "material": "N-SF5",
                 "tilt_z": 90.0, "tilt_order": 1},
                {"radius": 0.0, "thickness": 40.0, "diameter": 16.0},
            ],
            "image": {"decentre_y": 0.2, "tilt_x": -1.0, "tilt_y": 0.7},
        }
    )  # fmt: skip
    p, d, rays = _rays([(0.0, 0.0), (3.0, -4.0), (-5.0, 2.0)], half_width=5.0)
    x, y, opl, passed, _ = _drjit(lens, rays, len(p))
    ours = local_trace.trace(lens, local_trace.bundle(p, d), lens.primary_wavelength)
    assert passed.sum() > 100 and np.array_equal(ours.ok, passed)
    for a, b in ((ours.image_x, x), (ours.image_y, y), (ours.opl, opl)):
        assert np.abs(a - b)[passed].max() < 1e-9


def test_a_symmetric_lens_goes_to_the_symmetric_tracer_bit_for_bit(triplet):
    p, _, rays = _rays(FIELDS_DEG)
    wl = tracer.F(np.full(len(p), triplet.primary_wavelength * 1e-3))
    ours = tracer_local.trace(triplet, rays, wl, fresnel=True)
    theirs = tracer.trace(triplet, rays, wl, fresnel=True)
    a = tracer.to_numpy(*tracer.to_plane(ours, triplet.image_z), ours.transmittance, ours.clipped_by)
    b = tracer.to_numpy(*tracer.to_plane(theirs, triplet.image_z), theirs.transmittance, theirs.clipped_by)
    assert all(np.array_equal(u, v, equal_nan=True) for u, v in zip(a, b))


def test_breaks_of_zeros_trace_as_the_lens_on_one_axis(triplet):
    """A break of zeros before every surface and the sensor makes a lens as built of the triplet: its local-frame
    trace (frames, clipping, stop, Fresnel transmittance) equals the symmetric one's within 1e-12 mm."""
    zero = Placement()
    lens = replace(triplet, surfaces=tuple(replace(s, placement=zero) for s in triplet.surfaces), image_placement=zero)
    p, _, rays = _rays(FIELDS_DEG, half_width=4.0)
    x, y, opl, passed, ours = _drjit(lens, rays, len(p), fresnel=True)
    u, v, path, passes, theirs = _drjit(triplet, rays, len(p), fresnel=True)
    assert 0 < passed.sum() < len(p) and np.array_equal(passed, passes)
    for a, b in (
        (x, u),
        (y, v),
        (opl, path),
        *zip(
            tracer.to_numpy(ours.stop_x, ours.stop_y, ours.transmittance),
            tracer.to_numpy(theirs.stop_x, theirs.stop_y, theirs.transmittance),
        ),
    ):
        assert np.abs(a - b)[passed].max() < 1e-12
    assert np.array_equal(*tracer.to_numpy(ours.clipped_by, theirs.clipped_by))


def test_a_bundle_traced_in_drjit_is_the_numpy_tracer_s(cooke_as_built):
    """`trace_bundle`: `local_trace.trace`'s result (global points and directions, image and stop points, paths)."""
    lens = cooke_as_built(True, 1.5)
    p, d, _ = _rays(FIELDS_DEG)
    ours = tracer_local.trace_bundle(lens, local_trace.bundle(p, d), lens.primary_wavelength)
    theirs = local_trace.trace(lens, local_trace.bundle(p, d), lens.primary_wavelength)
    assert ours.ok.sum() > 200 and np.array_equal(ours.ok, theirs.ok)
    for name in ("x", "y", "z", "dx", "dy", "dz", "opl", "image_x", "image_y", "stop_x", "stop_y"):
        assert np.abs(getattr(ours, name) - getattr(theirs, name))[ours.ok].max() < 1e-9, name
