"""PSFs of the lens as built (`psf.as_built`, `psf.as_built_fraunhofer`): a lens whose placements are all zero
gives the symmetric path's PSFs, a decentred ideal lens's light lands the decentre × (1 − m) away, a field grid is
traced whole (no mirror) and a tilted sensor's PSFs differ on the two sides of the field."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from solas_mi import Lens
from solas_mi.optics import pupil
from solas_mi.optics.placement import Placement
from solas_mi.optics.pupil import Pupils
from solas_mi.psf import as_built, as_built_fraunhofer, geometric
from solas_mi.psf.fraunhofer import fraunhofer

PITCH_UM, SIZE, RAYS = 2.0, 33, 64


def _zero_placed(lens: Lens) -> Lens:
    """`lens` with a coordinate break of all zeros before every surface and at the image plane."""
    return replace(
        lens, surfaces=tuple(replace(s, placement=Placement()) for s in lens.surfaces), image_placement=Placement()
    )


@pytest.mark.parametrize("name", ["solas-doublet", "cooke-triplet", "double-gauss-50mm", "wide-angle-22mm"])
def test_a_lens_placed_with_zero_breaks_gives_the_symmetric_paths_geometric_psfs(name):
    lens = Lens.load(name)
    fields = np.array([[0.0, 0.0], [0.0, 0.6 * lens.field_deg], [0.3 * lens.field_deg, -0.5 * lens.field_deg]])
    wl = np.full(len(fields), lens.primary_wavelength)
    chief = pupil.chief_rays(lens, fields, wl)
    half = geometric.entrance_half_width(lens, fields, wl, chief)
    expected, _, power = geometric.geometric(lens, fields, wl, PITCH_UM, SIZE, RAYS, chief)
    data, image_xy, transmission = as_built.geometric(_zero_placed(lens), fields, wl, PITCH_UM, SIZE, RAYS, half)
    peak = expected.max(axis=(1, 2), keepdims=True)
    assert np.abs(data - expected).max() / peak.min() < 1e-9
    assert np.abs(image_xy - chief.image_xy).max() < 1e-9
    assert np.abs(transmission - power).max() < 1e-12
    _, _, found = as_built.geometric(_zero_placed(lens), fields, wl, PITCH_UM, SIZE, RAYS)
    assert np.abs(found - power).max() < 0.02 * power.max()  # the coarse pass's grid holds the whole pupil


def _ideal(decentre) -> Lens:
    """An f = 40 mm ideal lens, its own stop, decentred by `decentre` (x, y mm) and returned before the image
    plane at its focus."""
    dx, dy = decentre
    return Lens.from_dict(
        {
            "name": "decentred-ideal",
            "surface": [
                {
                    "radius": 0.0,
                    "focal_length": 40.0,
                    "thickness": 40.0,
                    "diameter": 10.0,
                    "stop": True,
                    "decentre_x": dx,
                    "decentre_y": dy,
                },
                {"radius": 0.0, "thickness": 0.0, "diameter": 40.0, "decentre_x": -dx, "decentre_y": -dy},
            ],
        }
    )


def test_a_decentred_ideal_lens_moves_its_psf_by_the_decentre_times_one_minus_m():
    """Object at infinity (m = 0): the light of every field lands D away from where the centred lens puts it."""
    shift = np.array([0.3, -0.2])
    for field in ([0.0, 0.0], [4.0, -6.0]):
        (centred, _), (moved, _) = (as_built.field_hits(_ideal(d), field, 550.0, 32) for d in ([0.0, 0.0], shift))
        centroid = [np.array([h.x @ h.power, h.y @ h.power]) / h.power.sum() for h in (centred, moved)]
        assert np.abs(centroid[1] - centroid[0] - shift * (1.0 - 0.0)).max() < 1e-12
        assert abs(moved.power.sum() - centred.power.sum()) < 1e-12  # the same light, moved


def _rms_radius_um(psf: np.ndarray) -> np.ndarray:
    """RMS radius (µm) of each PSF (n, size, size) about its centroid."""
    c = (np.arange(SIZE) - SIZE // 2) * PITCH_UM
    yy, xx = np.meshgrid(c, c, indexing="ij")
    w = psf / psf.sum(axis=(1, 2), keepdims=True)
    mx, my = (w * xx).sum(axis=(1, 2)), (w * yy).sum(axis=(1, 2))
    return np.sqrt((w * ((xx - mx[:, None, None]) ** 2 + (yy - my[:, None, None]) ** 2)).sum(axis=(1, 2)))


def test_a_tilted_sensors_field_grid_is_traced_whole_and_each_side_defocused_by_y_tan_tilt():
    """The doublet with its sensor tilted 0.5° about x: the PSFs at +y and −y differ (no half of the field
    mirrored), each as the untilted lens's at the defocus y·tan(0.5°) its image point's height gives."""
    lens = Lens.load("solas-doublet")
    tilt = 0.5
    tilted = replace(lens, image_placement=Placement(tilt_x=tilt))
    fields = np.array([[0.0, 0.7 * lens.field_deg], [0.0, -0.7 * lens.field_deg]])
    wl = lens.primary_wavelength
    data, image_xy, _ = as_built.geometric(tilted, fields, wl, PITCH_UM, SIZE, RAYS)
    radius = _rms_radius_um(data)
    assert abs(radius[0] - radius[1]) > 0.1 * radius.max()  # one side sharper than the other (measured: 14 %)
    level = _rms_radius_um(as_built.geometric(lens, fields, wl, PITCH_UM, SIZE, RAYS)[0])
    assert abs(level[0] - level[1]) < 1e-9 * level.max()  # ... which the untilted sensor's are not
    waves = as_built_fraunhofer.fraunhofer(tilted, fields, wl, PITCH_UM, SIZE, RAYS)  # so do the Fraunhofer PSFs
    flat = as_built_fraunhofer.fraunhofer(lens, fields, wl, PITCH_UM, SIZE, RAYS)
    assert abs(waves[0].max() - waves[1].max()) > 0.1 * waves.max()
    assert abs(flat[0].max() - flat[1].max()) < 1e-4 * flat.max()  # measured: 1.2e-6
    for k in range(2):
        dz = image_xy[k, 1] * np.tan(np.radians(tilt))
        last = lens.surfaces[-1]
        shifted = replace(lens, surfaces=(*lens.surfaces[:-1], replace(last, thickness=last.thickness + dz)))
        expected = _rms_radius_um(as_built.geometric(shifted, fields[k : k + 1], wl, PITCH_UM, SIZE, RAYS)[0])[0]
        assert abs(radius[k] - expected) < 0.01 * expected  # measured: 4e-5


def test_the_fraunhofer_psf_of_an_ideal_lens_peaks_as_its_closed_form():
    """An f = 40 mm ideal lens of radius a at infinity bends a ray at height h to tan θ = h/f without path
    difference; the peak is |∫ √(ρ dΩ/dA) dA|² / λ² with ρ = 1/(πa²) and dΩ/dA = f²/(h² + f²)²:
    (√ρ f π ln(1 + a²/f²))² / λ² — the same wherever the lens is decentred (m = 0)."""
    f, a, wl = 40.0, 5.0, 550.0
    peak = (
        (math.sqrt(1.0 / (math.pi * a * a)) * f * math.pi * math.log1p(a * a / (f * f))) ** 2 / (wl * 1e-6) ** 2 * 1e-6
    )
    for decentre in ([0.0, 0.0], [0.3, -0.2]):
        data = as_built_fraunhofer.field_psf(_ideal(decentre), (0.0, 0.0), wl, 1.0, 17, 128)
        assert abs(data.max() / peak - 1.0) < 0.005  # measured: 0.12 %, the rim's staircase


@pytest.mark.parametrize("name, field", [("solas-doublet", (0.0, 0.0)), ("cooke-triplet", (8.0, -12.0))])
def test_the_fraunhofer_psf_of_a_lens_placed_with_zero_breaks_is_the_symmetric_paths(name, field):
    """The ray sum over the entrance grid against the pupil function on its (α, β) grid (512 samples): two
    samplings that converge to one PSF (measured: 0.10 % and 0.37 % of the peak at 256 rays), in the same
    orientation (an oblique field would show a mirror)."""
    lens = Lens.load(name)
    wl = lens.primary_wavelength
    expected = fraunhofer(Pupils(lens, np.array([field]), np.array([wl])).sampled(512), 1.0, 48)[0]
    data = as_built_fraunhofer.field_psf(_zero_placed(lens), field, wl, 1.0, 48, 256)
    assert np.abs(data - expected).max() < 0.01 * expected.max()


def test_solas_mi_psf_of_a_lens_as_built_takes_the_numpy_tracer_s_paths(tmp_path, capsys):
    """`solas-mi psf` of the doublet with a tilted sensor, written as TOML: its geometric PSF is
    `psf.as_built`'s (normalised), the metadata says which path and that the paraxial data are about the nominal
    axis; the Fraunhofer path runs; a method without a path for the lens as built is refused by name."""
    from solas_mi.cli import main
    from solas_mi.imageio import read_exr
    from solas_mi.psf.as_built_methods import PATHS
    from solas_mi.psf.registry import METHODS

    doublet = Lens.load("solas-doublet")
    tilted = replace(doublet, name="tilted-doublet", image_placement=Placement(tilt_x=0.5))
    tilted.save(tmp_path / "tilted.toml")
    lens, wl = Lens.load(str(tmp_path / "tilted.toml")), doublet.primary_wavelength
    args = ["psf", str(tmp_path / "tilted.toml"), "--field-deg", "0,3", "--wavelengths-nm", f"{wl}"]
    args += ["--pitch-um", f"{PITCH_UM}", "--size", f"{SIZE}"]
    for method in PATHS:
        out = tmp_path / f"{method}.exr"
        assert (
            main([*args, "--psf-method", method, "--rays", f"{RAYS}", "--pupil-samples", f"{RAYS}", "-o", str(out)])
            == 0
        )
        channels, meta = read_exr(str(out))
        assert meta["path"] == PATHS[method] and "nominal axis" in meta["paraxial_axis"]
        data = next(iter(channels.values()))
        assert np.isfinite(data).all() and abs(data.sum() - 1.0) < 1e-6
    expected = as_built.geometric(lens, [[0.0, 3.0]], wl, PITCH_UM, SIZE, RAYS)[0][0]
    channels, _ = read_exr(str(tmp_path / "geometric.exr"))
    assert (
        np.abs(next(iter(channels.values())) - expected / expected.sum()).max() < 1e-6 * expected.max() / expected.sum()
    )
    refused = [m for m in METHODS if m not in PATHS]
    for method in refused:
        capsys.readouterr()
        assert main([*args, "--psf-method", method, "-o", str(tmp_path / "refused.exr")]) == 2
        assert f"PSF method {method!r} does not take it" in capsys.readouterr().err
    poly = [*args[:4], "--wavelengths-nm", "486.1,656.3", *args[6:], "-o", str(tmp_path / "poly.exr")]
    assert main(poly) == 2 and "takes one wavelength at a time" in capsys.readouterr().err
    assert main([*poly, "--psf-method", "geometric", "--rays", f"{RAYS}"]) == 0
    assert len(refused) >= 1 and not (tmp_path / "refused.exr").exists()
