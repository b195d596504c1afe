"""The shipped fisheye (nikkor-fisheye, US 7,161,746 B2): published focal length and f-number,
polar fields up to 90°, and real chief rays aimed through the stop centre by continuation."""

import numpy as np
import pytest

from solas_mi import Lens, SolasError
from solas_mi.optics import glass as glass_mod
from solas_mi.optics import pupil as P
from solas_mi.optics import tracer as T
from solas_mi.optics.fields import ANGLE, POLAR
from solas_mi.optics.paraxial import paraxial
from solas_mi.psf import psf

LINE_D = 587.5618  # nm


@pytest.fixture(scope="module")
def fisheye():
    return Lens.load("nikkor-fisheye")


def test_published_efl_and_f_number(fisheye):
    p = paraxial(fisheye, LINE_D)
    assert abs(p.efl_mm / 10.5 - 1.0) < 1e-3
    assert abs(p.f_number / 2.8 - 1.0) < 1e-2
    assert fisheye.field_type is POLAR and fisheye.field_deg >= 90.0


# The patent's n_d / V_d per element (US 7,161,746 B2), in file order.
PATENT_GLASS = [
    (1.62041, 60.29),
    (1.81600, 46.63),
    (1.72000, 43.69),
    (1.77250, 49.61),
    (1.72825, 28.46),
    (1.51742, 52.42),
    (1.83481, 42.72),
    (1.84666, 23.78),
    (1.49700, 81.61),
    (1.65160, 58.54),
]


def test_the_glasses_are_vendor_glasses_of_the_patents_nd_vd(fisheye):
    glasses = [s.glass for s in fisheye.surfaces if s.glass.kind != "air"]
    assert len(glasses) == len(PATENT_GLASS)
    for g, (nd, vd) in zip(glasses, PATENT_GLASS):
        assert g.kind in ("sellmeier", "polynomial") and g.name.split(":")[0] in glass_mod.VENDORS
        assert g.name in [m.key for m in glass_mod.match(nd, vd)]
        formula_nd, formula_vd = g.abbe()
        assert abs(formula_nd - nd) <= 4e-6 and abs(formula_vd - vd) <= 0.015, g.name
        lo, hi = g.range_nm
        assert lo <= 380.0 and hi >= 780.0, g.name  # the srgb response renders over 380-780 nm
    # n_d as the patent's to 4e-6: the d-line EFL is the scaled 10.5 mm to 1e-5 (the model glasses gave 10.500034)
    assert paraxial(fisheye, LINE_D).efl_mm == pytest.approx(10.5, rel=1e-5)


def test_scaled_to_10_5_mm_the_image_circle_is_the_products_diagonal(fisheye):
    """An independent check of the file's scaling (the transcription traces to 9.8995 mm; every length
    is ×1.060657 for the published 10.5 mm): the product's angle of view, 180° across the diagonal of
    the 23.6 × 15.8 mm DX frame, puts 90° at the half-diagonal 14.20 mm. The scaled lens lands its
    real chief ray there within 2 % (measured 14.00 mm); the table as transcribed lands 7 % short."""
    from dataclasses import replace

    half_diagonal = 0.5 * np.hypot(23.6, 15.8)
    ninety = np.array([[0.0, 90.0]])
    h = chief_rays_height(fisheye, ninety)
    assert abs(h / half_diagonal - 1.0) < 0.02
    k = 10.5 / 9.8995
    printed = replace(
        fisheye,
        surfaces=tuple(
            replace(s, radius=s.radius / k, thickness=s.thickness / k, diameter=s.diameter / k)
            for s in fisheye.surfaces
        ),
    )
    assert paraxial(printed, LINE_D).efl_mm == pytest.approx(9.8995, rel=1e-4)
    assert chief_rays_height(printed, ninety) / half_diagonal < 0.94


def chief_rays_height(lens, field_deg):
    return float(np.hypot(*P.chief_rays(lens, field_deg, np.array([LINE_D])).image_xy[0]))


def test_chief_rays_reach_the_stop_centre_out_to_90_degrees(fisheye):
    theta = np.concatenate([[0.0, 1.0], np.arange(10.0, 91.0, 10.0)])
    fields = np.stack([np.zeros_like(theta), theta], axis=-1)
    chief = P.chief_rays(fisheye, fields, np.full(len(theta), LINE_D))
    # the aimed rays, traced again from their entrance coordinates, cross the stop at its centre
    b = P.Bundle(fisheye, fields, np.full(len(theta), LINE_D), 1)
    tr = b.trace(T.F(chief.entrance[:, 0]), T.F(chief.entrance[:, 1]))
    ok, sx, sy = T.to_numpy(tr.ok, tr.stop_x, tr.stop_y)
    assert ok.all() and not chief.vignetted.any()
    assert np.abs(sx).max() < 1e-9 and np.abs(sy).max() < 1e-9
    h = chief.image_xy[:, 1]
    # paraxial near the axis (distortion grows as θ²: 1.2 % at 10°, so about 1e-4 at 1°), then a
    # fisheye: monotonic in θ and finite at 90°, where a rectilinear lens would need an infinite image
    assert abs(h[1] / (paraxial(fisheye, LINE_D).efl_mm * np.tan(np.radians(1.0))) - 1.0) < 5e-4
    assert np.all(np.diff(h) > 0) and np.isfinite(h[-1])
    # the frame's half-diagonal (23.6 x 15.8 mm: 14.2 mm) is reached within 2 % at 90°: 180° diagonal
    assert abs(h[-1] / np.hypot(11.8, 7.9) - 1.0) < 0.02


def test_polar_field_is_rotationally_symmetric(fisheye):
    """The same polar angle at any azimuth lands at the same image radius, rotated by the azimuth."""
    theta, phis = 85.0, np.radians([0.0, 30.0, 90.0, 200.0])
    fields = np.degrees(np.radians(theta) * np.stack([np.cos(phis), np.sin(phis)], axis=-1))
    xy = P.chief_rays(fisheye, fields, np.full(len(phis), LINE_D)).image_xy
    r = np.hypot(xy[:, 0], xy[:, 1])
    assert np.ptp(r) < 1e-9 * r[0]
    assert np.allclose(np.arctan2(xy[:, 1], xy[:, 0]) % (2 * np.pi), phis % (2 * np.pi), atol=1e-12)


def test_direction_launch_matches_tangent_launch_on_axis(doublet):
    """Below 90° on the y axis the direction form and the tangent form name the same rays. Their
    launch planes pivot at different points (the origin, and the axis point at launch_plane_z, L mm
    in front of it), so the same ray has e_y larger by L sin θ in the direction form."""
    theta = np.radians(np.array([0.0, 1.0, 2.0]))
    ex, ey = T.F([0.3, -1.2, 2.5]), T.F([1.0, 0.5, -2.0])
    a = T.launch(doublet, T.F(0.0 * theta), T.F(np.tan(theta)), ex, ey)
    d = POLAR.incoming(np.stack([0.0 * theta, np.degrees(theta)], axis=-1))
    shift = T.F(-T.launch_plane_z(doublet) * np.sin(theta))
    b = T.launch_direction(doublet, T.F(d[:, 0]), T.F(d[:, 1]), T.F(d[:, 2]), ex, ey + shift)
    wl = T.F([0.531] * 3)
    ta, tb = T.trace(doublet, a, wl), T.trace(doublet, b, wl)
    pa, pb = T.to_numpy(ta.rays.x, ta.rays.y, ta.rays.dy), T.to_numpy(tb.rays.x, tb.rays.y, tb.rays.dy)
    for u, v in zip(pa, pb):
        assert np.allclose(u, v, rtol=0, atol=1e-11)


def test_polar_field_limits():
    assert POLAR.check((0.0, 95.0)) == (0.0, 95.0)
    with pytest.raises(SolasError, match="below 180 deg"):
        POLAR.check((130.0, 130.0))
    with pytest.raises(SolasError, match="below 89 deg"):
        ANGLE.check((0.0, 95.0))


def test_polar_lens_with_an_aspheric_first_surface_is_refused(tmp_path):
    """Rays of polar fields meet surface 1 from the side, which is intersected as a whole sphere: a
    conic there is refused when the lens is read, not met later as a field the lens cannot image."""
    from solas_mi.resources import resource_dir

    text = (
        (resource_dir("scenes") / "lenses" / "nikkor_fisheye.toml")
        .read_text()
        .replace("radius = 90.1559", "radius = 90.1559\nconic = -0.5", 1)
    )
    assert "conic = -0.5" in text
    (tmp_path / "fe.toml").write_text(text)
    with pytest.raises(SolasError, match="surface 1 .* conic or asphere; a lens of polar fields"):
        Lens.load(tmp_path / "fe.toml")
    (tmp_path / "fe85.toml").write_text(text.replace("field_deg = 90.0", "field_deg = 85.0"))
    assert Lens.load(tmp_path / "fe85.toml").field_type is ANGLE  # tangent fields: the conic is traced


def test_psf_at_the_edge_of_the_field(fisheye):
    """At 90° (on the y axis and on the diagonal) the PSF is finite, sums to one and says how much of
    the transmitted light its window holds, converged under pupil refinement; both azimuths give the
    same transmission (symmetry, to the square pupil grid's resolution). 64 pupil samples alias there (the PSF warns so): 256 are needed."""
    out = [
        psf(fisheye, f, LINE_D, size=64, pitch_um=2.0, pupil_samples=n)
        for f, n in [((0.0, 90.0), 256), ((63.6396, 63.6396), 256), ((0.0, 90.0), 512)]
    ]
    for p in out:
        assert np.isfinite(p.data).all() and p.data.min() >= 0 and abs(p.data.sum() - 1.0) < 1e-12
        assert 0.0 < p.meta["energy_in_grid"] <= 1.0 and 0.0 < p.meta["transmission"] < 1.0
        assert abs(np.hypot(*p.chief_ray_mm) - 14.0045) < 1e-3
    assert abs(out[0].meta["transmission"] - out[1].meta["transmission"]) < 2e-3  # square pupil grid
    assert abs(out[0].meta["energy_in_grid"] - out[2].meta["energy_in_grid"]) < 1e-3


def test_rim_rays_fill_the_stop_out_to_90_degrees(fisheye):
    """Rays aimed at RIM_RAYS points of the stop's rim (grown out from the chief ray) all reach them
    to 1e-9 mm at 0…90°: the pupil ray fan fills the stop however the entrance pupil moves and tilts."""
    theta = np.array([0.0, 30.0, 60.0, 85.0, 90.0])
    fields = np.stack([np.zeros_like(theta), theta], axis=-1)
    wl = np.full(len(theta), LINE_D)
    chief = P.chief_rays(fisheye, fields, wl)
    ex, ey, tr, ok = P.stop_rim(P.Bundle(fisheye, fields, wl, P.RIM_RAYS), chief)
    sx, sy = T.to_numpy(tr.stop_x, tr.stop_y)
    phi = np.linspace(0.0, 2.0 * np.pi, P.RIM_RAYS, endpoint=False)
    r_stop = fisheye.surfaces[fisheye.stop_index].semi_diameter
    assert ok.all()
    assert np.abs(sx.reshape(ok.shape) - r_stop * np.cos(phi)).max() < 1e-9
    assert np.abs(sy.reshape(ok.shape) - r_stop * np.sin(phi)).max() < 1e-9
    # across the beam, the entrance pupil at 90° is squeezed along the field's azimuth (y: 3.64 → 1.63 mm)
    # and widened across it (x: 3.64 → 4.86 mm), as fisheye pupils grow toward the edge
    assert np.ptp(ey, axis=-1)[-1] < 0.5 * np.ptp(ey, axis=-1)[0]
    assert np.ptp(ex, axis=-1)[-1] > 1.2 * np.ptp(ex, axis=-1)[0]


def test_chief_ray_illumination_of_polar_fields_is_the_tangent_form(doublet_spec):
    """Per solid angle (polar fields: h·dh/dθ / sin θ) and per tangent area (cos³θ · J(0)/J) are the
    same radiometry: the doublet read with polar fields gives its relative illumination to 3e-4 (the
    finite differences differ: a one-sided step in θ against a central one in tan θ)."""
    from solas_mi.optics.illumination import chief_ray_illumination

    polar = Lens.from_dict(dict(doublet_spec, field_deg=89.0))
    assert polar.field_type is POLAR
    fields = np.array([[0.0, 1.0], [0.0, 2.0], [1.5, 0.0]])
    expected = chief_ray_illumination(Lens.from_dict(doublet_spec), fields, 531.0)
    assert chief_ray_illumination(polar, fields, 531.0) == pytest.approx(expected, abs=3e-4)


def test_lens_info_of_the_fisheye_names_its_projection(capsys):
    from solas_mi.cli import main

    assert main(["lens", "info", "nikkor-fisheye"]) == 0
    out = capsys.readouterr().out
    assert "closest projection: equisolid" in out and "rectilinear undefined beyond 90 deg" in out
    last = [line for line in out.splitlines() if line.strip().startswith("90.000")][-1].split()
    assert 0.3 < float(last[-1]) < 0.6  # relative illumination at 90°: finite (was inf)
