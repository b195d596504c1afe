"""A lens scaled to the frame camera's focal length (`optics.scale`): the paraxial scaling laws (EFL and
pupils scale, the f-number does not, geometric blur scales in mm, so it is the same in pixels of the
camera's focal length) and the batch option that asks for it."""

import math
from dataclasses import replace

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.convolution.methods import degrade
from solas_mi.optics.frame import FrameCamera
from solas_mi.optics.paraxial import paraxial
from solas_mi.optics.sag import sag
from solas_mi.optics.scale import scaled, scaled_to_focal
from solas_mi.optics.spot import spot
from solas_mi.psf.grid import psf_grid


@pytest.mark.parametrize("factor", [0.05, 0.5, 3.0])
def test_paraxial_scaling_laws(doublet, factor):
    a, b = paraxial(doublet), paraxial(scaled(doublet, factor))
    for name in ("efl_mm", "bfd_mm", "entrance_pupil_diameter_mm", "exit_pupil_z_mm", "image_z_mm"):
        assert getattr(b, name) == pytest.approx(factor * getattr(a, name), rel=1e-9), name
    assert b.f_number == pytest.approx(a.f_number, rel=1e-9)
    assert b.working_f_number == pytest.approx(a.working_f_number, rel=1e-9)
    sa, sb = spot(doublet, (0.0, 1.5), 531.0), spot(scaled(doublet, factor), (0.0, 1.5), 531.0)
    rms = [math.sqrt(np.mean(s.x_um**2 + s.y_um**2)) for s in (sa, sb)]
    assert rms[1] == pytest.approx(factor * rms[0], rel=1e-6)  # geometric blur scales with the lens


def test_every_sag_scales_with_the_lens(doublet):
    s = replace(doublet.surfaces[0], conic=-0.4, aspheric=(2e-6, -3e-9, 1e-12), qbfs=(0.01, -0.002), norm_radius=6.0)
    lens = replace(doublet, surfaces=(s, *doublet.surfaces[1:]))
    big = scaled(lens, 2.5).surfaces[0]
    r = np.linspace(0.0, s.semi_diameter, 9)
    assert np.allclose(sag((2.5 * r) ** 2, **big.shape), 2.5 * sag(r**2, **s.shape), rtol=1e-12, atol=1e-15)
    assert big.diameter == 2.5 * s.diameter and scaled(lens, 2.5).hash != lens.hash


def test_a_lens_scaled_to_the_camera_blurs_the_same_pixels_geometrically(doublet):
    """The camera: fx = 40000 px of 0.5 µm (EFL 20 mm). The doublet (EFL ≈ 100 mm) scaled by ≈ 0.2 gives
    the geometric blur in pixels that the unscaled lens gives on pixels of EFL/fx; the metadata says so."""
    lens, info = scaled_to_focal(doublet, 40000.0, 0.5)
    # the image scale on the doublet's image plane, 0.46 mm inside the paraxial focus: 98.80 mm, EFL 99.95 mm
    assert info["focal_mm"][1] == pytest.approx(20.0, rel=1e-9) and info["factor"] == pytest.approx(
        20.0 / 98.80, rel=1e-4
    )
    assert info["efl_mm"][1] == pytest.approx(info["factor"] * paraxial(doublet).efl_mm, rel=1e-9)
    assert info["f_number"][1] == pytest.approx(info["f_number"][0], rel=1e-9)
    frame = FrameCamera("pinhole", intrinsics=(40000.0, 40000.0, 80.0, 60.0))
    point = np.zeros((121, 161))
    point[60, 80] = 1.0
    widths, pitches = [], []
    for lns, pitch in ((doublet, 1.0), (lens, info["factor"])):  # the same PSF samples, scaled
        grid = psf_grid(
            lns,
            grid=(3, 3),
            wavelengths_nm=[531.0],
            size=64,
            pitch_um=pitch,
            method="geometric",
            rays=64,
            field_range_deg=(0.2, 0.2),
        )
        meta = {}
        out = degrade(point, grid, frame=frame, meta=meta)
        pitches.append(meta["camera"]["pitch_um"])
        c = np.arange(161) - 80
        widths.append(math.sqrt((out.sum(axis=0) * c**2).sum()))
    assert widths[0] > 2 and widths[1] == pytest.approx(widths[0], rel=1e-3)
    # the scaled lens's pixels are the camera's; the unscaled lens's are its image scale / fx, 5x larger
    assert pitches[1] == pytest.approx(0.5, rel=1e-4) and pitches[0] == pytest.approx(0.5 / info["factor"], rel=1e-3)
    with pytest.raises(SolasError, match="pixel pitch"):
        scaled_to_focal(doublet, 4000.0, 0.0)
    with pytest.raises(SolasError, match="scale factor"):
        scaled(doublet, -1.0)


def test_diffraction_does_not_scale_with_the_lens(doublet):
    """Scaled down until diffraction rules (EFL 1 and 2 mm), the doublet's axial PSF is the same in µm: the
    Airy pattern of its f-number (first dark ring at 1.22 λN holding 84 % of the light; 88 % here with
    the samples' own width), so in a camera's pixels of p µm it spans 1.22 λN / p, whatever the scale."""
    from solas_mi.psf.methods import psf

    x = (np.arange(128) - 64) * 0.25
    r = np.hypot(x[None], x[:, None])
    shapes = []
    for factor in (0.01, 0.02):
        lens = scaled(doublet, factor)
        a = np.asarray(psf(lens, (0.0, 0.0), 531.0, pitch_um=0.25, size=128).data, dtype=np.float64)
        ring = 1.22 * 0.531 * paraxial(lens).working_f_number
        assert a[r <= ring].sum() / a.sum() == pytest.approx(0.86, abs=0.03)
        shapes.append(a / a.sum())
    assert np.abs(shapes[0] - shapes[1]).max() < 0.02 * shapes[0].max()
