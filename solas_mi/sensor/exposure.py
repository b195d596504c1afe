"""From light on the image plane to photons per pixel (EMVA 1288 release 4.0, section 2.1, eq. 1).

A pixel of area A exposed for t to irradiance E (W/m²) of wavelength λ collects on average
    μ_p = A E t / (h c / λ) = A E t λ / (h c)
photons. The package's images (render or convolution) are scene-referred: a pixel holds the radiance
L of what it sees (relative illumination of the lens already applied by the engine). The camera
equation turns radiance into image irradiance for an f-number N and lens transmission T:
    E = π T L / (4 N²)
(object at infinity; the cos⁴ fall-off is the engine's, not repeated here).
"""

import numpy as np

from ..errors import SolasError

PLANCK = 6.62607015e-34  # J s (SI, exact)
LIGHT_SPEED = 299_792_458.0  # m/s (SI, exact)


# f/0.5 is the fastest a lens in air can be (N = 1 / (2 NA), NA <= 1); f/1000 is past any pinhole camera's
F_NUMBER_RANGE = (0.5, 1000.0)


def check_f_number(f_number, what: str = "f-number") -> float:
    """`f_number` as a float, or SolasError naming `what` unless it lies in F_NUMBER_RANGE."""
    low, high = F_NUMBER_RANGE
    if isinstance(f_number, bool) or not isinstance(f_number, (int, float)) or not low <= f_number <= high:
        raise SolasError(
            f"{what} {f_number!r} must be a number from {low:g} (a lens in air: N = 1 / (2 NA)) "
            f"to {high:g} (past any pinhole camera)"
        )
    return float(f_number)


def image_irradiance(radiance: np.ndarray, f_number: float, transmission: float = 1.0) -> np.ndarray:
    """Image-plane irradiance (W/m²) of scene radiance `radiance` (W/m²/sr) through a lens of f-number
    `f_number` and transmission `transmission`: E = π T L / (4 N²)."""
    check_f_number(f_number)
    if not 0 < transmission <= 1:
        raise SolasError(f"lens transmission {transmission!r} must be in (0, 1]")
    return np.pi * transmission * np.asarray(radiance, dtype=np.float64) / (4.0 * f_number**2)


ROUND_OFF = 1e-5  # negative values down to this fraction of the image's largest are round-off (read as 0)


def round_off_floor(image: np.ndarray) -> float:
    """The least value of `image` still read as round-off around zero: -ROUND_OFF of its largest magnitude."""
    return -ROUND_OFF * float(np.abs(image).max(initial=0.0))


def negatives_as_no_light(image: np.ndarray, what: str) -> tuple[np.ndarray, dict]:
    """The one rule of the camera commands (`solas-mi camera`, a batch's camera) for negative values of
    an input image: read as no light (0), their count and least value returned for the RAW's metadata.
    A spectral render's RGB is negative where a sample's colour lies outside the RGB gamut (few spp,
    saturated colours); an FFT convolution leaves round-off around zero. Values below the round-off
    (-ROUND_OFF of the image's largest) are also named in a one-line notice on stderr."""
    import sys

    floor = round_off_floor(image)
    beyond = int(np.count_nonzero(image < floor))
    if beyond:
        print(
            f"notice: {what}: {beyond} values below zero (least {image.min():.3g}, outside the RGB gamut or "
            "not light) read as no light; counted in the RAW's metadata",
            file=sys.stderr,
        )
    info = {
        "count": int(np.count_nonzero(image < 0.0)),
        "beyond_round_off": beyond,
        "least": float(min(image.min(initial=0.0), 0.0)),
        "round_off": ROUND_OFF,
    }
    return np.maximum(image, 0.0), info


def photons(
    irradiance: np.ndarray, exposure_s: float, pixel_pitch_um: float, wavelengths_nm: tuple[float, ...]
) -> np.ndarray:
    """Mean photons per pixel μ_p = A E t λ / (h c) of an irradiance image (H, W, C) in W/m², channel c
    at wavelength `wavelengths_nm[c]`, for a square pixel of pitch `pixel_pitch_um` and exposure
    `exposure_s` seconds."""
    image = np.asarray(irradiance, dtype=np.float64)
    if image.ndim != 3 or image.shape[2] != len(wavelengths_nm):
        raise SolasError(
            f"irradiance image of shape {image.shape} must be (height, width, "
            f"{len(wavelengths_nm)}): one channel per sensor wavelength"
        )
    if not np.all(np.isfinite(image)):
        raise SolasError(
            f"irradiance image holds {np.count_nonzero(~np.isfinite(image))} non-finite values; "
            "it must hold finite values >= 0"
        )
    # an FFT convolution leaves round-off around zero in dark regions: read as no light; more is an error
    floor = round_off_floor(image)
    if np.any(image < floor):
        raise SolasError(
            f"irradiance image holds {np.count_nonzero(image < floor)} values below zero (least "
            f"{image.min():.3g}); it must hold values >= 0 (down to -{ROUND_OFF:g} of its largest "
            "value are read as round-off and taken as 0)"
        )
    image = np.maximum(image, 0.0)
    if not exposure_s >= 0 or not np.isfinite(exposure_s):
        raise SolasError(f"exposure time {exposure_s!r} s must be a finite number >= 0")
    area = (pixel_pitch_um * 1e-6) ** 2
    energy = PLANCK * LIGHT_SPEED / (np.asarray(wavelengths_nm, dtype=np.float64) * 1e-9)  # J per photon
    with np.errstate(over="ignore", invalid="ignore"):
        out = image * (area * exposure_s / energy)
    if not np.all(np.isfinite(out)):
        raise SolasError(
            f"an exposure of {exposure_s:g} s at up to {image.max():.3g} W/m² gives more photons per pixel "
            "than a float64 holds (1.8e308); give a shorter exposure or a smaller scale"
        )
    return out
