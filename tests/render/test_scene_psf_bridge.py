"""Geometric PSFs traced through the scene's meshes and plugins (`validation.scene_psf`) against the
Float64 tracer: the lens as Mitsuba geometry is the tracer's lens."""

import math

import numpy as np
import pytest

from solas_mi.imageio import write_exr
from solas_mi.optics.camera import camera_for
from solas_mi.optics.pupil import chief_rays
from solas_mi.psf.geometric import entrance_grid_hits
from solas_mi.render.mitsuba import load_scene
from solas_mi.render.scene import write_scene
from solas_mi.validation.scene_psf import scene_psf

RAYS = 256


@pytest.fixture(scope="module")
def scene(doublet, tmp_path_factory, in_variant):
    """The doublet's scene with the tracer's radiometry (no Fresnel losses)."""
    out = tmp_path_factory.mktemp("scene")
    write_exr(out / "white.exr", {"Y": np.ones((12, 16), dtype=np.float32)})
    with in_variant("llvm_ad_spectral"):
        return load_scene(
            write_scene(doublet, out, "white.exr", camera_for(doublet, (12, 16)), fresnel="off"), "llvm_ad_spectral"
        )


def tracer_spot(lens, field, wavelength):
    """Centroid (µm from the chief ray) and RMS radius of the tracer's rays on the same entrance grid."""
    f, w = np.array([field], dtype=float), np.array([wavelength], dtype=float)
    dx, dy, p = entrance_grid_hits(lens, f, w, RAYS, chief_rays(lens, f, w))[0]
    cx, cy = np.average(dx, weights=p), np.average(dy, weights=p)
    return np.array([cx, cy]), math.sqrt(np.average((dx - cx) ** 2 + (dy - cy) ** 2, weights=p))


@pytest.mark.slow
@pytest.mark.parametrize("wavelength", [486.0, 531.0, 656.0])
@pytest.mark.parametrize("field", [(0.0, 0.0), (0.0, 2.0), (0.0, -2.0)])
def test_scene_psf_matches_tracer(doublet, scene, field, wavelength, variant_llvm_ad_spectral):
    p = scene_psf(scene, doublet, field, wavelength, rays=RAYS)
    centroid, rms = tracer_spot(doublet, field, wavelength)
    assert np.hypot(*(np.array(p.meta["centroid_um"]) - centroid)) < 0.5
    assert p.meta["rms_radius_um"] == pytest.approx(rms, rel=0.02)
    assert p.meta["transmission"] > 0.5 and p.data.sum() == pytest.approx(1.0, rel=1e-6)


def test_lateral_colour_matches_tracer(doublet, scene, variant_llvm_ad_spectral):
    """486 vs 656 nm centroid shift at +2°, the same through the scene and the tracer. (The chief rays
    are 3.1 µm apart; coma moves the 486 nm centroid up more, leaving 0.9 µm.)"""
    field = (0.0, 2.0)
    shift = {}
    for source in ("scene", "tracer"):
        pos = []
        for w in (486.0, 656.0):
            chief = chief_rays(doublet, np.array([field]), np.array([w])).image_xy[0] * 1e3
            c = (
                np.array(scene_psf(scene, doublet, field, w, rays=RAYS).meta["centroid_um"])
                if source == "scene"
                else tracer_spot(doublet, field, w)[0]
            )
            pos.append(chief + c)
        shift[source] = pos[0] - pos[1]
    assert 0.5 < abs(shift["tracer"][1]) < 5.0
    assert np.hypot(*(shift["scene"] - shift["tracer"])) < 0.2
