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

import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .. import jsonio
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
    seconds: dict[str, float]  # run time (s) of the render (both seeds), the PSF grid, the ideal image, the convolution

    def annuli(self) -> list[dict[str, float]]:
        """Per automotive annulus (`metrics.annuli`, of the sensor's corner radius): its name, RMS(convolved
        − direct), RMS(ideal − direct) and the render noise, each relative to the whole render's mean."""
        from ..metrics.annuli import ANNULI, ANNULUS_NAMES, annulus_map

        h, w = self.direct.shape
        index, mean = annulus_map(h, w), float(self.direct.mean())
        bounds = (0.0, *ANNULI["automotive"])
        rows = []
        for i, name in enumerate(ANNULUS_NAMES):
            m = index == i
            rows.append({"annulus": name, "from": bounds[i], "to": bounds[i + 1],
                         "rms_error": float(np.sqrt(np.mean((self.convolved[m] - self.direct[m]) ** 2))) / mean,
                         "rms_ideal": float(np.sqrt(np.mean((self.ideal[m] - self.direct[m]) ** 2))) / mean})
        return rows


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


# many parameters: the two sides of one comparison, each with its own sampling: the render's (size, pitch, spp,
# wavelength) and the PSF grid's (nodes, PSF pitch and size, pupil samples, method)
def compare_fisheye(lens: Lens, env: np.ndarray, fov_deg: float, size: int, pitch_um: float, grid: tuple[int, int],
                    spp: int, wavelength_nm: float | None = None, psf_pitch_um: float | None = None, psf_size: int = 64,
                    pupil_samples: int = 128, method: str = "geometric") -> FisheyeComparison:
    """Render `env` (equidistant, ±fov_deg) through the fisheye onto size×size pixels of pitch_um at
    one wavelength, against its ideal sensor image degraded by a grid (rows, columns) of PSFs.

    The PSFs are geometric by default, like the render (rays, no diffraction), on psf_size² samples of
    psf_pitch_um (default: pitch_um / 8, a window of psf_size / 8 pixels). A Fraunhofer PSF's window
    must stay inside its period λ/Δα (`psf.fraunhofer.sampling_warnings`), which at 128 pupil
    samples is about 0.2 mm for this lens: wider windows fold copies of the PSF in, blurring more than
    the lens does."""
    from ..render.image import render_image

    if lens.field_type.pinhole:
        raise SolasError(f"lens {lens.name} has tangent fields; the fisheye comparison needs a lens of polar fields")
    w = lens.primary_wavelength if wavelength_nm is None else lens.check_wavelength(wavelength_nm)
    seconds: dict[str, float] = {}

    def timed(name, fn, *args, **kwargs):
        start = time.perf_counter()
        value = fn(*args, **kwargs)
        seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - start
        return value

    runs = [timed("render", render_image, lens, env, sensor=(size, size), pitch_um=pitch_um, spp=spp,
                  response=f"mono:{w!r}", fov_deg=fov_deg, fresnel="off", mapping="equidistant",
                  variant="llvm_ad_spectral", seed=seed).image[..., 0] for seed in (0, 1)]
    direct = 0.5 * (runs[0] + runs[1])
    sensor_mm = (size * pitch_um * 1e-3,) * 2
    psf_pitch = pitch_um / 8 if psf_pitch_um is None else psf_pitch_um
    g = timed("psf grid", psf_grid, lens, grid=grid, wavelengths_nm=[w], pitch_um=psf_pitch, size=psf_size,
              pupil_samples=pupil_samples, method=method, layout="sensor", sensor_mm=sensor_mm)
    ideal = timed("ideal image", ideal_sensor_image, lens, env, fov_deg, size, pitch_um, w)
    convolved = timed("convolution", degrade, ideal, g, dtype=np.float64)
    mean = float(direct.mean())
    noise = float(np.sqrt(np.mean((runs[0] - runs[1]) ** 2)) / 2.0) / mean  # of the two-seed mean
    return FisheyeComparison(direct, convolved, ideal, float(np.sqrt(np.mean((convolved - direct) ** 2))) / mean, noise,
                             seconds)


def default_pitch_um(lens: Lens, size: int) -> float:
    """The pixel pitch (µm) at which a size×size sensor's corners reach the lens's field: its
    half-diagonal is the real chief ray's image height at field_deg (`optics.pupil.chief_rays`)."""
    from ..optics.pupil import chief_rays

    field = np.array([[0.0, lens.field_deg]])
    height = abs(float(chief_rays(lens, field, np.array([lens.primary_wavelength])).image_xy[0, 1]))
    return 1e3 * 2.0 * height / (size * np.sqrt(2.0))


def defocused(lens: Lens, defocus_mm: float) -> Lens:
    """`lens` with its image plane `defocus_mm` farther from the last surface (negative: nearer)."""
    last = lens.surfaces[-1]
    if not (np.isfinite(defocus_mm) and last.thickness + defocus_mm > 0):
        raise SolasError(f"defocus {defocus_mm:g} mm must be finite and leave the image plane behind the last "
                         f"surface (its distance is {last.thickness:g} mm)")
    return replace(lens, surfaces=lens.surfaces[:-1] + (replace(last, thickness=last.thickness + defocus_mm),))


def crossval_fisheye(lens: Lens, env: np.ndarray, out: str | Path, fov_deg: float, size: int = 64,
                     pitch_um: float | None = None, grid: tuple[int, int] = (5, 5), spp: int = 256,
                     defocus_mm: float = 0.0, log=print) -> FisheyeComparison:
    """`solas-mi crossval` for a lens of polar fields: `compare_fisheye` of the equidistant environment
    `env` (H×W, ±fov_deg across its width) on a size×size sensor (pitch: `default_pitch_um` unless
    given), with the film `defocus_mm` behind the image plane (both engines), written to `out`:
    direct.exr, convolved.exr, ideal.exr, error.exr ((convolved − direct) / mean(direct)) and
    error.png, table.md and crossval.json (settings, errors per annulus, run times). In focus a
    fisheye's PSFs are far smaller than pixels that span its image circle; a defocus of a few mm
    spreads them over pixels, so that the comparison tests the PSFs and not only the mapping."""
    from ..imageio import write_exr, write_text
    from .crossval import heat_png

    pitch = default_pitch_um(lens, size) if pitch_um is None else pitch_um
    lens = defocused(lens, defocus_mm) if defocus_mm else lens
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    log(f"crossval: fisheye {lens.name}, {size}x{size} px of {pitch:.1f} um, environment ±{fov_deg:g} deg "
        f"(equidistant), PSF grid {grid[0]}x{grid[1]} on the sensor, defocus {defocus_mm:g} mm, render {spp} spp "
        "x 2 seeds")
    r = compare_fisheye(lens, env, fov_deg, size, pitch, grid, spp)
    meta = {"lens": lens.name, "lens_hash": lens.hash, "fov_deg": fov_deg, "mapping": "equidistant",
            "defocus_mm": defocus_mm, "sensor_px": size, "pitch_um": pitch, "grid": list(grid), "spp_per_seed": spp, "seeds": 2,
            "wavelength_nm": lens.primary_wavelength, "rms_error": r.rms_error, "rms_noise": r.rms_noise,
            "rms_error_denoised": float(np.sqrt(max(r.rms_error ** 2 - r.rms_noise ** 2, 0.0))),
            "rms_ideal": float(np.sqrt(np.mean((r.ideal - r.direct) ** 2)) / r.direct.mean()),
            "mean_ratio": float(r.convolved.mean() / r.direct.mean()), "annuli": r.annuli(), "seconds": r.seconds}
    for name, image in (("direct", r.direct), ("convolved", r.convolved), ("ideal", r.ideal)):
        write_exr(out_dir / f"{name}.exr", {"Y": image.astype(np.float32)}, meta)
    rel = (r.convolved - r.direct) / r.direct.mean()
    write_exr(out_dir / "error.exr", {"Y": rel.astype(np.float32)}, dict(meta, values="(convolved - direct) / mean"))
    heat_png(out_dir / "error.png", np.abs(rel), f"{lens.name}: |convolved − direct| / mean(direct)")
    write_text(out_dir / "table.md", fisheye_markdown(meta))
    write_text(out_dir / "crossval.json", jsonio.dumps(meta, indent=1))
    return r


def fisheye_markdown(meta: dict) -> str:
    """The fisheye cross-validation's table: errors relative to the render's mean, whole and per annulus."""
    lines = [f"Fisheye cross-validation of {meta['lens']}: {meta['sensor_px']}x{meta['sensor_px']} px of "
             f"{meta['pitch_um']:.1f} um, film {meta['defocus_mm']:g} mm behind the image plane, PSF grid "
             f"{meta['grid'][0]}x{meta['grid'][1]} on the sensor, render "
             f"{meta['spp_per_seed']} spp x 2 seeds, {meta['wavelength_nm']:g} nm. Errors are RMS differences "
             "relative to the render's mean.", "",
             "| region | convolution vs render | ideal (no blur) vs render |", "|---|---|---|",
             f"| whole image | {100 * meta['rms_error']:.2f} % | {100 * meta['rms_ideal']:.2f} % |"]
    lines += [f"| {a['annulus']} ({a['from']:g}–{a['to']:g}) | {100 * a['rms_error']:.2f} % | "
              f"{100 * a['rms_ideal']:.2f} % |" for a in meta["annuli"]]
    s = meta["seconds"]
    lines += ["", f"Render noise (two-seed mean): {100 * meta['rms_noise']:.2f} %; without it (in quadrature) the "
              f"convolution is {100 * meta['rms_error_denoised']:.2f} % from the render; means agree to "
              f"{100 * abs(meta['mean_ratio'] - 1):.2f} %. Run time: render {s['render']:.1f} s, PSF grid "
              f"{s['psf grid']:.1f} s, ideal image {s['ideal image']:.1f} s, convolution {s['convolution']:.2f} s.", ""]
    return "\n".join(lines)
