"""Lenses whose surfaces overlap, loaded and traced as Zemax traces them: a glass element of negative
thickness (an optimiser's zero), an air gap whose faces cross inside their clear apertures, an image on the
last surface. Each is checked against numbers derived without the code under test: thick-lens and
ray-transfer-matrix formulas, and a hand trace of one real ray with the signed intersection (a line meets
a sphere where it meets it, before or after the point it comes from)."""

import math
import re

import numpy as np
import pytest

from solas_mi import Lens, SolasError, paraxial
from solas_mi.optics import tracer as T
from solas_mi.optics.focus import focused

N = 1.5  # model glass: one index at every wavelength
WL = 550.0


def _lens(surfaces, **extra):
    return Lens.from_dict({"name": "overlap", "wavelengths_nm": [WL], "surface": surfaces, **extra}, source="o.toml")


def _sphere_root(y, z, dy, dz, vertex, radius):
    """Where the line (y, z) + s (dy, dz) meets the sphere of `radius` through (0, vertex): the root nearer
    the vertex plane, whatever its sign of s (the cap about the axis)."""
    cz = vertex + radius
    b = 2 * (y * dy + (z - cz) * dz)
    c = y * y + (z - cz) ** 2 - radius * radius
    roots = [(-b + sign * math.sqrt(b * b - 4 * c)) / 2 for sign in (1, -1)]
    return min(roots, key=lambda s: abs(z + s * dz - vertex))


def _hand_ray(h, surfaces, image_z):
    """A ray parallel to the axis at height h through (vertex z, radius, n after) in order, from n = 1: its
    height on the plane image_z. Snell's law in vector form, the normal turned along the ray."""
    y, z, dy, dz, n = h, -100.0, 0.0, 1.0, 1.0
    for vertex, radius, n2 in surfaces:
        s = (vertex - z) / dz if radius == 0 else _sphere_root(y, z, dy, dz, vertex, radius)
        y, z = y + s * dy, z + s * dz
        ny, nz = (0.0, 1.0) if radius == 0 else (y / abs(radius), (z - vertex - radius) / abs(radius))
        if ny * dy + nz * dz < 0:
            ny, nz = -ny, -nz
        mu, cosi = n / n2, ny * dy + nz * dz
        k = math.sqrt(1 - mu * mu * (1 - cosi * cosi))
        dy, dz, n = mu * dy + (k - mu * cosi) * ny, mu * dz + (k - mu * cosi) * nz, n2
    return y + (image_z - z) / dz * dy


def _traced(lens, h):
    """The tracer's height on the image plane of the ray parallel to the axis at height h."""
    f = T.F(np.array([0.0]))
    tr = T.trace(lens, T.launch(lens, f, f, f, T.F(np.array([h]))), T.F(np.array([WL * 1e-3])))
    _, y, _ = T.to_plane(tr, lens.image_z)
    ok, y = T.to_numpy(tr.ok, y)
    assert ok[0]
    return float(y[0])


def _matrix_focus(elements):
    """EFL and BFD of (curvature, n before, n after, thickness after) refractions by ray-transfer matrices."""
    m = np.eye(2)
    for i, (c, n1, n2, t) in enumerate(elements):
        m = np.array([[1.0, 0.0], [-(n2 - n1) * c / n2, n1 / n2]]) @ m
        if i < len(elements) - 1:
            m = np.array([[1.0, t], [0.0, 1.0]]) @ m
    efl = -1.0 / m[1, 0]  # n = 1 on both sides
    return efl, -m[0, 0] / m[1, 0]


def test_negative_glass_element():
    """A biconcave element of centre thickness −0.02 mm (as a Cooke triplet's optimised F2 at −2.5e-5 mm):
    its faces overlap about the axis, within r = √(0.02 / (1/120 + 1/80)) ≈ 0.98 mm, and part beyond. The
    thick-lens formulas with the negative thickness give EFL and BFD (a virtual focus); real rays at 0.5 mm
    (inside the overlap: the second face comes first) and 5 mm land where the hand trace puts them."""
    r1, r2, t = -40.0, 60.0, -0.02
    efl = 1.0 / ((N - 1) * (1 / r1 - 1 / r2 + (N - 1) * t / (N * r1 * r2)))
    bfd = efl * (1 - (N - 1) * t / (N * r1))
    lens = _lens(
        [
            {"radius": r1, "thickness": t, "diameter": 16.0, "material": "model:1.5", "stop": True},
            {"radius": r2, "thickness": 30.0, "diameter": 16.0},
        ]
    )
    p = paraxial(lens, WL)
    assert p.efl_mm == pytest.approx(efl, rel=1e-12) and p.bfd_mm == pytest.approx(bfd, rel=1e-12)
    (note,) = lens.overlaps
    assert re.match(
        r"surfaces 1 \(surface 1\) and 2 \(surface 2\) overlap within r = [\d.]+ mm .*thickness -0.02 mm"
        r"\): traced sequentially, as Zemax does; the lens cannot be built as solid geometry",
        note,
    )
    r = float(re.search(r"r = ([\d.]+) mm", note).group(1))  # where the faces meet: gap 0 by the sphere sags
    sag = lambda radius: radius - math.copysign(math.sqrt(radius * radius - r * r), radius)  # noqa: E731
    assert t + sag(r2) - sag(r1) == pytest.approx(0.0, abs=1e-4)
    assert r == pytest.approx(math.sqrt(0.02 / (1 / 120 + 1 / 80)), rel=1e-3)
    for h in (0.5, 5.0):
        hand = _hand_ray(h, [(0.0, r1, N), (t, r2, 1.0)], t + 30.0)
        assert _traced(lens, h) == pytest.approx(hand, abs=1e-9)


def test_air_gap_crossing_at_the_rim():
    """Two air-spaced elements whose facing faces (R −40 and −35 mm, 0.5 mm apart on the axis) cross at
    r ≈ 16.7 mm, inside their 20 mm clear semi-diameters: EFL and BFD by ray-transfer matrices, the crossing
    where the sphere sags close the gap, and a real ray at 18 mm (beyond it: the second face comes first)
    where the hand trace with signed steps puts it."""
    s = [(60.0, 10.0, "model:1.5"), (-40.0, 0.5, "AIR"), (-35.0, 3.0, "model:1.5"), (-80.0, 0.0, "AIR")]
    c = [1 / r for r, _, _ in s]
    efl, bfd = _matrix_focus([(c[0], 1, N, 10.0), (c[1], N, 1, 0.5), (c[2], 1, N, 3.0), (c[3], N, 1, 0.0)])
    rows = [{"radius": r, "thickness": t, "diameter": 40.0, "material": m} for r, t, m in s]
    rows[0]["stop"], rows[-1]["thickness"] = True, bfd
    lens = _lens(rows)
    p = paraxial(lens, WL)
    assert p.efl_mm == pytest.approx(efl, rel=1e-12) and p.bfd_mm == pytest.approx(bfd, rel=1e-12)
    (note,) = lens.overlaps
    assert note.startswith("surfaces 2 (surface 2) and 3 (surface 3) cross at r = ")
    r = float(re.search(r"r = ([\d.]+) mm", note).group(1))
    sag = lambda radius, x: radius - math.copysign(math.sqrt(radius * radius - x * x), radius)  # noqa: E731
    gap = lambda x: 0.5 + sag(-35.0, x) - sag(-40.0, x)  # noqa: E731  (by the sphere sags)
    assert gap(r - 0.01) > 0 > gap(r + 0.01) and 15 < r < 17
    z = np.cumsum([0.0, 10.0, 0.5, 3.0])
    hand = _hand_ray(18.0, [(z[0], 60.0, N), (z[1], -40.0, 1.0), (z[2], -35.0, N), (z[3], -80.0, 1.0)], lens.image_z)
    assert _traced(lens, 18.0) == pytest.approx(hand, abs=1e-9)


def _rod():
    """A plano-convex rod (R 20 mm) whose flat back face, n R / (n − 1) = 60 mm behind, is its focus and image."""
    return _lens(
        [
            {"radius": 20.0, "thickness": N * 20.0 / (N - 1), "diameter": 12.0, "material": "model:1.5", "stop": True},
            {"radius": 0.0, "thickness": 0.0, "diameter": 12.0},
        ]
    )


def test_check_stability_expects_the_refusal_of_an_image_on_the_last_surface():
    """check-stability's exit-pupil case, which samples over the last vertex plane, expects the refusal."""
    from solas_mi.validation import stability

    case = stability._exit_pupil(_rod(), WL)
    assert case.passed and "the image plane lies on the last surface" in case.observed


def test_image_on_a_flat_last_surface():
    """A plano-convex rod whose flat back face is its focus (t = n R / (n − 1)): the image plane at
    distance 0 from the last surface loads, named; EFL R/(n − 1), BFD 0; a real ray at 4 mm lands where the
    single-surface hand trace puts it; focused at infinity it stays, at 1 m the image moves by Newton's
    f²/(d − f) (in glass: the flat face's refraction leaves the paraxial shift in air the same). What samples rays from an image point over the last vertex plane
    (relative illumination, the lens camera's pupil bounds) refuses it by name."""
    from solas_mi.optics.exit_pupil import pupil_bounds
    from solas_mi.optics.illumination import irradiance

    lens, radius = _rod(), 20.0
    t = N * radius / (N - 1)
    p = paraxial(lens, WL)
    assert p.efl_mm == pytest.approx(radius / (N - 1), rel=1e-12) and p.bfd_mm == pytest.approx(0.0, abs=1e-12)
    assert lens.image_z == t
    assert lens.overlaps == (
        "the image plane lies on surface 2 (surface 2) (distance 0 mm): traced sequentially, "
        "as Zemax does; the lens cannot be built as solid geometry",
    )
    assert _traced(lens, 4.0) == pytest.approx(_hand_ray(4.0, [(0.0, radius, N)], t), abs=1e-9)
    assert focused(lens, math.inf).image_z == t  # focused where it is: the image stays on the surface
    near = focused(lens, 1000.0)  # Newton: the image moves f² / (1000 − f) behind the focal point
    f = radius / (N - 1)
    assert near.surfaces[-1].thickness == pytest.approx(f * f / (1000.0 - f), rel=1e-9)
    for run in (lambda: irradiance(lens, np.zeros((1, 2)), WL), lambda: pupil_bounds(lens, 1.0)):
        with pytest.raises(SolasError, match=r"image plane lies on the last surface \(distance 0 mm\)"):
            run()


def test_virtual_image_and_touching_glass_stay_refused():
    """A negative distance to the image is a virtual image; glass of thickness 0 whose faces only touch
    (a biconcave element: its faces part away from the axis) holds no glass and overlaps nothing."""
    rows = [
        {"radius": 40.0, "thickness": 3.0, "diameter": 12.0, "material": "model:1.5", "stop": True},
        {"radius": 0.0, "thickness": -1.0, "diameter": 12.0},
    ]
    with pytest.raises(SolasError, match=r"distance to the image -1 mm must be positive: .*a virtual image"):
        _lens(rows)
    rows = [
        {"radius": -40.0, "thickness": 0.0, "diameter": 12.0, "material": "model:1.5", "stop": True},
        {"radius": 40.0, "thickness": 50.0, "diameter": 12.0},
    ]
    with pytest.raises(
        SolasError,
        match=r"surface 1 \(surface 1\): thickness 0 mm inside glass model:1.5, its "
        "faces touching without crossing",
    ):
        _lens(rows)


ZMX = """VERS 190513
MODE SEQ
NAME overlap singlet
UNIT MM X W X CM MR CPMM
ENPD 10
FTYP 0 0 1 1 0 0 0
XFLN 0
YFLN 0
WAVM 1 0.55 1
SURF 0
  TYPE STANDARD
  CURV 0.0
  DISZ INFINITY
SURF 1
  STOP
  TYPE STANDARD
  CURV {c1!r}
  DISZ -0.02
  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0
  DIAM 8 1 0 0 1 ""
SURF 2
  TYPE STANDARD
  CURV {c2!r}
  DISZ {bfd!r}
  DIAM 8 1 0 0 1 ""
SURF 3
  TYPE STANDARD
  CURV 0.0
  DISZ 0
"""


def test_zemax_file_and_command_line(tmp_path, capsys):
    """The negative element as a .zmx: loaded, written back (.zmx, .toml) with its negative thickness (a
    pbrt .dat refused: pbrt steps only forward), the
    overlap stated by `lens info` (text and JSON), PSF metadata and as a warning where a command loads it; the mesh scene
    refuses it, naming the surfaces and pointing to the tracer."""
    from strict_json import strict_loads

    from solas_mi.cli import main
    from solas_mi.render.scene import lens_parts

    r1, r2, t = -40.0, 60.0, -0.02
    efl = 1.0 / ((N - 1) * (1 / r1 - 1 / r2 + (N - 1) * t / (N * r1 * r2)))
    path = tmp_path / "neg.zmx"
    path.write_text(ZMX.format(c1=1 / r1, c2=1 / r2, bfd=30.0))
    lens = Lens.load(path)
    assert paraxial(lens, WL).efl_mm == pytest.approx(efl, rel=1e-12)
    for again in (Lens.load(lens.save(tmp_path / "again.zmx")), Lens.load(lens.save(tmp_path / "again.toml"))):
        assert again.surfaces[0].thickness == t and again.overlaps == lens.overlaps
    with pytest.raises(
        SolasError,
        match=r"surfaces 1 \(SURF 1\) and 2 \(SURF 2\) overlap .*pbrt's realistic camera "
        "steps only forward",
    ):
        lens.save(tmp_path / "again.dat")
    assert not (tmp_path / "again.dat").exists()
    assert main(["lens", "info", str(path)]) == 0
    out, err = capsys.readouterr()
    assert "overlap: surfaces 1 (SURF 1) and 2 (SURF 2) overlap within r = " in out
    assert "warning: lens overlap singlet: surfaces 1 (SURF 1) and 2 (SURF 2) overlap within r = " in err
    assert main(["lens", "info", str(path), "--json"]) == 0
    assert strict_loads(capsys.readouterr().out)["overlaps"] == list(lens.overlaps)
    from solas_mi.psf import psf

    assert psf(lens, (0.0, 0.0), WL, size=16).meta["overlaps"] == list(lens.overlaps)
    with pytest.raises(
        SolasError,
        match=r"lens overlap singlet cannot be built as Mitsuba geometry: surfaces 1 "
        r"\(SURF 1\) and 2 \(SURF 2\) overlap within .* the lens camera",
    ):
        lens_parts(lens)


@pytest.mark.parametrize("thickness, overlaps", [(0.5, True), (2.0, False)])
def test_a_tilted_face_overlaps_where_its_tilt_brings_it_before_the_last(thickness, overlaps):
    """A flat face tilted 10° about x behind a flat face `thickness` mm before it, both 20 mm across: its points at
    y < 0 come first where |y| sin 10° > thickness (nowhere inside r = 10 mm for 2 mm: 10 sin 10° = 1.74)."""
    lens = _lens(
        [
            {"radius": 0.0, "thickness": thickness, "diameter": 20.0, "material": "N-BK7", "stop": True},
            {"radius": 0.0, "thickness": 20.0, "diameter": 20.0, "tilt_x": 10.0},
        ]
    )
    if not overlaps:
        assert lens.overlaps == ()
        return
    (note,) = lens.overlaps
    x, y = map(
        float, re.search(r"overlap at \(x, y\) = \(([-\d.e]+), ([-\d.e]+)\) mm of the first's frame", note).groups()
    )
    ring = thickness / math.sin(math.radians(10.0))  # the tilted face's first ring that comes before
    assert note.startswith("surfaces 1 (surface 1) and 2 (surface 2) overlap at") and y < 0
    assert ring * math.cos(math.radians(10.0)) - 0.01 < math.hypot(x, y) < ring + 10.0 / 64 + 0.01


def test_the_lens_as_built_of_the_stages_overlaps_nothing(cooke_as_built):
    assert cooke_as_built(True, 1.5).overlaps == ()
