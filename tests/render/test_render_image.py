"""An input image through the lens geometry (`render.image`) against the Float64 tracer: radiometry
and image positions."""

import math

import numpy as np
import pytest

from solas_mi import SolasError
from solas_mi.optics.camera import camera_for
from solas_mi.optics.illumination import ideal_irradiance, irradiance, relative_illumination
from solas_mi.optics.pupil import chief_rays
from solas_mi.psf.geometric import entrance_grid_hits
from solas_mi.render.image import render_image

RAYS = 256


def test_white_object_relative_illumination(doublet):
    """A uniform white object renders the tracer's irradiance (image side, exact) and its
    transmitted-energy view (pupil transmission × cos³θ × J(0)/J) across the field within 1 %."""
    camera = camera_for(doublet, (6, 8))
    r = render_image(
        doublet,
        np.ones((6, 8)),
        sensor=(6, 8),
        spp=1024,
        response="mono:531",
        fresnel="off",
        variant="llvm_ad_spectral",
    )
    x, y = np.meshgrid(camera.pixel_x_mm(), camera.pixel_y_mm())
    pts = np.stack([x.ravel(), y.ravel()], -1)
    exact = irradiance(doublet, pts, 531.0, samples=256) / ideal_irradiance(doublet, camera.focal_mm)
    assert np.max(np.abs(r.image[..., 0].ravel() / exact - 1)) < 0.003
    axis = irradiance(doublet, np.zeros((1, 2)), 531.0, samples=256)[0] / ideal_irradiance(doublet, camera.focal_mm)
    # fields whose chief rays land at the pixel centres (rectilinear guess, refined once)
    guess = np.degrees(np.arctan(pts / camera.focal_mm))
    landed = chief_rays(doublet, guess, np.full(len(guess), 531.0)).image_xy
    fields = np.degrees(np.arctan(np.tan(np.radians(guess)) * pts / np.where(landed == 0, 1, landed)))
    ri = relative_illumination(doublet, fields, 531.0, pupil_samples=64)
    assert np.max(np.abs(r.image[..., 0].ravel() / axis / ri - 1)) < 0.01
    assert r.image.min() < 0.99 * r.image.max()  # the corners are darker: the test can tell


def test_white_object_never_exceeds_the_lens_transmission(doublet):
    lossless = render_image(
        doublet, np.ones((6, 8)), sensor=(6, 8), spp=192, response="lines", fresnel="off", variant="llvm_ad_spectral"
    ).image
    real = render_image(
        doublet,
        np.ones((6, 8)),
        sensor=(6, 8),
        spp=192,
        response="lines",
        fresnel="transmit",
        variant="llvm_ad_spectral",
    ).image
    camera = camera_for(doublet, (6, 8))
    # a lossless lens gives at most its on-axis irradiance (in the ideal camera's unit: (f'/f)² × sin²u'/tan²u')
    axis = irradiance(doublet, np.zeros((1, 2)), 531.0, samples=256)[0] / ideal_irradiance(doublet, camera.focal_mm)
    assert lossless.max() <= axis * (1 + 2e-3)
    assert np.all(real < lossless) and 0.85 < real.mean() / lossless.mean() < 0.95  # two air-glass surfaces + cement


def test_dot_lands_where_the_tracer_says(doublet):
    """A bright texel at field (+2°, 0) seen through a ±2.5° image: its rendered centroid is the
    tracer's (chief ray + geometric PSF centroid) within 0.5 µm."""
    fov = 2.5
    camera = camera_for(doublet, (24, 720), fov_deg=fov)
    image = np.zeros((24, 720))
    t = math.tan(math.radians(fov)) / 360
    col = int(math.floor(math.tan(math.radians(2.0)) / t + 360))
    image[11:13, col] = 1.0  # two texels straddling y = 0
    field = np.degrees(np.arctan((col + 0.5 - 360) * t))
    r = render_image(
        doublet,
        image,
        sensor=(24, 720),
        fov_deg=fov,
        spp=64,
        response="mono:531",
        fresnel="off",
        variant="llvm_ad_spectral",
    )
    img = r.image[..., 0]
    x, y = np.meshgrid(camera.pixel_x_mm(), camera.pixel_y_mm())
    cx = float((img * x).sum() / img.sum()) * 1e3
    f, w = np.array([[field, 0.0]]), np.array([531.0])
    chief = chief_rays(doublet, f, w)
    dx, _, power = entrance_grid_hits(doublet, f, w, RAYS, chief)[0]  # the tracer's rays, µm from the chief ray
    assert cx == pytest.approx(chief.image_xy[0, 0] * 1e3 + np.average(dx, weights=power), abs=0.5)
    assert abs(float((img * y).sum() / img.sum()) * 1e3) < 0.5


def test_bad_inputs(doublet):
    with pytest.raises(SolasError, match="camera response"):
        render_image(doublet, np.ones((6, 8)), sensor=(6, 8), spp=4, response="infrared", variant="llvm_ad_spectral")
    with pytest.raises(SolasError, match="boundary"):
        render_image(doublet, np.ones((6, 8)), sensor=(6, 8), spp=4, boundary="wrap", variant="llvm_ad_spectral")
    # a user's value is never replaced: 0 rings was silently 32
    with pytest.raises(SolasError, match="cap rings 0 must be an integer from 2"):
        render_image(doublet, np.ones((6, 8)), sensor=(6, 8), spp=4, rings=0, variant="llvm_ad_spectral")
    with pytest.raises(SolasError, match="focus distance sets the lens camera of a scene file"):
        render_image(doublet, np.ones((6, 8)), sensor=(6, 8), spp=4, focus_distance=500.0)
