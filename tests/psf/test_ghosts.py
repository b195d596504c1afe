"""Two-reflection ghosts (`optics.ghost_paths`, `psf.ghosts`) against closed forms: a plane-parallel plate's
ghost energy R₁R₂ (relative to the direct image; R₁R₂T₁T₂ of the light that enters) and its lateral
displacement 2 t tan θ' at field θ, with bare faces and coated ones; every ghost of a rotationally
symmetric lens on axis centred on the axis; the path count N(N−1)/2; the command's table and files."""

import math
import re

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.errors import SolasError
from solas_mi.optics import coating, ghost_paths
from solas_mi.psf import stray_light as ghosts

THICKNESS = 8.0


def plate(front=None, back=None):
    """A stop in air, then a plane-parallel N-BK7 plate wide enough that no face clips the ghost."""
    faces = [
        {"radius": 0.0, "thickness": THICKNESS, "diameter": 80.0, "material": "N-BK7"},
        {"radius": 0.0, "thickness": 50.0, "diameter": 80.0},
    ]
    for face, c in zip(faces, (front, back)):
        if c is not None:
            face["coating"] = c
    return Lens.from_dict(
        {"name": "plate", "surface": [{"radius": 0.0, "thickness": 5.0, "diameter": 10.0, "stop": True}, *faces]}
    )


@pytest.mark.parametrize("coated", [False, True])
@pytest.mark.parametrize("deg", [0.0, 12.0, 35.0])
def test_plate_ghost_energy_and_displacement_are_the_closed_forms(coated, deg):
    c = {"kind": "quarter_wave", "material": "MGF2", "design_nm": 550.0} if coated else None
    lens = plate(c, c)
    wavelength = 531.0
    report = ghosts.ghosts(lens, (0.0, deg), [wavelength], rays=64)
    (ghost,) = report.ghosts
    assert ghost.surfaces == (3, 2)
    n = float(lens.surfaces[1].glass.index(wavelength))
    sin_t = math.sin(math.radians(deg)) / n
    cos_t, cos_a = math.sqrt(1.0 - sin_t**2), math.cos(math.radians(deg))
    inside = (
        lens.surfaces[1].coating.power(n, 1.0, wavelength, cos_t)
        if coated
        else coating.stack_power(n, [], [], 1.0, wavelength, cos_t)
    )
    entering = (
        lens.surfaces[1].coating.power(1.0, n, wavelength, cos_a)
        if coated
        else coating.stack_power(1.0, [], [], n, wavelength, cos_a)
    )
    r = float(inside.reflectance)  # both reflections: from the glass side at θ' (the faces are alike)
    t = float(entering.transmittance) * float(inside.transmittance)
    assert abs(ghost.energy - r * r) <= 1e-9 * r * r
    assert abs(ghost.energy * t - r * r * t) <= 1e-9 * r * r * t  # of the light that enters: R₁R₂T₁T₂
    shift = 2.0 * THICKNESS * sin_t / cos_t
    assert abs(ghost.centroid_mm[1] - report.direct_centroid_mm[1] - shift) <= 1e-9 * max(shift, 1e-9) + 1e-12
    assert abs(ghost.centroid_mm[0] - report.direct_centroid_mm[0]) < 1e-12


def test_on_axis_every_ghost_is_centred_and_the_paths_number_n_n_minus_1_over_2(triplet):
    report = ghosts.ghosts(triplet, (0.0, 0.0), [587.5618], rays=64)
    surfaces = ghost_paths.reflecting(triplet)
    assert len(report.ghosts) == len(surfaces) * (len(surfaces) - 1) // 2 == 15
    for g in report.ghosts:
        assert g.energy > 0 and max(abs(c) for c in g.centroid_mm) < 1e-9 * max(g.rms_mm, 1.0)
    assert abs(report.direct_centroid_mm[0]) < 1e-12 and abs(report.direct_centroid_mm[1]) < 1e-12


@pytest.mark.parametrize(
    "front", [{}, {"conic": -0.6, "aspheric": [2e-6, -1e-9]}, {"qbfs": [0.01, -0.004], "norm_radius": 15.0}]
)
def test_the_direct_path_is_the_tracer_s(doublet_spec, front):
    """The ghost tracer's direct path lands where the Dr.Jit tracer's does (same rays, same lens): spheres,
    and a front face made a conic with even-asphere terms, or a Qbfs asphere (Newton's method both ways)."""
    from solas_mi.optics import tracer

    doublet_spec["surface"][0].update(front)
    doublet = Lens.from_dict(doublet_spec)
    start = ghosts.launch(doublet, (0.0, 1.5), 16)
    end = ghost_paths.trace(doublet, None, start, 531.0)
    rays = tracer.Rays(
        *(tracer.F(a) for a in (start.x, start.y, start.z, start.dx, start.dy, start.dz)),
        tracer.F(np.zeros(len(start.x))),
    )
    traced = tracer.trace(doublet, rays, tracer.F(0.531))
    x, y, ok, clipped = tracer.to_numpy(*tracer.to_plane(traced, doublet.image_z)[:2], traced.ok, traced.clipped_by)
    passed = ok & (clipped == 0)
    t = (doublet.image_z - end.z) / end.dz
    np.testing.assert_allclose(end.x + t * end.dx, x[passed], atol=1e-9)
    np.testing.assert_allclose(end.y + t * end.dy, y[passed], atol=1e-9)


def test_ideal_lens_and_bad_rays_are_refused():
    lens = Lens.from_dict(
        {
            "name": "ideal",
            "surface": [{"radius": 0.0, "thickness": 100.0, "diameter": 10.0, "stop": True, "focal_length": 100.0}],
        }
    )
    with pytest.raises(SolasError, match="ideal thin lens"):
        ghosts.ghosts(lens, (0.0, 0.0))
    with pytest.raises(SolasError, match="rays 3 must be an integer from 8"):
        ghosts.ghosts(plate(), (0.0, 0.0), rays=3)


def test_ghosts_command_prints_the_table_and_writes_the_hdr_psf(tmp_path, capsys):
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr

    out = tmp_path / "ghosts.exr"
    assert main(["ghosts", "solas-doublet", "--field-deg", "0,1", "--size", "64", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "3,1" in printed and "all ghosts" in printed and (tmp_path / "ghosts.png").exists()
    channels, meta = read_exr(out)
    data = channels["Y"]
    assert np.isfinite(data).all() and data.min() >= 0
    assert abs(data.sum() - 1.0) < 0.01  # the direct image's energy 1 (the window holds it), ghosts ~1e-5 more
    assert len(meta["ghosts"]) == 3 and meta["unit"].startswith("fraction of the direct image")


def test_ghosts_command_warns_only_by_its_own_options_and_asks_for_rays_where_none_arrive(tmp_path, capsys):
    """At 8 rays per side no ray of the doublet's grid arrives by any ghost path (each energy 0, as the table shows):
    the command says to raise --rays, naming the 8; a window of 9 px of 0.2 um holds too little of the direct image
    for its Fraunhofer core, and that note names no option the command lacks (its parser's, the one place)."""
    import argparse

    from solas_mi.cli import build_parser, main

    assert not any(g.energy for g in ghosts.ghosts(Lens.load("solas-doublet"), (0.0, 0.0), rays=8).ghosts)
    out = tmp_path / "ghosts.exr"
    argv = ["ghosts", "solas-doublet", "--field-deg", "0,0", "--rays", "8", "--pitch-um", "0.2", "--size", "9"]
    assert main([*argv, "-o", str(out)]) == 0
    err = capsys.readouterr().err
    (commands,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    takes = {flag for action in commands.choices["ghosts"]._actions for flag in action.option_strings}
    assert "raise --rays (now 8)" in err and "Fraunhofer core is not sound" in err
    assert set(re.findall(r"--[a-z][a-z-]*", err)) <= takes


def test_shared_prefixes_give_each_path_s_own_trace(triplet):
    """`trace_all` (paths sharing their common parts) equals `trace` of each path alone, bit for bit."""
    start = ghosts.launch(triplet, (0.0, 8.0), 24)
    together = ghost_paths.trace_all(triplet, start, 587.5618)
    assert set(together) == {None, *ghost_paths.paths(triplet)}
    for path, r in together.items():
        alone = ghost_paths.trace(triplet, path, start, 587.5618)
        for a, b in zip(
            (r.x, r.y, r.z, r.dx, r.dy, r.dz, r.power),
            (alone.x, alone.y, alone.z, alone.dx, alone.dy, alone.dz, alone.power),
        ):
            assert np.array_equal(a, b)


def test_a_near_point_source_on_axis_gives_centred_ghosts(doublet_spec):
    """A point source at a finite distance (rays from the point, its power per cell ∝ cos³/d²): on axis
    every ghost is centred; the direct image's centroid too."""
    doublet_spec["object"] = {"distance": 2000.0}
    lens = Lens.from_dict(doublet_spec)
    report = ghosts.ghosts(lens, (0.0, 0.0), [531.0], rays=64)
    assert len(report.ghosts) == 3 and all(g.energy > 0 for g in report.ghosts)
    for g in report.ghosts:
        assert max(abs(c) for c in g.centroid_mm) < 1e-9
    assert max(abs(c) for c in report.direct_centroid_mm) < 1e-12


def test_a_fisheye_takes_fields_from_the_front_only():
    """A lens of polar fields: a field below 89° is launched along its polar direction (on the y axis the
    same as an angle field's), one from the side is refused by name, never traced along a wrong direction."""
    lens = Lens.load("nikkor-fisheye")
    report = ghosts.ghosts(lens, (0.0, 30.0), [587.5618], rays=32)
    assert report.direct_power > 0 and report.direct_centroid_mm[1] > 0
    with pytest.raises(SolasError, match="polar angle below 89 deg"):
        ghosts.ghosts(lens, (0.0, 95.0), rays=16)


def test_a_focused_ghost_is_called_so_and_blurred_by_its_airy_pattern(tmp_path):
    """A singlet's ghost (3, 2) focuses 93 mm before the image: with the image plane moved there it is
    focused (RMS far inside its Airy radius 0.61 λ / NA), and the HDR PSF spreads its light by that
    pattern: the Airy kernel sums to 1 and its first dark ring lies at the radius."""
    from solas_mi.psf import stray_psf

    rows = [
        {"radius": 0.0, "thickness": 2.0, "diameter": 2.0, "stop": True},
        {"radius": 51.68, "thickness": 4.0, "diameter": 20.0, "material": "N-BK7"},
        {"radius": -51.68, "thickness": 97.0, "diameter": 20.0},
    ]
    spec = {"name": "singlet", "wavelengths_nm": [550.0], "surface": rows}
    (ghost,) = ghosts.ghosts(Lens.from_dict(spec), (0.0, 0.0), rays=96).ghosts
    assert not ghost.focused and ghost.focus_mm < -50
    rows[-1]["thickness"] += ghost.focus_mm
    (focused,) = ghosts.ghosts(Lens.from_dict(spec), (0.0, 0.0), rays=96).ghosts
    assert focused.focused and focused.rms_mm < 0.5 * focused.airy_mm and 1e-3 < focused.airy_mm < 0.1
    kernel = stray_psf.airy_kernel(6.0)
    assert abs(kernel.sum() - 1.0) < 1e-12
    centre = len(kernel) // 2
    ring = kernel[centre, centre + 4 : centre + 9]  # the profile from 4 to 8 pixels out: its minimum at 6
    assert int(np.argmin(ring)) + 4 == 6
    image = np.zeros((64, 64))
    image[32, 32] = 1.0
    blurred = stray_psf.airy_blur(image, 3.0)
    assert abs(blurred.sum() - 1.0) < 1e-9 and blurred.max() < 0.2


def test_the_direct_image_has_its_diffraction_wings_beyond_its_core():
    """Beyond the Fraunhofer core (33 px) the HDR PSF's direct image carries its diffraction wings: its ring means
    agree with a Fraunhofer PSF computed over the whole window (resolved, converged) across the core's edge (no
    step) and out to 38 px (within 40 %, the wings' 1/r³ asymptote), where the rays alone left zero."""
    from solas_mi.psf import stray_psf
    from solas_mi.psf.methods import psf

    lens, size, pitch, fine = Lens.load("solas-doublet"), 81, 10.0, 3
    report = ghosts.ghosts(lens, (0.0, 0.0), rays=16)
    report.hits = {}  # the direct image alone
    data, _, notes = stray_psf.stray_psf(lens, report, pitch, size)
    whole = psf(lens, (0.0, 0.0), list(lens.wavelengths_nm), pitch_um=pitch / fine, size=size * fine,
                normalization="sum", pupil_samples=448)  # fmt: skip
    assert not notes and not whole.meta["warnings"]
    reference = whole.data.reshape(size, fine, size, fine).sum(axis=(1, 3)) * float(whole.meta["energy_in_grid"])
    r = np.hypot(*(np.indices((size, size)) - size // 2))
    for ring in (15, 16, 17, 18, 24, 30, 38):
        near = np.abs(r - ring) < 0.5
        assert data[near].mean() == pytest.approx(reference[near].mean(), rel=0.1 if ring < 20 else 0.4), ring


@pytest.mark.parametrize("size", [2, 16, 32])
def test_an_even_window_narrower_than_the_core_holds_the_core_centred(size):
    """An even --size below the widest core (33 px) once made a 33 px core for a 32 px window (a broadcast
    error); the core is now the widest odd window inside the grid, its centre pixel the grid's (size // 2):
    the PSF is finite, carries at most the direct image's light, and is centred within a pixel."""
    from solas_mi.psf import stray_psf

    lens = Lens.load("solas-doublet")
    report = ghosts.ghosts(lens, (0.0, 0.0), rays=16)
    report.hits = {}  # the direct image alone
    data, _, _ = stray_psf.stray_psf(lens, report, 10.0, size)
    assert data.shape == (size, size) and np.isfinite(data).all() and 0 < data.sum() <= 1.0 + 1e-9
    centroid = [float((np.indices(data.shape)[k] * data).sum() / data.sum()) for k in (0, 1)]
    assert centroid == pytest.approx([size // 2, size // 2], abs=1.0)
