"""The lens as built: coordinate breaks (`placement`), surfaces without rotational symmetry in a lens
file, and the NumPy tracer that works in each surface's frame (`local_trace`): the same rays as the
Dr.Jit tracer through every shipped lens and an asphere, a tilted plate's shift t·sin(θ − θ′)/cos θ′,
a decentred ideal lens's image moved by the decentre × (1 − m), the TOML round trip, and the stages
that take symmetric lenses only refusing the others by name."""

import math

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics import aiming, ghost_paths, local_trace, pupil, shapes, tracer
from solas_mi.optics.lens import shipped_lenses
from solas_mi.optics.placement import Placement


def _lens(*rows, **extra) -> Lens:
    return Lens.from_dict({"name": "as-built", "surface": [dict(r) for r in rows], **extra})


def _collimated(lens, field_deg, n=9):
    """The Dr.Jit tracer's launch (`aiming.Bundle`) of an n×n bundle about the chief ray of `field_deg`,
    and its rays' points and directions."""
    chief = pupil.chief_rays(lens, np.array([field_deg]), np.array([lens.primary_wavelength])).entrance[0]
    span = np.linspace(-0.05, 0.05, n) * lens.surfaces[lens.stop_index].semi_diameter
    ex, ey = (a.ravel() for a in np.meshgrid(chief[0] + span, chief[1] + span))
    rays = aiming.Bundle(lens, np.array([field_deg]), np.array([lens.primary_wavelength]), n * n).launch(
        tracer.F(ex), tracer.F(ey)
    )
    return (
        rays,
        np.stack(tracer.to_numpy(rays.x, rays.y, rays.z), 1),
        np.stack(tracer.to_numpy(rays.dx, rays.dy, rays.dz), 1),
    )


ASPHERE = _lens(
    {
        "radius": 30.0,
        "conic": -0.7,
        "aspheric": [2e-6, -1e-9],
        "qbfs": [0.01, -0.004],
        "norm_radius": 9.0,
        "thickness": 5.0,
        "diameter": 18.0,
        "material": "N-BK7",
        "stop": True,
    },
    {"radius": -60.0, "thickness": 40.0, "diameter": 18.0},
)


@pytest.mark.parametrize("name", [*shipped_lenses(), "asphere"])
def test_the_numpy_tracer_traces_symmetric_lenses_as_the_drjit_tracer(name):
    """Image points and optical paths within 1e-9 mm at fields in two dimensions (all kinds of today)."""
    lens = ASPHERE if name == "asphere" else Lens.load(name)
    wl = lens.primary_wavelength
    top = lens.field_deg
    for field in ([0.0, 0.0], [0.3 * top, 0.6 * top], [0.0, -0.8 * top]):
        rays, p, d = _collimated(lens, field)
        traced = tracer.trace(lens, rays, tracer.F(np.full(len(p), wl * 1e-3)))
        x, y, opl = tracer.to_numpy(*tracer.to_plane(traced, lens.image_z))
        passed = tracer.to_numpy(traced.ok & (traced.clipped_by == 0))[0]
        ours = local_trace.trace(lens, local_trace.bundle(p, d), wl)
        assert passed.sum() > 40 and np.array_equal(ours.ok, passed)
        for a, b in ((ours.image_x, x), (ours.image_y, y), (ours.opl, opl)):
            assert np.abs(a - b)[passed].max() < 1e-9


@pytest.mark.parametrize("order, tilt", [(0, 12.0), (1, -25.0)])
def test_a_tilted_plate_shifts_a_ray_by_its_closed_form(order, tilt):
    """A plate of thickness t tilted by θ shifts the ray along the axis by t·sin(θ − θ′)/cos θ′,
    sin θ = n sin θ′, and leaves its direction."""
    t = 4.0
    lens = _lens(
        {
            "radius": 0.0,
            "thickness": t,
            "diameter": 30.0,
            "material": "N-BK7",
            "stop": True,
            "tilt_x": tilt,
            "tilt_order": order,
        },
        {"radius": 0.0, "thickness": 20.0, "diameter": 30.0},
    )
    out = local_trace.trace(lens, local_trace.bundle([0.0, 0.0, -10.0], [0.0, 0.0, 1.0]), 587.56)
    theta = math.radians(abs(tilt))
    inside = math.asin(math.sin(theta) / lens.surfaces[0].glass.index(587.56))
    assert out.ok.all() and abs(out.x[0]) < 1e-15
    assert abs(abs(out.y[0]) - t * math.sin(theta - inside) / math.cos(inside)) < 1e-12
    assert abs(out.dy[0]) < 1e-15 and out.dz[0] == pytest.approx(1.0, abs=1e-15)


def test_a_decentred_ideal_lens_moves_the_image_by_the_decentre_times_one_minus_m():
    """An object 200 mm before an f = 50 mm ideal lens decentred by D in y (a break back before the image
    plane): every ray from the axial object point meets at y = D (1 − m), m = −s′/s."""
    s, f, decentre = 200.0, 50.0, 0.7
    image = 1.0 / (1.0 / f - 1.0 / s)
    lens = _lens(
        {"radius": 0.0, "focal_length": f, "thickness": 10.0, "diameter": 20.0, "stop": True, "decentre_y": decentre},
        {"radius": 0.0, "thickness": image - 10.0, "diameter": 40.0, "decentre_y": -decentre},
        object={"distance": s},
    )
    gx, gy = (a.ravel() for a in np.meshgrid(np.linspace(-6, 6, 7), np.linspace(-6, 6, 7) + decentre))
    out = local_trace.trace(lens, local_trace.bundle([0.0, 0.0, -s], np.stack([gx, gy, np.full(gx.size, s)], 1)), 550.0)
    m = -image / s
    assert out.ok.all()
    assert np.abs(out.y - decentre * (1.0 - m)).max() < 1e-12 and np.abs(out.x).max() < 1e-12


def test_breaks_chain_and_undo():
    """A break of order 1 with every value negated undoes one of order 0."""
    there = Placement(0.3, -0.2, 5.0, -7.0, 30.0, 0)
    back = Placement(-0.3, 0.2, -5.0, 7.0, -30.0, 1)
    origin, axes = back.apply(*there.apply(np.zeros(3), np.eye(3)))
    assert np.abs(origin).max() < 1e-15 and np.abs(axes - np.eye(3)).max() < 1e-15


AS_BUILT = (
    {
        "kind": "toroid",
        "radius": 40.0,
        "conic": -0.3,
        "terms_y": [1e-5],
        "radius_rotation": -80.0,
        "thickness": 4.0,
        "diameter": 16.0,
        "material": "N-BK7",
        "stop": True,
    },
    {
        "kind": "biconic",
        "radius": -50.0,
        "radius_x": -70.0,
        "conic_x": 0.5,
        "thickness": 2.0,
        "diameter": 16.0,
        "decentre_x": 0.1,
        "tilt_y": 0.5,
    },
    {
        "kind": "cylinder",
        "radius": 60.0,
        "thickness": 3.0,
        "diameter": 16.0,
        "material": "N-SF5",
        "tilt_z": 90.0,
        "tilt_order": 1,
    },
    {"radius": 0.0, "thickness": 40.0, "diameter": 16.0},
)


def test_kinds_and_breaks_read_write_and_read_back(tmp_path):
    lens = _lens(*AS_BUILT)
    assert [s.kind for s in lens.surfaces] == [row.get("kind", "plane") for row in AS_BUILT]
    assert lens.surfaces[1].placement == Placement(0.1, 0.0, 0.0, 0.5, 0.0, 0)
    back = Lens.load(lens.save(tmp_path / "as-built.toml"))
    assert back.hash == lens.hash and back.surfaces == lens.surfaces
    assert lens.hash != _lens(*AS_BUILT[:1], {**AS_BUILT[1], "tilt_y": 0.6}, *AS_BUILT[2:]).hash
    out = local_trace.trace(
        lens,
        local_trace.bundle(np.stack([np.linspace(-3, 3, 5), np.zeros(5), np.full(5, -5.0)], 1), [0.0, 0.0, 1.0]),
        550.0,
    )
    assert out.ok.all() and np.isfinite(out.image_y).all()


@pytest.mark.parametrize(
    "change, message",
    [
        ({"kind": "freeform"}, f"kind = 'freeform' must be one of {', '.join(shapes.NAMED)}"),
        ({"aspheric": [1e-6]}, "a toroid takes radius, conic, terms_y, radius_rotation; not aspheric"),
        ({"tilt_order": 2}, "tilt_order = 2 must be one of 0, 1"),
        ({"tilt_x": "5"}, "tilt_x = '5' must be a finite number"),
        ({"radius_rotation": 7.0}, "the toroid closes before the clear semi-diameter 8"),
    ],
)
def test_a_bad_kind_or_break_is_named(change, message):
    with pytest.raises(SolasError, match=message.replace("(", r"\(")):
        _lens({**AS_BUILT[0], **change}, *AS_BUILT[1:])


def test_the_stages_of_symmetric_lenses_refuse_the_lens_as_built_by_name(tmp_path):
    lens = _lens(*AS_BUILT)
    rays, _, _ = _collimated(ASPHERE, [0.0, 0.0], 2)
    with pytest.raises(SolasError, match=r"surface 1 \(surface 1\) is a toroid, which the Dr.Jit tracer"):
        tracer.trace(lens, rays, tracer.F(np.full(4, 0.55)))
    with pytest.raises(SolasError, match="the ghost tracer"):
        ghost_paths.paths(lens)
    tilted = _lens(
        {"radius": 0.0, "thickness": 5.0, "diameter": 10.0, "stop": True, "tilt_x": 1.0},
        {"radius": 0.0, "thickness": 5.0, "diameter": 10.0},
    )
    with pytest.raises(SolasError, match=r"decentred or tilted \(a coordinate break before it\)"):
        tracer.trace(tilted, rays, tracer.F(np.full(4, 0.55)))
    with pytest.raises(SolasError, match="a .zmx file holds no surfaces without rotational symmetry"):
        lens.save(tmp_path / "as-built.zmx")
    assert shapes.KINDS["toroid"].extra["symmetric"] is False
