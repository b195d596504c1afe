"""A virtual object (a negative object distance: the object point lies behind surface 1 and the light
arrives converging toward it, as Zemax traces `DISZ` < 0 on `SURF 0`) against first-order optics worked
by hand and an independent real-ray trace: an ideal lens by the thin-lens equation, a real singlet by
Gauss's refraction formula surface by surface and Snell's law in vector form; the optical path of the
converging pencil, the round trips, what `lens info` and PSF metadata say, and the refusals of the
renderers that need a scene in front of the lens.

Signs: z along the light, distances from a surface to a point positive when the point lies after it
(s > 0 for a virtual object behind the surface, s' > 0 for a real image); each surface maps
n'/s' = n/s + (n' − n)/R (an ideal lens: 1/s' = 1/s + 1/f), with the lateral magnification
m = (n s')/(n' s).
"""

import math

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.cli import main as cli_main
from solas_mi.optics import pupil as P
from solas_mi.optics import tracer as T
from solas_mi.optics.paraxial import paraxial
from solas_mi.psf import psf

WL = 550.0


def _ideal(f=50.0, gap=10.0, behind=25.0):
    """A flat stop, `gap` mm before an ideal lens of focal length `f`; the object `behind` mm behind
    the ideal lens (gap + behind behind surface 1); the image plane on its thin-lens image."""
    image = 1.0 / (1.0 / behind + 1.0 / f)
    return Lens.from_dict(
        {
            "wavelengths_nm": [WL],
            "field_deg": 5.0,
            "object": {"distance": -(gap + behind)},
            "surface": [
                {"radius": 0.0, "thickness": gap, "diameter": 8.0, "stop": True},
                {"radius": 0.0, "thickness": image, "diameter": 30.0, "focal_length": f},
            ],
        }
    )


def _singlet(distance=-30.0):
    """A biconvex N-BK7 singlet (R1 = 40, R2 = −60 mm, 6 mm thick), its front face the stop, the object
    `distance` mm from surface 1; the image plane on the paraxial image (by hand, `_gauss`)."""
    rows = [
        {"radius": 40.0, "thickness": 6.0, "diameter": 12.0, "stop": True, "material": "N-BK7"},
        {"radius": -60.0, "thickness": 10.0, "diameter": 12.0},
    ]
    n = Lens.from_dict({"surface": rows}).surfaces[0].glass.index(WL)
    rows[1]["thickness"] = _gauss(n, distance)[0]
    return Lens.from_dict(
        {"wavelengths_nm": [WL], "field_deg": 4.0, "object": {"distance": distance}, "surface": rows}
    ), n


def _gauss(n, distance):
    """(s2', m): the image distance after the singlet's back face and the magnification, surface by surface."""
    s1 = -distance  # the object, from surface 1 (positive: behind it)
    s1p = n / (1.0 / s1 + (n - 1.0) / 40.0)
    s2 = s1p - 6.0
    s2p = 1.0 / (n / s2 + (1.0 - n) / -60.0)
    return s2p, (s1p / (n * s1)) * (n * s2p / s2)


def _rays(lens, object_point, aperture=3.0, count=9):
    """A grid of rays from the object point through entrance points (ex, ey) on surface 1's plane,
    traced by the tracer to the image plane: (ex, ey, x, y, opl, ok)."""
    g = np.linspace(-aperture, aperture, count)
    ex, ey = (a.ravel() for a in np.meshgrid(g, g))
    F = T.F
    rays = T.launch(lens, F(0.0 * ex), F(0.0 * ex), F(ex), F(ey), (F(object_point[0]), F(object_point[1])))
    traced = T.trace(lens, rays, F(WL / 1000.0))
    x, y, opl = T.to_numpy(*T.to_plane(traced, lens.image_z))
    (ok,) = T.to_numpy(traced.ok)
    return ex, ey, x, y, opl, ok


def test_an_ideal_lens_images_a_virtual_object_by_the_thin_lens_equation():
    """Object 25 mm behind f = 50: 1/s' = 1/25 + 1/50, s' = 16.67 mm, m = s'/s = +2/3 (erect); every ray
    toward the object point (0.9, 2.1) mm lands on (0.6, 1.4) mm with one optical path (a converging
    pencil's path counted toward its point: a wrong sign leaves 0.05 mm of spread)."""
    lens = _ideal()
    s, s2 = 25.0, 1.0 / (1.0 / 25.0 + 1.0 / 50.0)
    p = paraxial(lens, WL)
    assert p.focus_z_mm == pytest.approx(10.0 + s2, rel=1e-14)
    assert p.image_offset_mm == pytest.approx(0.0, abs=1e-12)
    assert p.efl_mm == pytest.approx(50.0, rel=1e-14)  # the system's, at any object distance
    *_, x, y, opl, ok = _rays(lens, (0.9, 2.1))
    assert ok.all()
    assert np.abs(x - 0.9 * s2 / s).max() < 1e-12 and np.abs(y - 2.1 * s2 / s).max() < 1e-12
    assert np.ptp(opl) < 1e-11
    # the field angle names the chief ray toward the entrance pupil (surface 1's centre): its object point
    # lies 35 mm behind it, at 35·tan θ, and lands m times that away
    chief = P.chief_rays(lens, np.array([[0.0, 5.0]]), np.array([WL])).image_xy[0, 1]
    assert chief == pytest.approx(35.0 * math.tan(math.radians(5.0)) * s2 / s, rel=1e-12)
    assert p.chief_ray_image_height_mm[1] == pytest.approx(chief, rel=1e-12)


def test_a_real_singlet_images_a_virtual_object_by_gauss_formula():
    """Object 30 mm behind the singlet's front vertex: the paraxial image and chief-ray height from
    n'/s' = n/s + (n' − n)/R at each face, the EFL from the thick-lens formula."""
    lens, n = _singlet()
    s2p, m = _gauss(n, -30.0)
    p = paraxial(lens, WL)
    efl = 1.0 / ((n - 1.0) * (1.0 / 40.0 - 1.0 / -60.0 + (n - 1.0) * 6.0 / (n * 40.0 * -60.0)))
    assert p.efl_mm == pytest.approx(efl, rel=1e-13)
    assert p.focus_z_mm == pytest.approx(6.0 + s2p, rel=1e-13)
    assert p.bfd_mm == pytest.approx(s2p, rel=1e-13)
    assert p.entrance_pupil_z_mm == 0.0
    tan = math.tan(math.radians(4.0))
    assert p.chief_ray_image_height_mm[1] == pytest.approx(m * 30.0 * tan, rel=1e-12)


def _snell_trace(n, object_point, ex, ey, image_z):
    """The singlet traced by hand: the line from (ex, ey, 0) toward the object point, each sphere met by its
    quadratic about the centre, Snell's law n (d × N) = n' (d' × N) in vector form."""
    o = np.array([object_point[0], object_point[1], 30.0])
    p = np.stack([ex, ey, np.zeros_like(ex)], -1)
    d = o - p
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    for vertex, radius, n1, n2 in ((0.0, 40.0, 1.0, n), (6.0, -60.0, n, 1.0)):
        c = np.array([0.0, 0.0, vertex + radius])
        w = p - c
        b = np.sum(w * d, -1)
        root = np.sqrt(b * b - (np.sum(w * w, -1) - radius * radius))
        t = np.where(radius > 0, -b - root, -b + root)  # the cap nearer the vertex
        p = p + t[:, None] * d
        normal = (c - p) / radius  # toward +z at the vertex
        cos_i = np.sum(d * normal, -1)
        mu = n1 / n2
        cos_t = np.sqrt(1.0 - mu * mu * (1.0 - cos_i**2))
        d = mu * d + (cos_t - mu * cos_i)[:, None] * normal
    t = (image_z - p[:, 2]) / d[:, 2]
    return p[:, 0] + t * d[:, 0], p[:, 1] + t * d[:, 1]


def test_real_rays_toward_a_virtual_object_follow_snells_law_and_converge_near_axis():
    """The tracer's rays toward the virtual object point (0.5, 1.5) mm land where the hand trace puts them
    (1e-10 mm); the near-axis rays toward a point near the axis converge on its paraxial image."""
    lens, n = _singlet()
    _, m = _gauss(n, -30.0)
    ex, ey, x, y, _, ok = _rays(lens, (0.5, 1.5), aperture=5.0)
    hx, hy = _snell_trace(n, (0.5, 1.5), ex, ey, lens.image_z)
    assert ok.all()
    assert np.abs(x - hx).max() < 1e-10 and np.abs(y - hy).max() < 1e-10
    *_, x, y, _, ok = _rays(lens, (0.02, 0.06), aperture=0.01, count=3)  # aberrations: 2.5e-8 mm
    assert ok.all() and np.abs(x - 0.02 * m).max() < 1e-7 and np.abs(y - 0.06 * m).max() < 1e-7


def test_ideal_lens_on_the_virtual_object_point_keeps_the_pencil_perfect():
    """Zemax's relay form: the stop at surface 1, the object 40 mm behind it on an ideal lens (f = 30), a
    second one (f = 45) 90 mm on, the image on its conjugate. Every ray of a field meets the first lens at
    one point, so its path there is one constant: the wavefront stays flat at 0° and 15° (the public
    Relay_exit_pupilMatched.zmx carried 0.24 mm of OPD at 18.6° when the lens took that point's pencil as
    coming from infinity)."""
    s2 = 1.0 / (1.0 / 45.0 - 1.0 / 90.0)
    lens = Lens.from_dict(
        {
            "wavelengths_nm": [WL],
            "field_deg": 15.0,
            "object": {"distance": -40.0},
            "surface": [
                {"radius": 0.0, "thickness": 40.0, "diameter": 8.0, "stop": True},
                {"radius": 0.0, "thickness": 90.0, "diameter": 40.0, "focal_length": 30.0},
                {"radius": 0.0, "thickness": s2, "diameter": 40.0, "focal_length": 45.0},
            ],
        }
    )
    pf = P.pupil_function(lens, np.array([[0.0, 0.0], [0.0, 15.0]]), np.full(2, WL), 48)
    assert (pf.coverage > 0).sum() > 2 * 1000
    assert np.abs(np.where(pf.coverage > 0, pf.opd_mm, 0.0)).max() < 1e-11
    # the object point 40 tan 15° on the first lens; its image by the second, m = −s2/90
    chief = P.chief_rays(lens, np.array([[0.0, 15.0]]), np.array([WL])).image_xy[0, 1]
    assert chief == pytest.approx(-40.0 * math.tan(math.radians(15.0)) * s2 / 90.0, rel=1e-12)


def test_an_intermediate_image_on_an_ideal_lens_is_perfect_off_axis():
    """The same at a real object: an ideal lens f = 50 images the object 100 mm before it onto a second
    ideal lens (a field lens) 100 mm on; a third lens images that onto the film. The pencil meets the
    field lens at one point: no aberration at 5° either."""
    s3 = 1.0 / (1.0 / 40.0 - 1.0 / 80.0)
    lens = Lens.from_dict(
        {
            "wavelengths_nm": [WL],
            "field_deg": 5.0,
            "object": {"distance": 100.0},
            "surface": [
                {"radius": 0.0, "thickness": 100.0, "diameter": 10.0, "stop": True, "focal_length": 50.0},
                {"radius": 0.0, "thickness": 80.0, "diameter": 40.0, "focal_length": 60.0},
                {"radius": 0.0, "thickness": s3, "diameter": 60.0, "focal_length": 40.0},
            ],
        }
    )
    pf = P.pupil_function(lens, np.array([[0.0, 5.0]]), np.array([WL]), 48)
    assert (pf.coverage > 0).sum() > 1000
    assert np.abs(np.where(pf.coverage > 0, pf.opd_mm, 0.0)).max() < 1e-11


@pytest.mark.parametrize("suffix", [".toml", ".zmx"])
def test_a_virtual_object_round_trips(tmp_path, suffix):
    lens, _ = _singlet()
    back = Lens.load(lens.save(tmp_path / f"v{suffix}"))
    assert back.object_distance == -30.0 and back.virtual_object
    assert back.hash == lens.hash


def test_lens_info_and_psf_metadata_say_the_object_is_virtual(tmp_path, capsys):
    lens = _ideal()
    path = lens.save(tmp_path / "v.toml")
    assert cli_main(["lens", "info", str(path)]) == 0
    assert "object: virtual, 35 mm behind surface 1, light converging toward it" in capsys.readouterr().out
    meta = psf(lens, (0.0, 2.0), WL, size=32).meta
    assert meta["virtual_object"].startswith("35 mm behind surface 1")
    assert "virtual_object" not in psf(_singlet(200.0)[0], (0.0, 0.0), WL, size=32).meta


def test_a_zero_object_distance_is_refused():
    with pytest.raises(SolasError, match=r"object distance 0 must be a non-zero number .*negative: a virtual object"):
        Lens.from_dict(
            {
                "object": {"distance": 0},
                "surface": [{"radius": 0.0, "thickness": 50.0, "diameter": 10.0, "stop": True, "focal_length": 50.0}],
            }
        )


def test_the_mesh_scene_refuses_a_virtual_object_by_name():
    from solas_mi.render.scene import lens_parts

    with pytest.raises(
        SolasError,
        match="the mesh scene: lens .* has a virtual object, 30 mm behind surface 1 .*no scene in front of the lens",
    ):
        lens_parts(_singlet()[0])


ZMX = """VERS 190513 80 123457 L123457
MODE SEQ
UNIT MM X W X CM MR CPMM
OBNA 0.02 0
FTYP 1 0 2 1 0 0 0
XFLN 0 0
YFLN 0 20
WAVM 1 0.55 1
PWAV 1
SURF 0
  TYPE STANDARD
  CURV 0.0
  DISZ -500
SURF 1
  STOP
  TYPE STANDARD
  CURV 0.0
  DISZ 50
SURF 2
  TYPE PARAXIAL
  PARM 1 100
  DISZ {image!r}
  DIAM 30 1
SURF 3
  TYPE STANDARD
  CURV 0.0
  DISZ 0
"""


def test_a_zemax_file_with_a_virtual_object_sizes_its_pupil_and_fields(tmp_path):
    """DISZ −500 on SURF 0: the object-space NA 0.02 makes the stop's semi-diameter 500·tan(asin 0.02) (the
    cone converging on the point behind it), and the 20 mm object-height field the angle atan(20/500) toward
    the entrance pupil, positive, whose object point lies 20 mm off the axis."""
    s2 = 1.0 / (1.0 / 450.0 + 1.0 / 100.0)  # the ideal lens 50 mm on sees the object 450 mm behind it
    (tmp_path / "virtual.zmx").write_text(ZMX.replace("{image!r}", repr(s2)))
    lens = Lens.load(tmp_path / "virtual.zmx")
    assert lens.object_distance == -500.0
    assert lens.surfaces[0].semi_diameter == pytest.approx(500.0 * math.tan(math.asin(0.02)), rel=1e-12)
    assert lens.field_deg == pytest.approx(math.degrees(math.atan(20.0 / 500.0)), rel=1e-12)
    assert abs(T.object_points(lens, np.array([[0.0, lens.field_deg]]))[0, 1]) == pytest.approx(20.0, rel=1e-12)
    p = paraxial(lens)  # 1/s' = 1/450 + 1/100, m = s'/450
    assert p.focus_z_mm == pytest.approx(50.0 + s2, rel=1e-13)
    assert abs(p.chief_ray_image_height_mm[1]) == pytest.approx(20.0 * s2 / 450.0, rel=1e-12)


def test_an_object_in_the_entrance_pupil_is_refused_by_name(tmp_path):
    """The stop 40 mm behind surface 1 and the virtual object on it: every chief ray meets the object point,
    so an object-height field names no angle (it divided by zero) and a field angle no object point."""
    text = (
        ZMX.replace("DISZ -500", "DISZ -40")
        .replace("  STOP\n", "")
        .replace("  TYPE PARAXIAL", "  STOP\n  TYPE PARAXIAL")
        .replace("OBNA 0.02 0", "ENPD 10")
        .replace("{image!r}", "80")
    )
    (tmp_path / "pupil.zmx").write_text(text.replace("DISZ 50", "DISZ 40"))
    with pytest.raises(SolasError, match=r"the object lies in the entrance pupil \(40 mm from surface 1\)"):
        Lens.load(tmp_path / "pupil.zmx")
