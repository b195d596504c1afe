"""The high-dynamic-range stray-light PSF of a point source (`stray_psf`): the direct image (geometric over
the window, its core the Fraunhofer PSF where that is sound, its diffraction wings beyond the core,
`diffraction_wings`) plus every ghost of `stray_light.ghosts`, its rays binned and smoothed over their
spacing, a focused ghost blurred by its Airy pattern; in fractions of the direct image's energy per pixel,
written as OpenEXR and a log-scale PNG (`write`).
"""

from __future__ import annotations

import math

import numpy as np

from ..optics.lens import Lens
from .geometric import bin_hits
from .stray_light import GhostReport, working_f_number

DIRECT_SIZES = (33, 17, 9)  # pixels per side of the direct image's Fraunhofer core, the widest sound one
MAX_FINE = 1024  # the finest direct PSF's pixels per side (its pitch resolves the diffraction pattern)
GEOMETRIC_RAYS = 512  # rays per side of the direct image's geometric PSF over the whole window
LOG_DECADES = 8  # the log-scale PNG shows 1e-8 of the peak to the peak


def stray_psf(
    lens: Lens, report: GhostReport, pitch_um: float, size: int, pupil_samples: int = 256
) -> tuple[np.ndarray, tuple[float, float], list[str]]:
    """The HDR stray-light PSF (size × size, row 0 the top) in fractions of the direct image's energy per
    pixel: the direct image (geometric over the window, its central pixels the Fraunhofer PSF's where that
    is sound, `_diffraction_core`) plus every ghost's rays binned and smoothed over their spacing (`smooth`),
    a focused one blurred by its Airy pattern (`airy_blur`), centred on the first wavelength's chief ray;
    also that centre (mm) and a note where the direct image's core stays geometric."""
    from .base import check_grid
    from .methods import psf

    check_grid(pitch_um, size)
    field, wavelengths = report.field_deg, list(report.wavelengths_nm)
    geometric = psf(
        lens,
        field,
        wavelengths,
        pitch_um=pitch_um,
        size=size,
        normalization="sum",
        method="geometric",
        rays=GEOMETRIC_RAYS,
    )
    cx, cy = geometric.chief_ray_mm
    total = geometric.data * float(geometric.meta["energy_in_grid"])
    core, notes = _diffraction_core(lens, field, wavelengths, pitch_um, size, pupil_samples)
    if core is not None:
        lo = size // 2 - len(core) // 2
        total[lo : lo + len(core), lo : lo + len(core)] = core
        total += diffraction_wings(core, size)
    ghosts = {(g.surfaces[0] - 1, g.surfaces[1] - 1): g for g in report.ghosts}
    for path, (x, y, w) in report.hits.items():
        if len(w) > 1:
            binned, _ = bin_hits([((x - cx) * 1e3, (y - cy) * 1e3, w)], pitch_um, size)
            image = smooth(binned[0] * pitch_um**2, ray_spacing_um(x, y, w) / pitch_um)
            total += airy_blur(image, ghosts[path].airy_mm * 1e3 / pitch_um) if ghosts[path].focused else image
    return total, (cx, cy), notes


WING_RING = 3  # pixels: the core's outermost ring that scales the diffraction wings to it


def diffraction_wings(core: np.ndarray, size: int) -> np.ndarray:
    """The direct image's diffraction wings beyond its Fraunhofer core (zero inside it), size × size: the far
    field of a pupil's edge, whose ring-averaged irradiance falls as 1/r³ (the Airy pattern's mean (λN)/(π³ r³)
    per unit area, r from the centre pixel), scaled to the core's own mean over its outermost `WING_RING`
    pixels (so an aberrated or polygonal pupil's level is its own, and the PSF has no step at the core's edge).
    The wings are round: an iris's spikes beyond the core are not modelled."""
    half = len(core) // 2
    rows, cols = np.indices((size, size)) - size // 2
    r = np.hypot(rows, cols)
    model = 1.0 / np.maximum(r, 0.5) ** 3
    inside = (np.abs(rows) <= half) & (np.abs(cols) <= half)
    ring = inside & (r > half - WING_RING) & (r <= half)
    if not ring.any() or half < 2 * WING_RING:
        return np.zeros((size, size))
    core_ring = core[(rows[ring] + half), (cols[ring] + half)]
    scale = float(core_ring.mean() / model[ring].mean())
    return np.where(inside, 0.0, scale * model)


AIRY_REACH = 4.0  # the Airy kernel's half width, in Airy radii (it holds 98 % of the pattern's light)
AIRY_OVERSAMPLE = 5  # samples per pixel side of the Airy kernel, summed into the pixel


def airy_kernel(radius_px: float) -> np.ndarray:
    """The Airy pattern (2 J1(v)/v)² of first dark ring `radius_px` pixels, integrated over each pixel (from
    `AIRY_OVERSAMPLE`² samples), out to `AIRY_REACH` radii, summing to 1."""
    from scipy.special import j1

    half = max(1, math.ceil(AIRY_REACH * radius_px))
    n = 2 * half + 1
    fine = (np.arange(n * AIRY_OVERSAMPLE) + 0.5) / AIRY_OVERSAMPLE - n / 2.0
    v = 3.8317059702075125 * np.hypot(*np.meshgrid(fine, fine)) / radius_px  # J1's first zero at the radius
    pattern = np.where(v > 0, (2.0 * j1(v) / np.where(v > 0, v, 1.0)) ** 2, 1.0)
    kernel = pattern.reshape(n, AIRY_OVERSAMPLE, n, AIRY_OVERSAMPLE).sum(axis=(1, 3))
    return kernel / kernel.sum()


def airy_blur(image: np.ndarray, radius_px: float) -> np.ndarray:
    """`image` blurred by the Airy pattern of first dark ring `radius_px` pixels (a focused ghost's
    diffraction); under half a pixel, unchanged. Light blurred out of the window is lost, as it is."""
    if not radius_px >= 0.5:
        return image
    from scipy.signal import fftconvolve

    kernel = airy_kernel(min(radius_px, image.shape[0] / AIRY_REACH))
    return np.maximum(fftconvolve(image, kernel, mode="same"), 0.0)


def _diffraction_core(lens: Lens, field, wavelengths: list, pitch_um: float, size: int, pupil_samples: int):
    """The direct image's core by diffraction: the Fraunhofer PSF at a pitch that resolves it (λ N / 2 at the
    shortest wavelength) summed into the pixels, on the widest of `DIRECT_SIZES` windows where it is sound
    (no warning); (core, []) or (None, [why the rays' core stays])."""
    from .methods import psf

    fine_pitch = 0.5 * min(wavelengths) * 1e-3 * working_f_number(lens)
    odd_size = size - 1 + size % 2  # the widest odd window inside the grid (its centre pixel is the grid's)
    for inner in [min(odd_size, n) for n in DIRECT_SIZES]:
        fine = max(1, min(math.ceil(pitch_um / fine_pitch), MAX_FINE // inner)) | 1
        direct = psf(
            lens,
            field,
            wavelengths,
            pitch_um=pitch_um / fine,
            size=inner * fine,
            normalization="sum",
            pupil_samples=pupil_samples,
        )
        if not direct.meta["warnings"]:
            core = direct.data.reshape(inner, fine, inner, fine).sum(axis=(1, 3))
            return core * float(direct.meta["energy_in_grid"]), []
    # a PSF warning reads "what is wrong; the remedy by `psf`'s options", which `ghosts` does not take: the first part
    why = direct.meta["warnings"][0].split("; ")[0]
    return None, [
        f"the direct image is geometric ({GEOMETRIC_RAYS} x {GEOMETRIC_RAYS} rays): its Fraunhofer core "
        f"is not sound here ({why})"
    ]


def ray_spacing_um(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> float:
    """The mean distance (µm) between a ghost's rays on the image plane: √(π (2 σ)² / rays), σ its RMS radius."""
    cx, cy = np.average(x, weights=w), np.average(y, weights=w)
    rms = math.sqrt(np.average((x - cx) ** 2 + (y - cy) ** 2, weights=w))
    return 1e3 * math.sqrt(math.pi * (2.0 * rms) ** 2 / len(w))


def smooth(image: np.ndarray, sigma_px: float) -> np.ndarray:
    """`image` blurred by a normalised Gaussian of `sigma_px` pixels (a ray stands for its neighbourhood;
    under half a pixel: unchanged), edges zero-padded (light blurred out of the window is lost, as it is)."""
    if sigma_px < 0.5:
        return image
    half = int(min(3.0 * sigma_px, (image.shape[0] - 1) // 2))  # "same" keeps the image's length
    kernel = np.exp(-0.5 * (np.arange(-half, half + 1) / sigma_px) ** 2)
    kernel /= kernel.sum()
    rows = np.apply_along_axis(np.convolve, 1, image, kernel, "same")
    return np.apply_along_axis(np.convolve, 0, rows, kernel, "same")


def write(report: GhostReport, data: np.ndarray, centre_mm: tuple[float, float], pitch_um: float, exr, png) -> None:
    """The HDR PSF as OpenEXR (channel Y, the ghost table in its metadata) and a log-scale PNG (black:
    `LOG_DECADES` decades below the peak), whole or not at all."""
    from ..imageio import write_exr, write_png
    from ..outputs import written_together

    meta = {
        "field_deg": list(report.field_deg),
        "wavelengths_nm": list(report.wavelengths_nm),
        "pitch_um": pitch_um,
        "size": len(data),
        "chief_ray_origin_mm": list(centre_mm),
        "unit": "fraction of the direct image's energy per pixel",
        "ghosts": [
            {
                "surfaces": list(g.surfaces),
                "energy": g.energy,
                "centroid_mm": list(g.centroid_mm),
                "rms_mm": g.rms_mm,
                "focus_mm": g.focus_mm,
                "focused": g.focused,
                "airy_mm": g.airy_mm if math.isfinite(g.airy_mm) else None,  # None: a parallel beam
            }
            for g in report.ghosts
            if g.energy > 0
        ],
        "irradiance": "ghosts: binned rays, a focused one blurred by its Airy pattern; the direct image: rays, "
        "its core Fraunhofer's where sound",
    }
    shown = np.log10(np.maximum(data / max(float(data.max()), 1e-300), 10.0**-LOG_DECADES)) / LOG_DECADES + 1.0
    with written_together(exr, png) as (tmp_exr, tmp_png):
        write_exr(tmp_exr, {"Y": data.astype(np.float32)}, meta)
        write_png(tmp_png, shown, encoded=True)
