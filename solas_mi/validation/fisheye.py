"""A fisheye image two ways: rendered directly through the lens geometry, and as its ideal sensor
image degraded by the lens's own sensor-space PSF grid (`psf-grid --layout sensor`).

The object is an environment image at infinity in a wide mapping (`plugins/image_object.py`, e.g.
equidistant). The ideal sensor image is what a lens with the real chief-ray mapping and no blur
would record: each pixel averages the environment over sub-pixel points, each point looking up the
field whose real chief ray lands there (`psf.sensor.fields_for_points`), times the lossless lens's
image irradiance at that height over the paraxial camera's (`optics.illumination.irradiance`, which
carries the pupil's shrinking and tilting, vignetting and the mapping's change of scale). The PSF grid
("sum" normalised) then only blurs it. Both images are irradiance in the paraxial camera's units, the
units `lens_sensor` uses for a lens of polar fields, so they compare pixel for pixel. Lengths in mm,
pitch in µm, angles in degrees.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..convolution.methods import degrade
from ..errors import SolasError
from ..optics.illumination import ideal_irradiance, irradiance
from ..optics.lens import Lens
from ..optics.paraxial import paraxial
from ..psf.grid import psf_grid
from ..psf.sensor import fields_for_points

SUBPIXELS = 1  # points per pixel axis: the convolution takes input pixels as piecewise-constant texels
RADII = 48  # image heights at which the irradiance is traced (then interpolated)


@dataclass
class FisheyeComparison:
    direct: np.ndarray  # (H, W) the render
    convolved: np.ndarray  # (H, W) the ideal sensor image through the PSF grid
    ideal: np.ndarray  # (H, W) the ideal sensor image
    rms_error: float  # RMS(convolved − direct) / mean(direct)
    rms_noise: float  # RMS render noise / mean(direct), from two seeds


def environment_lookup(env: np.ndarray, fov_deg: float, fields_deg: np.ndarray) -> np.ndarray:
    """Texels of an equidistant environment image (width spanning ±fov_deg) at polar fields (…, 2):
    nearest texel, the image object's model; 0 outside."""
    h, w = env.shape
    pitch = 2.0 * fov_deg / w
    col = np.floor(fields_deg[..., 0] / pitch + w / 2).astype(int)
    row = np.floor(h / 2 - fields_deg[..., 1] / pitch).astype(int)
    inside = (col >= 0) & (col < w) & (row >= 0) & (row < h)
    return np.where(inside, env[np.clip(row, 0, h - 1), np.clip(col, 0, w - 1)], 0.0)


def ideal_sensor_image(lens: Lens, env: np.ndarray, fov_deg: float, size: int, pitch_um: float,
                       wavelength_nm: float) -> np.ndarray:
    """The ideal sensor image (size×size pixels of pitch_um) of an equidistant environment image."""
    pitch = pitch_um * 1e-3
    sub = (np.arange(size * SUBPIXELS) + 0.5) / SUBPIXELS - size / 2  # pixel units, +x right
    x, y = np.meshgrid(sub * pitch, -sub * pitch)
    points = np.stack([x, y], axis=-1)
    fields = fields_for_points(lens, points, wavelength_nm)
    radiance = environment_lookup(env, fov_deg, fields)
    r = np.hypot(x, y)
    radii = np.linspace(0.0, r.max(), RADII)
    e = irradiance(lens, np.stack([np.zeros(RADII), radii], axis=-1), wavelength_nm, samples=128)
    scale = np.interp(r, radii, e) / ideal_irradiance(lens, paraxial(lens).efl_mm, wavelength_nm)
    value = radiance * scale
    return value.reshape(size, SUBPIXELS, size, SUBPIXELS).mean(axis=(1, 3))


def compare_fisheye(lens: Lens, env: np.ndarray, fov_deg: float, size: int, pitch_um: float, grid: tuple[int, int],
                    spp: int, wavelength_nm: float | None = None, psf_pitch_um: float = 10.0, psf_size: int = 64,
                    pupil_samples: int = 128) -> FisheyeComparison:
    """Render `env` (equidistant, ±fov_deg) through the fisheye onto size×size pixels of pitch_um at
    one wavelength, against its ideal sensor image degraded by a grid (rows, columns) of PSFs."""
    from ..render.image import render_image

    if not lens.polar_field:
        raise SolasError(f"lens {lens.name} has tangent fields; the fisheye comparison needs a lens of polar fields")
    w = lens.primary_wavelength if wavelength_nm is None else lens.check_wavelength(wavelength_nm)
    runs = [render_image(lens, env, (size, size), pitch_um, spp=spp, response=f"mono:{w!r}", fov_deg=fov_deg,
                         fresnel="off", mapping="equidistant", variant="llvm_ad_spectral", seed=seed).image[..., 0]
            for seed in (0, 1)]
    direct = 0.5 * (runs[0] + runs[1])
    sensor_mm = (size * pitch_um * 1e-3,) * 2
    g = psf_grid(lens, grid, [w], pitch_um=psf_pitch_um, size=psf_size, pupil_samples=pupil_samples,
                 layout="sensor", sensor_mm=sensor_mm)
    ideal = ideal_sensor_image(lens, env, fov_deg, size, pitch_um, w)
    convolved = degrade(ideal, g, dtype=np.float64)
    mean = float(direct.mean())
    noise = float(np.sqrt(np.mean((runs[0] - runs[1]) ** 2)) / 2.0) / mean  # of the two-seed mean
    return FisheyeComparison(direct, convolved, ideal, float(np.sqrt(np.mean((convolved - direct) ** 2))) / mean, noise)
