"""The lens as built: coordinate breaks (`placement`), surfaces without rotational symmetry in a lens
file, and the NumPy tracer that works in each surface's frame (`local_trace`): the same rays as the
Dr.Jit tracer through every shipped lens and an asphere, a tilted plate's shift t·sin(θ − θ′)/cos θ′,
a decentred ideal lens's image moved by the decentre × (1 − m), the TOML round trip, and the stages
that take symmetric lenses only refusing the others by name; in .zmx files (`zemax_asbuilt`): TOROIDAL
and BICONICX read scaled by UNIT, the round trip through .zmx and TOML, an element tilted and returned as
OpticStudio's break pair leaves it, and what is not read refused by name."""

import math
import re

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics import aiming, ghost_paths, local_aim, local_trace, pupil, shapes, tracer
from solas_mi.optics.lens import shipped_lenses
from solas_mi.optics.placement import FACING_LIMIT, SPIN_LIMIT, Placement, frames


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


ASPHERE_ROWS = (
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
ASPHERE = _lens(*ASPHERE_ROWS)


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


def test_a_sensor_tilted_by_scheimpflug_s_angle_images_a_tilted_object_plane_sharply():
    """Scheimpflug: an object plane tilted by α (z = −s + y tan α) images through an ideal lens (f) onto the
    plane tilted by β, tan β = m tan α (m = −s′/s), through the axial image: every pencil from the object
    plane meets in one point on a sensor tilted by β (`image_placement`); on the upright sensor the pencils
    off the axis are blurred."""
    s, f, alpha = 150.0, 50.0, math.radians(20.0)
    image = 1.0 / (1.0 / f - 1.0 / s)
    beta = math.degrees(math.atan(-image / s * math.tan(alpha)))
    rows = ({"radius": 0.0, "focal_length": f, "thickness": image, "diameter": 30.0, "stop": True},)
    tilted = _lens(*rows, object={"distance": s}, image={"tilt_x": beta})
    upright = _lens(*rows, object={"distance": s})
    aim = np.stack([a.ravel() for a in np.meshgrid(np.linspace(-8, 8, 5), np.linspace(-8, 8, 5))] + [np.zeros(25)], 1)
    for y in (-20.0, 0.0, 15.0, 30.0):
        point = np.array([0.0, y, -s + y * math.tan(alpha)])
        pencil = local_trace.bundle(point, aim - point)
        sharp, blurred = (local_trace.trace(lens, pencil, 550.0) for lens in (tilted, upright))
        assert sharp.ok.all() and np.ptp(sharp.image_x) < 1e-12 and np.ptp(sharp.image_y) < 1e-11
        assert y == 0.0 or np.ptp(blurred.image_y) > 0.1


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
    lens = _lens(*AS_BUILT, image={"decentre_y": 0.2, "tilt_x": 1.5})
    assert [s.kind for s in lens.surfaces] == [row.get("kind", "plane") for row in AS_BUILT]
    assert lens.surfaces[1].placement == Placement(0.1, 0.0, 0.0, 0.5, 0.0, 0)
    back = Lens.load(lens.save(tmp_path / "as-built.toml"))
    assert back.hash == lens.hash and back.surfaces == lens.surfaces and back.image_placement == lens.image_placement
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
        ({"tilt_x": 1e300}, f"tilt_x = 1e+300 degrees; |tilt_x| must be below {FACING_LIMIT:g}"),
        ({"tilt_y": 90.0}, f"tilt_y = 90 degrees; |tilt_y| must be below {FACING_LIMIT:g}"),
        ({"tilt_z": -1e3}, f"tilt_z = -1000 degrees; |tilt_z| must be at most {SPIN_LIMIT:g}"),
        ({"radius_rotation": 7.0}, "the toroid closes before the clear semi-diameter 8"),
    ],
)
def test_a_bad_kind_or_break_is_named(change, message):
    with pytest.raises(SolasError, match=re.escape(message)):
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
    sensor = _lens(*ASPHERE_ROWS, image={"tilt_x": 0.5})
    with pytest.raises(SolasError, match=r"its image plane \(the sensor\) is decentred or tilted, which the ghost"):
        ghost_paths.paths(sensor)
    with pytest.raises(SolasError, match="a .dat file holds no surfaces without rotational symmetry"):
        lens.save(tmp_path / "as-built.dat")
    assert shapes.KINDS["toroid"].extra["symmetric"] is False


def test_a_lens_as_built_grown_by_s_images_s_times_farther_out():
    """`scale.scaled`: every length (radii, terms, decentres) times s, the tilts kept: a bundle grown by s
    meets the image plane at s times the points."""
    from solas_mi.optics.scale import scaled

    lens, s = _lens(*AS_BUILT), 1.9
    points = np.stack([np.linspace(-3, 3, 5), np.linspace(-1, 2, 5), np.full(5, -5.0)], 1)
    out = local_trace.trace(lens, local_trace.bundle(points, [0.0, 0.02, 1.0]), 550.0)
    big = local_trace.trace(scaled(lens, s), local_trace.bundle(points * s, [0.0, 0.02, 1.0]), 550.0)
    assert out.ok.all() and big.ok.all()
    assert np.abs(big.image_x - s * out.image_x).max() < 1e-12 and np.abs(big.image_y - s * out.image_y).max() < 1e-12


def _zmx(surfaces: str, unit: str = "MM") -> str:
    return f"""VERS 190513 80 123457 L123457
MODE SEQ
NAME as-built
UNIT {unit} X W X CM MR CPMM
FLOA
FTYP 0 0 1 1 0 0 0
XFLN 0
YFLN 0
WAVM 1 0.55 1
PWAV 1
SURF 0
  TYPE STANDARD
  DISZ INFINITY
{surfaces}SURF 99
  TYPE STANDARD
  DISZ 0
"""


def _load(tmp_path, text: str) -> Lens:
    path = tmp_path / "lens.zmx"
    path.write_text(text)
    return Lens.load(path)


SINGLET = """SURF 1
  STOP
  TYPE TOROIDAL
  CURV 0.25
  CONI -0.5
  PARM 1 -3.0
  PARM 2 0.002
  PARM 3 -0.0001
  DISZ 0.4
  GLAS N-BK7 0 0 1.5168 64.17 0 0 0 0 0 0
  DIAM 0.8 1
SURF 2
  TYPE BICONICX
  CURV -0.1
  CONI 0.3
  PARM 1 -2.5
  PARM 2 -0.7
  DISZ 5
  DIAM 0.8 1
"""


def test_toroidal_and_biconicx_read_scaled_to_mm(tmp_path):
    """In centimetres: radii and the radius of rotation ×10, α_i (on y^2i) ×10^(1−2i), conics kept."""
    toroid, biconic = (s.form for s in _load(tmp_path, _zmx(SINGLET, "CM")).surfaces)
    assert toroid == shapes.KINDS["toroid"].function(40.0, -0.5, (0.002 / 10, -0.0001 / 1000), -30.0)
    assert biconic.radius == pytest.approx(-100.0, rel=1e-15) and biconic.conic == 0.3
    assert (biconic.radius_x, biconic.conic_x) == (-25.0, -0.7)
    assert (
        shapes.KINDS["cylinder"].function(4.0, -0.5)
        == _load(tmp_path, _zmx(SINGLET.replace("  PARM 1 -3.0\n  PARM 2 0.002\n  PARM 3 -0.0001\n", "")))
        .surfaces[0]
        .form
    )


def test_the_lens_as_built_round_trips_through_zmx_and_toml(tmp_path):
    lens = _lens(*AS_BUILT, image={"tilt_y": -2.0, "tilt_order": 1})
    back = Lens.load(Lens.load(lens.save(tmp_path / "a.zmx")).save(tmp_path / "b.toml"))
    for s, t in zip(lens.surfaces, back.surfaces):
        assert s.placement == t.placement and s.kind == t.kind and back.image_placement == lens.image_placement
        assert all(
            v == pytest.approx(w, rel=1e-15) for v, w in zip(s.geometry.table().values(), t.geometry.table().values())
        )
    eight = _lens({**AS_BUILT[0], "terms_y": [1e-5] * 8}, *AS_BUILT[1:])
    with pytest.raises(SolasError, match="a toroid of 8 terms_y has no .zmx form"):
        eight.save(tmp_path / "eight.zmx")


def test_an_element_tilted_and_returned_by_a_break_pair(tmp_path):
    """OpticStudio's element tilt: a break tilting by θ before the element, its reverse (order 1, values
    negated) after: the element lies in the tilted frame; after it the axes are the original ones, the
    vertex moved by the element's thickness along the tilted axis, t (0, −sin θ, cos θ)."""
    theta, t = 3.0, 4.0
    text = _zmx(f"""SURF 1
  TYPE COORDBRK
  DISZ 0
  PARM 3 {theta}
SURF 2
  STOP
  CURV 0.02
  DISZ {t}
  GLAS N-BK7 0 0 1.5168 64.17 0 0 0 0 0 0
  DIAM 8 1
SURF 3
  CURV -0.02
  DISZ 0
  DIAM 8 1
SURF 4
  TYPE COORDBRK
  DISZ 0
  PARM 3 {-theta}
  PARM 6 1
SURF 5
  CURV 0
  DISZ 50
  DIAM 8 1
""")
    lens = _load(tmp_path, text)
    assert [s.placement for s in lens.surfaces] == [Placement(tilt_x=theta), None, Placement(tilt_x=-theta, order=1)]
    origin, axes = frames(lens.surfaces)[2]
    assert np.abs(axes - np.eye(3)).max() < 1e-15
    assert (
        np.abs(origin - t * np.array([0.0, -math.sin(math.radians(theta)), math.cos(math.radians(theta))])).max()
        < 1e-15
    )


@pytest.mark.parametrize("order", [0, 1])
def test_a_break_with_a_thickness_of_its_own_places_the_next_surface_as_zemax_does(tmp_path, order):
    """A COORDBRK with DISZ t: the next vertex lies t along the new z axis from the break's point, its axes the
    break's (built here from `Placement.apply` and that step); the reader folds t into the gap before and the
    decentres, exactly."""
    t, moves = 5.0, (0.2, -0.1, 3.0, -2.0, 10.0)
    cb = "".join(f"  PARM {k} {v}\n" for k, v in enumerate(moves, start=1)) + f"  PARM 6 {order}\n"
    lens = _load(tmp_path, _zmx(SINGLET + f"SURF 3\n  TYPE COORDBRK\n  DISZ {t}\n{cb}SURF 4\n  DISZ 10\n  DIAM 1 1\n"))
    origin, axes = Placement(*moves, order).apply(np.array([0.0, 0.0, 0.4 + 5.0]), np.eye(3))
    expected = origin + axes[:, 2] * t
    placed = frames(lens.surfaces)[2]
    assert np.abs(placed[0] - expected).max() < 1e-12 and np.abs(placed[1] - axes).max() < 1e-15


@pytest.mark.parametrize(
    "extra, message",
    [
        (
            "SURF 3\n  TYPE COORDBRK\n  DISZ 0\n  PARM 3 5\nSURF 4\n  TYPE COORDBRK\n  DISZ 0\n  PARM 1 2\n",
            "followed by another break that does not undo it",
        ),
        ("SURF 3\n  TYPE TOROIDAL\n  PARM 12 0.5\n  DIAM 1 1\n", "TOROIDAL PARM 12 = 0.5 is not read"),
        ("SURF 3\n  TYPE TOROIDAL\n  XDAT 1 2\n  XDAT 2 3\n  DIAM 1 1\n", "TOROIDAL extra data XDAT 1 = 2 is not read"),
        (
            "SURF 3\n  TYPE TOROIDAL\n  XDAT 2 3\n  XDAT 3 0.1\n  DIAM 1 1\n",
            "TOROIDAL extra data XDAT 2 = 3 is not read",
        ),
        ("SURF 3\n  TYPE COORDBRK\n  DISZ 0\n  PARM 1\n  PARM 3 5\n", r"SURF 3 \(line \d+\): PARM 1 has no value"),
        ("SURF 3\n  TYPE COORDBRK\n  DISZ 0\n  PARM\n  PARM 3 5\n", r"SURF 3 \(line \d+\): PARM has no whole number"),
        ("SURF 3\n  TYPE TOROIDAL\n  XDAT 1\n  DIAM 1 1\n", r"SURF 3 \(line \d+\): XDAT 1 has no value"),
        (
            "SURF 3\n  TYPE COORDBRK\n  DISZ 0\n  PARM 3 1e300\n",
            f"tilt_x = 1e\\+300 degrees; \\|tilt_x\\| must be below {FACING_LIMIT:g}",
        ),
        (
            "SURF 3\n  TYPE COORDBRK\n  DISZ 0\n  PARM 4 -90\n",
            f"tilt_y = -90 degrees; \\|tilt_y\\| must be below {FACING_LIMIT:g}",
        ),
    ],
)
def test_what_is_not_read_is_refused_by_name(tmp_path, extra, message):
    with pytest.raises(SolasError, match=message):
        _load(tmp_path, _zmx(SINGLET + extra))


@pytest.mark.parametrize("name", ["cooke-triplet", "double-gauss-50mm", "wide-angle-22mm"])
def test_chief_rays_aimed_in_two_dimensions_are_the_drjit_tracers(name):
    """`local_aim`: x and y aimed together at the stop's centre land where the Dr.Jit tracer's chief rays do."""
    lens, wl = Lens.load(name), 587.5618
    f = lens.field_deg
    fields = np.array([[0.0, 0.0], [0.3 * f, 0.6 * f], [-0.5 * f, 0.2 * f], [0.7 * f, -0.7 * f]])
    ours = local_aim.chief_rays(lens, fields, wl)
    theirs = pupil.chief_rays(lens, fields, np.full(len(fields), wl))
    assert ours.found.all() and np.abs(ours.image_xy - theirs.image_xy).max() < 1e-9


def test_the_chief_ray_of_a_decentred_ideal_lens_lands_at_the_decentre_plus_f_tan_theta():
    """An ideal lens of focal f decentred by (Dx, Dy), the stop on it, the image plane at its focus back on
    the axis: the chief ray passes the lens's centre undeviated, to (Dx + f tan θx, Dy + f tan θy)."""
    f, dx, dy = 40.0, 0.4, -0.25
    lens = _lens(
        {
            "radius": 0.0,
            "focal_length": f,
            "thickness": f,
            "diameter": 20.0,
            "stop": True,
            "decentre_x": dx,
            "decentre_y": dy,
        },
        {"radius": 0.0, "thickness": 0.0, "diameter": 40.0, "decentre_x": -dx, "decentre_y": -dy},
    )
    fields = np.array([[0.0, 0.0], [3.0, -5.0], [-8.0, 2.0]])
    chief = local_aim.chief_rays(lens, fields, 550.0)
    expected = np.array([dx, dy]) + f * np.tan(np.radians(fields))
    assert chief.found.all() and np.abs(chief.image_xy - expected).max() < 1e-12
    with pytest.raises(SolasError, match="aimed for an object at infinity only"):
        local_aim.chief_rays(_lens(*ASPHERE_ROWS, object={"distance": 500.0}), fields, 550.0)


def test_the_fisheye_s_chief_rays_are_aimed_out_to_80_degrees_as_the_drjit_tracer_s():
    """`local_aim` on the shipped fisheye (no breaks): its chief rays land where the Dr.Jit tracer's do at every
    field the Dr.Jit aim reaches, 0 to 80° in x, y and both (45° once circled without converging)."""
    lens, wl = Lens.load("nikkor-fisheye"), 587.5618
    angles = np.arange(0.0, 81.0, 5.0)
    fields = np.concatenate([np.stack([0 * angles, angles], 1), [[45.0, 0.0], [30.0, 30.0], [-50.0, 40.0]]])
    ours = local_aim.chief_rays(lens, fields, wl)
    theirs = pupil.chief_rays(lens, fields, np.full(len(fields), wl))
    aimed = ~theirs.off_centre
    assert aimed.sum() >= len(fields) - 2 and ours.found[aimed].all()
    assert np.abs(ours.image_xy - theirs.image_xy)[aimed].max() < 1e-9


def test_a_toroid_s_normalisation_radius_without_terms_is_read_as_nothing(tmp_path):
    """TOROIDAL's XDAT 1 is its number of Zernike terms and XDAT 2 their normalisation radius: with no terms
    (Thorlabs' cylinder lenses write XDAT 1 0, XDAT 2 100) the radius changes nothing, and the lens loads as
    without it (it was refused)."""
    plain = _load(tmp_path, _zmx(SINGLET))
    extra = SINGLET.replace("  TYPE TOROIDAL\n", "  TYPE TOROIDAL\n  XDAT 1 0\n  XDAT 2 100\n", 1)
    assert extra != SINGLET and _load(tmp_path, _zmx(extra)).surfaces == plain.surfaces


@pytest.mark.parametrize("key, kind", [("radius_x", "biconic"), ("conic_x", "biconic"), ("terms_y", "toroid")])
def test_a_kind_s_key_without_kind_is_refused_not_dropped(key, kind):
    """A surface's radius_x, conic_x, terms_y or radius_rotation without `kind` was read as a sphere, the key
    dropped unread; it is refused, naming the key and the kind that takes it."""
    row = {key: value for key, value in AS_BUILT[0].items() if key not in ("kind", "terms_y", "radius_rotation")}
    value = [1e-5] if key in shapes.KINDS[kind].extra["lists"] else 30.0
    with pytest.raises(SolasError, match=f"{key} without kind: .* needs kind = '{kind}'"):
        _lens({**row, key: value}, *AS_BUILT[1:])
